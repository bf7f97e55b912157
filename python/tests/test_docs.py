"""The documentation site's build (`docs/build.sh` with docs/conf.py) fails on what would let the docs
rot: a broken internal link or anchor, a page in no table of contents, a tutorial cell that
raises. Each case builds a tiny site with the real configuration, once as it should be (it must
build) and once broken (it must fail, naming the fault); the real site then builds with its
tutorials left unexecuted (CI builds it with them: .ci/run)."""

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO, cli_binary

DOCS = REPO / "docs"


def _tools():
    for name in ["sphinx", "myst_nb", "furo"]:
        if os.environ.get("COLLOIDSIM_REQUIRE_TOOLS"):
            importlib.import_module(name)  # CI: a missing tool fails, never skips
        else:
            pytest.importorskip(name)


def _build(src: Path, out: Path, *extra: str, env=None):
    """`docs/build.sh` (the one command that builds the site) on another source folder."""
    e = dict(os.environ, PYTHON=sys.executable, DOCS_SRC=str(src), DOCS_OUT=str(out), **(env or {}))
    return subprocess.run(
        ["bash", str(DOCS / "build.sh"), "-q", *extra], capture_output=True, text=True, env=e,
        timeout=600,
    )


PAGE = "# A page\n\nSee [the other page](other.md#a-section).\n"
OTHER = "# Other\n\n## A section\n\nText.\n"
INDEX = "# Site\n\n```{toctree}\npage\nother\n```\n"
NOTEBOOK = """---
file_format: mystnb
kernelspec:
  name: python3
  display_name: Python 3
  language: python
---

# A tutorial

```{code-cell} ipython3
x = 1 + 1
print(x)
```
"""


def _site(root: Path, pages) -> Path:
    root.mkdir()
    for name, text in pages.items():
        (root / name).write_text(text)
    return root


SMALL = {"COLLOIDSIM_DOCS_SKIP_GENERATED": "1"}


@pytest.fixture(scope="module")
def good_site(tmp_path_factory):
    """The small site unbroken builds: the failures below are the faults'."""
    _tools()
    root = tmp_path_factory.mktemp("site")
    pages = {"index.md": INDEX, "page.md": PAGE, "other.md": OTHER}
    good = _build(_site(root / "good", pages), root / "good-html", env=SMALL)
    assert good.returncode == 0, good.stderr


@pytest.mark.parametrize(
    "broken, expect",
    [
        ({"page.md": PAGE.replace("other.md#", "missing.md#")}, "missing.md"),
        ({"page.md": PAGE.replace("#a-section", "#no-such-section")}, "no-such-section"),
        ({"index.md": INDEX.replace("other\n", "")}, "toctree"),
    ],
    ids=["link", "anchor", "page-in-no-toctree"],
)
def test_a_broken_link_or_a_page_in_no_toctree_fails_the_build(tmp_path, good_site, broken, expect):
    pages = {"index.md": INDEX, "page.md": PAGE, "other.md": OTHER}
    bad = _build(_site(tmp_path / "bad", {**pages, **broken}), tmp_path / "bad-html", env=SMALL)
    assert bad.returncode != 0, f"the build passed with a broken site:\n{bad.stderr}"
    assert expect in bad.stderr, bad.stderr


def test_a_tutorial_that_raises_fails_the_build(tmp_path):
    _tools()
    pages = {"index.md": INDEX.replace("other\n", "tutorial\n"), "page.md": "# A page\n",
             "tutorial.md": NOTEBOOK}
    good = _build(_site(tmp_path / "good", pages), tmp_path / "good-html", env=SMALL)
    assert good.returncode == 0, good.stderr
    assert "2" in (tmp_path / "good-html" / "tutorial.html").read_text()  # it was executed
    broken = NOTEBOOK.replace("print(x)", "raise ValueError('a tutorial that rotted')")
    bad = _build(_site(tmp_path / "bad", {**pages, "tutorial.md": broken}), tmp_path / "bad-html",
                 env=SMALL)
    assert bad.returncode != 0, f"the build passed with a failing tutorial:\n{bad.stderr}"
    assert "a tutorial that rotted" in bad.stderr + bad.stdout


def test_the_site_builds_with_its_generated_reference(tmp_path):
    """The real site, its tutorials not executed (CI executes them): every link, anchor and page
    in place, the CLI pages generated from the binary's parser and the output files from tiny
    runs of the examples."""
    _tools()
    env = {"COLLOIDSIM_BIN": str(cli_binary())}
    r = _build(DOCS, tmp_path / "html", "-D", "nb_execution_mode=off", env=env)
    assert r.returncode == 0, r.stderr
    for page in ["index", "reference/generated/cli/run", "reference/generated/outputs",
                 "reference/python-api", "keys/bcd", "tutorials/bcd-first-run"]:
        assert (tmp_path / "html" / f"{page}.html").is_file(), page
    cli = (tmp_path / "html" / "reference/generated/cli/run.html").read_text()
    assert "--restart" in cli
