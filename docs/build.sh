#!/usr/bin/env bash
# Build the documentation site into docs/_build/html (open index.html). Every warning is an
# error: a broken link or anchor, a page in no table of contents, a tutorial cell that raises.
# Needs the Python package and the doc tools (docs/requirements.txt) in the Python on PATH (or
# $PYTHON), and the colloidsim program ($COLLOIDSIM_BIN, else target/release or target/debug).
# Extra arguments go to sphinx-build (e.g. `-j 2`).
set -euo pipefail
cd "$(dirname "$0")/.."
exec "${PYTHON:-python3}" -m sphinx -E -W --keep-going -b html "$@" docs docs/_build/html
