"""`colloidsim.run/theory/check` give what the CLI gives, byte for byte, and fail as it fails."""

import json
import os
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import colloidsim
from conftest import EXAMPLES

# Fields of summary.json that depend on the machine, not on the run.
VOLATILE = {"wall_seconds", "particle_steps_per_second", "threads"}


def assert_same_outputs(a: Path, b: Path):
    fa = sorted(os.listdir(a))
    fb = sorted(os.listdir(b))
    assert fa == fb, f"different files: {fa} vs {fb}"
    for name in fa:
        x = (a / name).read_bytes()
        y = (b / name).read_bytes()
        if name == "summary.json":
            sx, sy = json.loads(x), json.loads(y)
            for k in VOLATILE:
                sx.pop(k, None)
                sy.pop(k, None)
            assert sx == sy, f"summary.json differs: {set(k for k in sx if sx[k] != sy.get(k))}"
        else:
            assert x == y, f"{name} differs between the CLI and Python"


# Every example that finishes in a few seconds (the others differ only in their sizes).
EXAMPLE_RUNS = [
    "bcd/hard-rods-cosine.toml",
    "bcd/tilted-washboard.toml",
    "bcd/channel-trap.toml",
    "bcd/single-file.toml",
    "dpd/colloids-equilibrium.toml",
    "droplet/drying-bd.toml",
]


@pytest.mark.parametrize("example", EXAMPLE_RUNS)
def test_run_equals_the_cli_byte_for_byte(example, tmp_path, cli):
    path = EXAMPLES / example
    cli("run", path, "--out", tmp_path / "cli", "--quiet")
    r = colloidsim.run(path, out=tmp_path / "py")
    assert_same_outputs(tmp_path / "cli", tmp_path / "py")
    assert r.out == tmp_path / "py"
    assert r.summary["completed"] is True
    # Every CSV is there as numpy columns named by its header.
    for name in r.files:
        if name.endswith(".csv"):
            header = (r.out / name).read_text().splitlines()[0].split(",")
            table = r[name[:-4]]
            assert list(table) == header
            assert all(isinstance(table[c], np.ndarray) for c in header)


@pytest.mark.parametrize("example", ["bcd/hard-rods-cosine.toml", "bcd/channel-trap.toml"])
def test_theory_equals_the_cli(example, tmp_path, cli):
    path = EXAMPLES / example
    cli("theory", path, "--out", tmp_path / "cli")
    r = colloidsim.theory(path, out=tmp_path / "py")
    assert_same_outputs(tmp_path / "cli", tmp_path / "py")
    assert r.summary["converged"] is True
    assert r.density.rho.shape == r.density.x.shape


def test_theory_with_the_trokhymchuk_pair_correlation_equals_the_cli(tmp_path, cli):
    scenario = {
        "method": "droplet-bd",
        "seed": 1,
        "system": {"particles": 200, "phi0": 0.05},
        "drying": {"peclet": 10, "final_volume_fraction": 0.3},
        "run": {"dt": 0.004},
        "observe": {"profile": {"bins": 10, "fractions": [0, 1.0]}},
    }
    path = tmp_path / "small.toml"
    path.write_text(
        'method = "droplet-bd"\nseed = 1\n[system]\nparticles = 200\nphi0 = 0.05\n'
        "[drying]\npeclet = 10\nfinal_volume_fraction = 0.3\n[run]\ndt = 0.004\n"
        "[observe]\nprofile = { bins = 10, fractions = [0, 1.0] }\n"
    )
    args = ("--hydrodynamics", "rpy", "--pair", "trokhymchuk", "--dx", "0.05")
    cli("theory", path, "--out", tmp_path / "cli", *args)
    r = colloidsim.theory(
        path, out=tmp_path / "py", hydrodynamics="rpy", pair="trokhymchuk", dx=0.05
    )
    assert_same_outputs(tmp_path / "cli", tmp_path / "py")
    assert r.summary["pair_correlation"] == "trokhymchuk"
    assert r.summary["status"] == "ok"
    d = colloidsim.theory(
        scenario, out=tmp_path / "dict", hydrodynamics="rpy", pair="trokhymchuk", dx=0.05
    )
    assert (d.out / "profile_1.00.csv").read_bytes() == (r.out / "profile_1.00.csv").read_bytes()
    with pytest.raises(colloidsim.ColloidsimError, match="--pair must be"):
        colloidsim.theory(scenario, out=tmp_path / "bad", hydrodynamics="rpy", pair="py")


