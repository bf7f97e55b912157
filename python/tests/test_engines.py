"""Engines stepped by hand: deterministic, consistent with `run`, arrays read-only."""

import numpy as np
import pytest

import colloidsim
from conftest import EXAMPLES

BCD_SCENARIO = {
    "method": "bcd",
    "seed": 7,
    "system": {"length": 20.0, "particles": 10, "diameter": 0.5},
    "potential": {"cosine": {"amplitude": 6.0, "wavelength": 1.0}},
    "run": {"dt": 1e-3, "time": 1.0},
}


def test_bcd_steps_are_deterministic_and_split_freely():
    a = colloidsim.BCD(BCD_SCENARIO)
    b = colloidsim.BCD(BCD_SCENARIO)
    a.step(200)
    b.step(50)
    b.step(150)
    assert a.steps == b.steps == 200
    assert np.array_equal(a.positions, b.positions)
    assert a.time == pytest.approx(0.2)
    c = colloidsim.BCD(BCD_SCENARIO, seed=8)
    c.step(200)
    assert not np.array_equal(a.positions, c.positions)


def test_bcd_engine_ends_where_the_run_ends(tmp_path):
    # A run of the same scenario writes its last positions to final_configuration.csv.
    sc = dict(BCD_SCENARIO, run={"dt": 1e-3, "time": 0.5})
    r = colloidsim.run(sc, out=tmp_path / "r")
    e = colloidsim.BCD(sc)
    e.step(r.summary["steps"])
    assert np.array_equal(e.positions, r.final_configuration.x)


def test_bcd_positions_keep_order_and_hard_core_and_forces_are_the_field():
    e = colloidsim.BCD(BCD_SCENARIO)
    e.step(500)
    x = e.positions
    assert x.shape == (10,)
    assert np.all(np.diff(x) >= 0.5 - 1e-12)
    # f = -dU/dx for U = (U0/2) cos(2 pi x): f = pi U0 sin(2 pi x).
    assert np.allclose(e.forces, np.pi * 6.0 * np.sin(2 * np.pi * x), rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError):
        x[0] = 1.0  # read-only
    assert e.velocities is None


def test_brownian_dynamics_and_dpd_engines():
    bd = colloidsim.BrownianDynamics(EXAMPLES / "droplet/drying-bd.toml")
    p0 = bd.positions.copy()
    bd.step(10)
    assert bd.positions.shape == (bd.particles, 3)
    assert not np.array_equal(p0, bd.positions)
    assert bd.forces.shape == (bd.particles, 3)
    dpd = colloidsim.DPD(EXAMPLES / "dpd/colloids-equilibrium.toml", overrides={"system.box_length": 8.0})
    dpd.step(5)
    v = dpd.velocities
    assert v.shape == (dpd.particles, 3) and np.all(np.isfinite(v))
    assert dpd.steps == 5


BULK_SCENARIO = {
    "method": "bd",
    "seed": 3,
    "system": {"particles": 1, "box_length": 7.0, "body_force": [0.0, 0.0, -2.0]},
    "run": {"dt": 0.01, "time": 1.0},
    "hydrodynamics": {"model": "rpy"},
}


def test_brownian_dynamics_engine_of_a_periodic_bulk():
    # One sphere with RPY (PSE) under a body force: no pair force, so the systematic force is
    # the body force; the sphere stays in the periodic box and drifts along -z.
    bd = colloidsim.BrownianDynamics(BULK_SCENARIO)
    assert bd.method == "bd" and bd.particles == 1
    assert np.array_equal(bd.box, [7.0, 7.0, 7.0])
    assert np.array_equal(bd.forces, [[0.0, 0.0, -2.0]])
    again = colloidsim.BrownianDynamics(BULK_SCENARIO)
    bd.step(40)
    again.step(15)
    again.step(25)
    assert np.array_equal(bd.positions, again.positions)
    assert np.all(np.abs(bd.positions) <= 3.5)
    assert bd.steps == 40 and bd.time == pytest.approx(0.4)
    # The free-draining twin, with Leimkuhler-Matthews.
    free = dict(BULK_SCENARIO, hydrodynamics={"model": "free-draining"})
    free["run"] = {"dt": 0.01, "time": 1.0, "integrator": "lm"}
    fd = colloidsim.BrownianDynamics(free)
    fd.step(10)
    assert fd.positions.shape == (1, 3)
    with pytest.raises(colloidsim.ColloidsimError, match="hydrodynamics.method"):
        colloidsim.BrownianDynamics(dict(BULK_SCENARIO, hydrodynamics={"model": "rpy", "method": "direct"}))


