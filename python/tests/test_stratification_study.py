"""scripts/stratification_study.py (docs/stratification.md): its scenarios are valid for the CLI,
its reference (the uniform mixture) and threshold are right, and an MPCD point's seeds are
averaged as the study's droplets."""

import csv
import importlib.util
import json
import math
import os

import pytest

from conftest import REPO

spec = importlib.util.spec_from_file_location(
    "stratification_study", REPO / "scripts" / "stratification_study.py"
)
study = importlib.util.module_from_spec(spec)
spec.loader.exec_module(study)


@pytest.fixture
def at_repo(monkeypatch):
    """The script reads the examples relative to the repository root, as it is run."""
    monkeypatch.chdir(REPO)


@pytest.mark.parametrize("alpha", [2.0, 4.0])
@pytest.mark.parametrize("method", ["bd-fd", "bd-rpy-k500", "bd-fd-k2000", "bd-rpy-hard", "mpcd-slip",
                                    "mpcd-noslip-k800", "mpcd-noslip-hard"])
def test_scenarios_are_valid(cli, tmp_path, at_repo, monkeypatch, method, alpha):
    monkeypatch.setattr(study, "ALPHA", alpha)
    if study.is_mpcd(method):
        text = study.mpcd_scenario(10, 0.1, method, 108, 3)
        boundary = "slip" if method == "mpcd-slip" else "no-slip"
        assert f'boundary = "{boundary}"' in text and "seed = 3" in text
        assert f"diameters = [2.0, {2.0 * alpha}]" in text
        assert "final_volume_fraction = 0.5" in text
        # 800 kT/d^2 with d = 2 cells is 200 kT/cell^2 (the example's 100 kT/cell^2 else).
        assert ("stiffness = 200.0" in text) == method.endswith("-k800")
        assert ("stiffness = 100.0" in text) == (method == "mpcd-slip")
        # A hard wall: neither stiffness nor range (the CLI refuses them beside it).
        assert ("hard = true" in text) == method.endswith("-hard")
        assert ("range" not in text) == method.endswith("-hard")
    else:
        text = study.scenario(10, 0.1, 4, method, 650)
        assert f"diameters = [1.0, {alpha}]" in text
        assert ("[hydrodynamics]" in text) == ("rpy" in method)
        assert ("stiffness = 500.0" in text) == method.endswith("-k500")
        # Beyond 500 kT/d^2 the step shrinks to keep k D0 dt / kT = 0.1.
        assert ("dt = 0.000471239" in text) == method.endswith("-k2000")
        # A hard wall in place of the spring, at the default step.
        assert ("hard = true" in text) == method.endswith("-hard")
        assert ("stiffness" not in text) == method.endswith("-hard")
    large = int(650 // (1 + alpha**3)) if not study.is_mpcd(method) else int(108 // (1 + alpha**3))
    total = 108 if study.is_mpcd(method) else 650
    assert f"counts = [{total - large}, {large}]" in text
    path = tmp_path / "point.toml"
    path.write_text(text)
    out = cli("check", path)
    assert "is valid" in out.stdout


def test_ideal_delta_of_a_hard_walled_uniform_mixture():
    # In a very stiff interface each species fills a ball of radius w_k = R + offset -
    # (d_k - d) / 2 uniformly, with <r> = 3 w_k / 4.
    radius, offset = 10.0, -0.5
    p = {"stiffness": 1e6, "range": 0.5, "offset": offset, "diameter": 1.0,
         "species": {"diameters": [1.0, 2.0]}}
    walls = [radius + offset - 0.5 * (d - 1.0) for d in (1.0, 2.0)]
    exact = 0.75 * (walls[0] - walls[1]) / radius
    assert study.ideal_delta(p, radius) == pytest.approx(exact, rel=2e-3)
    # One size: no difference; a softer interface lets both out alike.
    p1 = dict(p, species={"diameters": [1.0, 1.0]}, stiffness=10.0)
    assert abs(study.ideal_delta(p1, radius)) < 1e-12
    # The hard wall (`interface.hard`: stiffness and range 0) is the same limit.
    hard = dict(p, stiffness=0.0, range=0.0, hard_interface=True)
    assert study.ideal_delta(hard, radius) == pytest.approx(exact, rel=2e-3)


def test_threshold_is_where_s_stays_positive():
    # S crosses zero half way (in log Pe_s) between 1 and 10: Pe_s = sqrt(10).
    got, note = study.crossing([(1.0, -0.1), (10.0, 0.1), (100.0, 0.2)], 0.1)
    assert got == pytest.approx(math.sqrt(10.0) * 0.05) and note == ""
    # Positive again after a dip: the last crossing counts.
    got, _ = study.crossing([(1.0, 0.1), (3.0, -0.1), (9.0, 0.1)], 0.2)
    assert got == pytest.approx(math.sqrt(27.0) * 0.1)
    assert study.crossing([(1.0, 0.1), (3.0, 0.2)], 0.1)[0] is None
    assert "above" in study.crossing([(1.0, 0.1), (3.0, -0.2)], 0.1)[1]


def fake_mpcd_seed(folder, deltas, beyond):
    os.makedirs(folder)
    params = {"interface": [100.0, 1.0, -1.0], "solvent": {"srd": {"kt": 1.0}}, "diameter": 2.0,
              "species": {"diameters": [2.0, 4.0]}, "particles": 108}
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump({"method": "droplet-mpcd", "completed": True, "parameters": params,
                   "colloids": {"centres_beyond_R_at_end": beyond}}, f)
    with open(os.path.join(folder, "stratification.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["fraction", "t", "R", "radius_difference", "radius_difference_err"])
        for frac, d in zip((0.5, 1.0), deltas):
            w.writerow([frac, 10 * frac, 8.0 - frac, d, ""])
    with open(folder + ".wall", "w") as f:
        f.write("12.5\n")


def test_an_mpcd_point_averages_its_seeds(tmp_path):
    point = tmp_path / "mpcd-slip" / "phi0.1-pe10"
    fake_mpcd_seed(str(point / "seed1"), (0.10, 0.20), 1)
    fake_mpcd_seed(str(point / "seed2"), (0.14, 0.10), 0)
    assert study.state(str(point)) == "done"
    assert study.state(str(point), replicas=2) == "done"
    assert study.state(str(point), replicas=3) is None
    got, params = study.measures(str(point))
    mean, err, radius = got[1.0]
    assert mean == pytest.approx(0.15) and err == pytest.approx(0.05) and radius == 7.0
    assert got[0.5][:2] == pytest.approx((0.12, 0.02))
    assert params["replicas"] == 2 and params["stiffness"] == 100.0 and params["kt"] == 1.0
    assert study.run_costs(str(point)) == (25.0, 1)


def test_from_csv_draws_only_the_fractions_asked(tmp_path):
    """`--from-csv` with `--drawn 0.5` redraws the data file, its thresholds and the diagram half
    way through drying from a committed data file, and no other diagram."""
    import subprocess
    import sys

    data = REPO / "docs" / "data" / "stratification_study-n108-hard.csv"
    subprocess.run(
        [sys.executable, str(REPO / "scripts" / "stratification_study.py"), "--runs", str(tmp_path),
         "--from-csv", str(data), "--methods", "bd-fd-hard,bd-rpy-hard", "--peclet", "3,10,30,100",
         "--drawn", "0.5", "--tag=-t", "--data", str(tmp_path), "--img", str(tmp_path)],
        check=True, capture_output=True)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert "stratification-diagram-t050-t.png" in names, names
    assert not any(n.startswith("stratification-diagram-t100") for n in names), names
    with open(tmp_path / "stratification_study-t.csv") as f:
        rows = list(csv.DictReader(f))
    assert {r["method"] for r in rows} == {"bd-fd-hard", "bd-rpy-hard"}
    assert {float(r["fraction"]) for r in rows} == {0.5, 0.75, 1.0}
