"""Pages of the site generated at build time (conf.py calls them; their folders are not in git).

`cli_pages(folder)`: one page per command of the `colloidsim` program, from its own parser
(`colloidsim CMD --help`), so that the reference cannot drift from the code.
"""

import os
import re
import shutil
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def cli_binary() -> Path:
    """The `colloidsim` binary: $COLLOIDSIM_BIN, else the newest of this checkout's
    target/release and target/debug (as python/tests/conftest.py), else the one on PATH."""
    env = os.environ.get("COLLOIDSIM_BIN")
    if env:
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    found = [p for p in (target / "release/colloidsim", target / "debug/colloidsim") if p.exists()]
    if found:
        return max(found, key=lambda p: p.stat().st_mtime)
    on_path = shutil.which("colloidsim")
    if on_path:
        return Path(on_path)
    raise RuntimeError(
        "docs: no colloidsim binary for the CLI reference: build it (`cargo build --release`) "
        "or set COLLOIDSIM_BIN"
    )


def _help(binary: Path, words):
    p = subprocess.run([str(binary), *words, "--help"], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"colloidsim {' '.join(words)} --help failed:\n{p.stderr}")
    return p.stdout


def _subcommands(text: str):
    """The names listed under `Commands:` in clap's help, without `help`."""
    names, inside = [], False
    for line in text.splitlines():
        if line.strip() == "Commands:":
            inside = True
            continue
        if inside:
            m = re.match(r"^  (\S+)\s", line + " ")
            if not m:
                break
            if m.group(1) != "help":
                names.append(m.group(1))
    return names


def _first_line(text: str) -> str:
    return text.strip().splitlines()[0] if text.strip() else ""


def _write(path: Path, text: str) -> None:
    """Write only when changed, so that Sphinx rereads only what changed."""
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def cli_pages(folder: Path) -> None:
    binary = cli_binary()
    folder.mkdir(parents=True, exist_ok=True)
    top = _help(binary, [])
    commands = _subcommands(top)
    pages = []
    for cmd in commands:
        text = _help(binary, [cmd])
        body = [f"# `colloidsim {cmd}`", "", _first_line(text), "", "```text", text.rstrip(), "```", ""]
        for sub in _subcommands(text):
            sub_text = _help(binary, [cmd, sub])
            body += [f"## `colloidsim {cmd} {sub}`", "", "```text", sub_text.rstrip(), "```", ""]
        _write(folder / f"{cmd}.md", "\n".join(body))
        pages.append(cmd)
    for old in folder.glob("*.md"):
        if old.stem not in pages and old.name != "index.md":
            old.unlink()
    index = [
        "# Command line (`colloidsim`)",
        "",
        "Generated at build time from the program's own parser (`colloidsim --help` and each "
        "command's `--help`), so it is the program's text word for word.",
        "",
        "```text",
        top.rstrip(),
        "```",
        "",
        "```{toctree}",
        ":maxdepth: 1",
        "",
        *pages,
        "```",
        "",
    ]
    _write(folder / "index.md", "\n".join(index))
