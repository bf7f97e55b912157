"""Shared fixtures: the repository, its examples and the CLI binary the results are compared with."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"


def cli_binary() -> Path:
    """The `colloidsim` binary of this checkout: $COLLOIDSIM_BIN, else the newest of
    target/release and target/debug (cargo test builds the latter, optimised)."""
    env = os.environ.get("COLLOIDSIM_BIN")
    if env:
        return Path(env)
    found = [p for p in (REPO / "target/release/colloidsim", REPO / "target/debug/colloidsim") if p.exists()]
    if not found:
        pytest.fail(
            "no colloidsim binary: build it with `cargo build --release` (or set COLLOIDSIM_BIN)"
        )
    return max(found, key=lambda p: p.stat().st_mtime)


@pytest.fixture(scope="session")
def cli():
    """Run the CLI; returns the completed process (stdout and stderr as text)."""
    binary = cli_binary()

    def call(*args, env=None, check=True):
        e = dict(os.environ)
        e.update(env or {})
        p = subprocess.run(
            [str(binary), *map(str, args)], capture_output=True, text=True, env=e
        )
        if check and p.returncode != 0:
            raise AssertionError(f"colloidsim {' '.join(map(str, args))} failed:\n{p.stderr}")
        return p

    return call
