"""Sphinx configuration of colloidsim's documentation site (`docs/build.sh` builds it).

Sphinx with MyST, as HOOMD-blue, freud and gsd do: the Markdown pages of docs/ are read as
they are, the tutorials are MyST-NB text notebooks executed at every build, and the reference
is generated from the code (the CLI's parser, the Python docstrings and stubs, the keys'
declarations through `colloidsim keys`, whose pages a Rust test keeps equal to the code).
"""

import os
import shutil
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent

project = "colloidsim"
author = "the colloidsim authors"
copyright = "2026, the colloidsim authors"

extensions = [
    "myst_nb",  # MyST Markdown pages and MyST-NB text notebooks (includes myst_parser)
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]

# Pages and folders that are not part of the site: outputs, data tables, build folders.
exclude_patterns = [
    "_build",
    "data",
    "**/.ipynb_checkpoints",
    "**.ipynb",
    "README.md",
]

# Every warning is an error under `-W` (docs/build.sh): a broken internal link or anchor, a
# page in no toctree, a failed cell.
myst_heading_anchors = 4  # GitHub's anchors (`page.md#a-heading`), as the pages already use
myst_enable_extensions = ["dollarmath", "colon_fence"]
suppress_warnings = []

# Tutorials: executed at every build. A cell that raises is a warning that shows the cell and
# its traceback, and so an error under `-W` (docs/build.sh): the build goes on to report every
# fault, then fails. (`nb_execution_raise_on_error = True` would stop at the first, naming only
# the page.)
nb_execution_mode = "force"
nb_execution_raise_on_error = False
nb_execution_allow_errors = False
nb_execution_show_tb = True
nb_execution_timeout = 300
nb_merge_streams = True

# Python API from the installed package (its docstrings; the stubs give the extension's types).
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False}
napoleon_google_docstring = True
napoleon_numpy_docstring = True

html_theme = "furo"
html_title = "colloidsim"

# The generated reference (docs/generate.py; not in git): the CLI's pages from its parser, the
# output files from tiny runs. COLLOIDSIM_DOCS_SKIP_GENERATED=1 leaves them out, for the test
# that builds small sites with this configuration (python/tests/test_docs.py).
if not os.environ.get("COLLOIDSIM_DOCS_SKIP_GENERATED"):
    sys.path.insert(0, str(DOCS))
    import generate  # noqa: E402

    generate.cli_pages(DOCS / "reference" / "generated" / "cli")
    generate.output_page(DOCS / "reference" / "generated" / "outputs.md")
    _stale = generate.stale_keys_pages()


def _warn_stale_keys(app):
    """docs/keys pages that differ from the program's `colloidsim keys` fail the build (-W)."""
    from sphinx.util import logging

    for method in globals().get("_stale", []):
        logging.getLogger(__name__).warning(
            f"docs/keys/{method}.md differs from `colloidsim keys {method} --format markdown`: "
            "write it again (crates/cli/tests/keys_pages.rs says how)"
        )


# The tutorials' runs write into new temporary folders (`out=None`); the kernels inherit TMPDIR,
# so they land in one folder of this build, removed when the build ends.
_runs = tempfile.mkdtemp(prefix="colloidsim-docs-")
os.environ["TMPDIR"] = _runs


def setup(app):
    app.connect("builder-inited", _warn_stale_keys)
    app.connect("build-finished", lambda app, exc: shutil.rmtree(_runs, ignore_errors=True))