def test_a_bulk_bd_run_equals_the_cli_byte_for_byte(tmp_path, cli):
    # method = "bd": RPY (PSE) under a body force, MSD, trajectory, two replicas.
    path = tmp_path / "bulk.toml"
    path.write_text(
        'method = "bd"\nseed = 2\nreplicas = 2\n[system]\nparticles = 20\nbox_length = 8.0\n'
        "body_force = [0.0, 0.0, -1.0]\n[run]\ndt = 0.01\ntime = 1.0\n"
        "[observe.trajectory]\nevery = 20\n[hydrodynamics]\nmodel = \"rpy\"\n"
    )
    cli("run", path, "--out", tmp_path / "cli", "--quiet")
    r = colloidsim.run(path, out=tmp_path / "py")
    assert_same_outputs(tmp_path / "cli", tmp_path / "py")
    assert list(r.msd) == ["t", "msd", "err"]
    assert r.summary["blocks"] == 16
    assert r.summary["sedimentation_coefficient"]["dilute_reference"] > 0


def test_check_equals_the_cli(cli):
    path = EXAMPLES / "bcd/hard-rods-cosine.toml"
    out = cli("check", path, "--json", "--set", "run.dt=2e-4").stdout
    printed = json.loads(out[: out.rindex("}") + 1])
    assert colloidsim.check(path, overrides={"run.dt": 2e-4}) == printed
    assert printed["run"]["dt"] == 2e-4


def test_a_dict_a_toml_string_and_a_file_run_alike(tmp_path):
    path = EXAMPLES / "bcd/tilted-washboard.toml"
    text = path.read_text()
    import tomllib

    as_dict = tomllib.loads(text)
    a = colloidsim.run(path, out=tmp_path / "file")
    b = colloidsim.run(text, out=tmp_path / "text")
    c = colloidsim.run(as_dict, out=tmp_path / "dict")
    for other in (b, c):
        for name in a.files:
            if name.endswith(".csv"):
                assert (a.out / name).read_bytes() == (other.out / name).read_bytes(), name


def test_overrides_meet_the_same_validation_as_the_cli(tmp_path, cli):
    path = EXAMPLES / "bcd/hard-rods-cosine.toml"
    p = cli("run", path, "--set", "run.dt=-1", "--out", tmp_path / "cli", check=False)
    assert p.returncode != 0
    with pytest.raises(colloidsim.ColloidsimError) as e:
        colloidsim.run(path, out=tmp_path / "py", overrides=["run.dt=-1"])
    # The same message as the CLI's (after its "error: " prefix).
    assert str(e.value) == p.stderr.strip().removeprefix("error: ")
    assert "run.dt" in str(e.value)
    with pytest.raises(colloidsim.ColloidsimError, match=r"run.dt: must be a finite number > 0, got -1.0"):
        colloidsim.run(path, out=tmp_path / "py", overrides={"run.dt": -1.0})
    # Nothing was written for bad input.
    assert not (tmp_path / "py").exists()
    with pytest.raises(colloidsim.ColloidsimError, match="observe.nonsense|unknown field"):
        colloidsim.check(path, overrides=["observe.nonsense=3"])