def test_monte_carlo_and_mpcd_engines():
    mc = colloidsim.MonteCarlo(EXAMPLES / "mc/bulk.toml")
    p0 = mc.positions.copy()
    mc.step(2)
    assert mc.steps == 2 and mc.positions.shape == p0.shape and not np.array_equal(p0, mc.positions)
    srd = colloidsim.MPCD(EXAMPLES / "mpcd/viscosity.toml", overrides={"system.box": 6.0})
    assert srd.particles == 5 * 6**3
    srd.step(3)
    v = srd.velocities
    assert v.shape == (srd.particles, 3) and np.all(np.isfinite(v))
    assert abs(srd.time - 0.3) < 1e-12 and srd.dt == 0.1
    # The cell thermostat keeps the solvent at kT = 1 (m = 1): 3 (N - 1) kT within 5 sigma.
    n = srd.particles
    twice_ke = float(np.sum((v - v.mean(axis=0)) ** 2))
    assert abs(twice_ke / (3 * (n - 1)) - 1.0) < 5 * (2 / (3 * n)) ** 0.5
    with pytest.raises(colloidsim.ColloidsimError, match="method = 'mpcd'"):
        colloidsim.MPCD(BCD_SCENARIO)


def test_an_mpcd_engine_with_a_colloid():
    over = {"system.box": 8.0, "system.diameter": 3.0, "run.collisions": 100, "run.equilibrate": 10,
            "observe.vacf_lags": 5}
    a = colloidsim.MPCD(EXAMPLES / "mpcd/colloid-diffusion.toml", overrides=over)
    solvent = 5 * 8**3
    assert a.particles == solvent + 43
    x0 = a.positions.copy()
    a.step(4)
    b = colloidsim.MPCD(EXAMPLES / "mpcd/colloid-diffusion.toml", overrides=over)
    b.step(1)
    b.step(3)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.velocities, b.velocities)
    x, f = a.positions, a.forces
    assert not np.array_equal(x0[solvent:], x[solvent:])
    # The vertices lie on the sphere of diameter 3 about the centre, within the bond strain.
    r = np.linalg.norm(x[solvent + 1:] - x[solvent], axis=1)
    assert r.shape == (42,) and np.all(np.abs(r - 1.5) < 0.1)
    assert np.all(f[:solvent] == 0.0) and np.abs(f[solvent:]).max() > 0.0
    # One colloid's bonds are internal forces: they sum to zero.
    assert np.abs(f[solvent:].sum(axis=0)).max() < 1e-9 * np.abs(f).max()


def test_engine_classes_check_the_method():
    with pytest.raises(colloidsim.ColloidsimError, match="method = 'dpd'"):
        colloidsim.DPD(BCD_SCENARIO)
    with pytest.raises(ValueError, match="steps"):
        colloidsim.BCD(BCD_SCENARIO).step(-1)


def test_analyzers_see_every_trigger_step_and_leave_the_trajectory_alone():
    seen = []
    a = colloidsim.BCD(BCD_SCENARIO)
    a.add_analyzer(lambda e: seen.append((e.steps, e.positions.copy())), colloidsim.Periodic(7))
    odd = []
    a.add_analyzer(lambda e: odd.append(e.steps), lambda step: step % 10 == 3)
    a.step(20)
    a.step(30)
    assert [s for s, _ in seen] == list(range(7, 50, 7))
    assert odd == [3, 13, 23, 33, 43]
    b = colloidsim.BCD(BCD_SCENARIO)
    b.step(50)
    assert np.array_equal(a.positions, b.positions)
    # Each analyzer saw the engine at its step: the positions of a plain run at step 21.
    c = colloidsim.BCD(BCD_SCENARIO)
    c.step(21)
    assert np.array_equal(dict(seen)[21], c.positions)
    with pytest.raises(colloidsim.ColloidsimError, match="period"):
        colloidsim.Periodic(0)
    with pytest.raises(colloidsim.ColloidsimError, match="trigger"):
        a.add_analyzer(print, "often")


def test_snapshots_are_gsd_frames(tmp_path):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    e = colloidsim.BrownianDynamics(EXAMPLES / "droplet/drying-bd.toml")
    path = tmp_path / "own.gsd"
    with gsd_hoomd.open(str(path), "w") as t:
        e.add_analyzer(lambda en: t.append(en.snapshot()), colloidsim.Periodic(5))
        e.step(10)
    with gsd_hoomd.open(str(path)) as t:
        assert [f.configuration.step for f in t] == [5, 10]
        np.testing.assert_array_equal(t[1].particles.position, e.positions.astype(np.float32))
    rods = colloidsim.BCD(BCD_SCENARIO)
    rods.step(100)
    f = rods.snapshot()
    x = f.particles.position[:, 0] + 10.0 + 20.0 * f.particles.image[:, 0]
    np.testing.assert_allclose(x, rods.positions, atol=1e-5)
    assert list(f.configuration.box) == [20.0, 20.0, 0.0, 0.0, 0.0, 0.0]
