#!/usr/bin/env bash
# Build the documentation site into docs/_build/html (open index.html). Every warning is an
# error: a broken link or anchor, a page in no table of contents, a tutorial cell that raises.
# Needs the Python package and the doc tools (docs/requirements.txt) in the Python on PATH (or
# $PYTHON), and the colloidsim program ($COLLOIDSIM_BIN, else target/release or target/debug).
# Extra arguments go to sphinx-build (e.g. `-j 2`). DOCS_SRC and DOCS_OUT build another source
# folder with this configuration (the tests of python/tests/test_docs.py do).
set -euo pipefail
cd "$(dirname "$0")/.."
exec "${PYTHON:-python3}" -m sphinx -E -W --keep-going -b html -c docs "$@" \
  "${DOCS_SRC:-docs}" "${DOCS_OUT:-docs/_build/html}"