def test_error_paths_raise_with_the_cli_message(tmp_path):
    with pytest.raises(colloidsim.ColloidsimError, match="no such file"):
        colloidsim.run(tmp_path / "missing.toml")
    with pytest.raises(colloidsim.ColloidsimError, match="unknown method 'nope'"):
        colloidsim.check({"method": "nope"})
    with pytest.raises(colloidsim.ColloidsimError, match="missing key 'method'"):
        colloidsim.check("seed = 3\n")
    with pytest.raises(ValueError, match="threads"):
        colloidsim.run(EXAMPLES / "bcd/tilted-washboard.toml", out=tmp_path / "t", threads=0)
    out = tmp_path / "full"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    with pytest.raises(colloidsim.ColloidsimError, match="not empty"):
        colloidsim.run(EXAMPLES / "bcd/tilted-washboard.toml", out=out)
    assert (out / "keep.txt").read_text() == "mine"
    with pytest.raises(colloidsim.ColloidsimError, match="no theory counterpart"):
        colloidsim.theory(EXAMPLES / "dpd/colloids-equilibrium.toml", out=tmp_path / "th")
    with pytest.raises(colloidsim.ColloidsimError, match="is complete"):
        r = colloidsim.run(EXAMPLES / "bcd/tilted-washboard.toml", out=tmp_path / "done")
        colloidsim.resume(r.out)


def test_an_interrupted_run_raises_keyboardinterrupt_and_resumes_bitwise(tmp_path, monkeypatch):
    path = EXAMPLES / "bcd/hard-rods-cosine.toml"
    whole = colloidsim.run(path, out=tmp_path / "whole", overrides={"run.time": 20.0})
    monkeypatch.setenv("COLLOIDSIM_INTERRUPT_AT_STEP", "12345")
    with pytest.raises(KeyboardInterrupt, match="colloidsim.resume"):
        colloidsim.run(path, out=tmp_path / "cut", overrides={"run.time": 20.0})
    assert (tmp_path / "cut" / "checkpoint.bin").exists()
    assert not (tmp_path / "cut" / "summary.json").exists()
    monkeypatch.delenv("COLLOIDSIM_INTERRUPT_AT_STEP")
    resumed = colloidsim.resume(tmp_path / "cut")
    assert_same_outputs(whole.out, resumed.out)


def test_warnings_become_python_warnings(tmp_path):
    # A contact window that the time step biases (the run warns, as the CLI does).
    sc = {
        "method": "bcd",
        "system": {"length": 10.0, "particles": 5, "diameter": 0.5},
        "run": {"dt": 1e-2, "time": 0.1},
        "observe": {"contact_density": {"bins": 10, "window": 0.01}},
    }
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        r = colloidsim.run(sc, out=tmp_path / "w")
    assert any("contact_density" in str(x.message) for x in w)
    assert any("contact_density" in x for x in r.warnings)


def test_keys_and_methods_are_listed():
    names = [n for m in colloidsim.methods() for n in m["names"]]
    assert {"bcd", "droplet-bd", "dpd"} <= set(names)
    keys = {k["path"]: k for k in colloidsim.keys("bcd")}
    assert keys["run.dt"]["unit"] and keys["run.dt"]["range"]
    with pytest.raises(colloidsim.ColloidsimError, match="unknown method"):
        colloidsim.keys("nope")


