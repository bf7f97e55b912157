"""The Python example runs and its BCD curve lies on the exact theory."""

import importlib.util
import os

import pytest

from conftest import REPO


def test_the_bcd_example_script_draws_bcd_on_the_exact_theory(tmp_path):
    if os.environ.get("COLLOIDSIM_REQUIRE_TOOLS"):
        import matplotlib  # noqa: F401  (CI: a missing matplotlib fails, never skips)
    else:
        pytest.importorskip("matplotlib")
    spec = importlib.util.spec_from_file_location(
        "bcd_beside_theory", REPO / "examples/python/bcd_beside_theory.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    rel = mod.main(tmp_path)
    assert (tmp_path / "density.png").stat().st_size > 10_000
    # 40 time units at dt = 1e-4: seeds 1, 2, 3 give a largest bin deviation of 0.7, 1.2 and
    # 0.3 % of the peak; a cosine amplitude 10 % too low gives 6.5 %.
    assert rel < 0.03