def test_ensemble_equals_the_cli_and_averages_the_replicas(tmp_path, cli):
    scenario = {
        "method": "bcd",
        "seed": 11,
        "system": {"length": 10.0, "particles": 5, "diameter": 0.5},
        "potential": {"cosine": {"amplitude": 2.0, "wavelength": 1.0}},
        "run": {"dt": 1e-3, "equilibrate": 0.2, "time": 2.0},
        "observe": {"density": {"bins": 20}},
    }
    path = tmp_path / "tiny.toml"
    path.write_text(colloidsim._colloidsim.toml_from_json(json.dumps(scenario)))
    cli("ensemble", path, "--out", tmp_path / "cli", "--replicas", "3", "--quiet")
    r = colloidsim.ensemble(path, replicas=3, out=tmp_path / "py")
    for sub in ["replica-0", "replica-1", "replica-2"]:
        assert_same_outputs(tmp_path / "cli" / sub, tmp_path / "py" / sub)
    assert (tmp_path / "cli" / "density.csv").read_bytes() == (r.out / "density.csv").read_bytes()
    members = np.array([colloidsim.Table(r.out / f"replica-{k}/density.csv")["rho"] for k in range(3)])
    np.testing.assert_allclose(r.density["rho"], members.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(
        r.density["rho_err"], members.std(axis=0, ddof=1) / np.sqrt(3), rtol=1e-9, atol=1e-15
    )
    obs = r.observables
    assert set(obs["observable"]) >= {"steps"} and np.all(obs["n"] == 3)
    with pytest.raises(colloidsim.ColloidsimError, match="vary seed"):
        colloidsim.ensemble(path, vary={"seed": [1, 2]}, out=tmp_path / "bad")
    assert not (tmp_path / "bad").exists()


def test_ensemble_returns_the_headline_observables_per_sweep_point(tmp_path, cli):
    scenario = {
        "method": "bcd",
        "seed": 11,
        "system": {"length": 10.0, "particles": 5, "diameter": 0.5},
        "potential": {"cosine": {"amplitude": 2.0, "wavelength": 1.0}},
        "run": {"dt": 1e-3, "equilibrate": 0.2, "time": 2.0},
        "observe": {"density": {"bins": 20}, "current": True},
    }
    path = tmp_path / "tiny.toml"
    path.write_text(colloidsim._colloidsim.toml_from_json(json.dumps(scenario)))
    vary = ["--vary", "potential.cosine.amplitude=[1.0, 3.0]"]
    cli("ensemble", path, "--out", tmp_path / "cli", "--replicas", "2", *vary, "--quiet")
    r = colloidsim.ensemble(
        path, replicas=2, vary={"potential.cosine.amplitude": [1.0, 3.0]}, out=tmp_path / "py"
    )
    assert (tmp_path / "cli" / "headline.csv").read_bytes() == (r.out / "headline.csv").read_bytes()
    h = r.headline
    np.testing.assert_array_equal(h["potential.cosine.amplitude"], [1.0, 3.0])
    np.testing.assert_array_equal(h["replicas"], [2, 2])
    assert [d["name"] for d in r.summary["headline"]] == [
        "peak_density", "theory_l1", "particle_current", "mean_contact_density"
    ]
    for name in ["peak_density", "theory_l1", "particle_current"]:
        members = np.array(
            [
                [json.loads((r.out / f"point-{p}/replica-{k}/summary.json").read_text())[name]
                 for k in range(2)]
                for p in range(2)
            ]
        )
        np.testing.assert_allclose(h[name], members.mean(axis=1), rtol=1e-12)
        np.testing.assert_allclose(
            h[name + "_err"], members.std(axis=1, ddof=1) / np.sqrt(2), rtol=1e-9
        )
    # Not observed: empty fields (NaN), with the reason in the summary.
    assert np.all(np.isnan(h["mean_contact_density"]))
    assert "observe.contact_density" in r.summary["nulls"]["points[0].headline.mean_contact_density.mean"]


def test_an_interrupted_ensemble_resumes_to_the_cli_folder(tmp_path, cli):
    path = tmp_path / "tiny.toml"
    path.write_text(
        colloidsim._colloidsim.toml_from_json(
            json.dumps(
                {
                    "method": "bcd",
                    "seed": 11,
                    "system": {"length": 10.0, "particles": 5, "diameter": 0.5},
                    "run": {"dt": 1e-3, "equilibrate": 0.2, "time": 2.0},
                    "observe": {"density": {"bins": 20}},
                }
            )
        )
    )
    cli("ensemble", path, "--out", tmp_path / "cli", "--replicas", "2", "--quiet")
    stopped = cli(
        "ensemble", path, "--out", tmp_path / "py", "--replicas", "2",
        env={"COLLOIDSIM_INTERRUPT_AT_STEP": "1000"}, check=False,
    )
    assert stopped.returncode != 0 and "--restart" in stopped.stderr
    r = colloidsim.resume(tmp_path / "py")
    assert r.summary["completed"] is True
    assert (tmp_path / "cli" / "density.csv").read_bytes() == (r.out / "density.csv").read_bytes()
    for sub in ["replica-0", "replica-1"]:
        assert_same_outputs(tmp_path / "cli" / sub, tmp_path / "py" / sub)
