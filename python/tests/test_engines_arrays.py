"""Engines from keywords, arrays and gsd frames; state set between runs; forces from Python."""

import os

import numpy as np
import pytest

import colloidsim
from colloidsim import ColloidsimError


def tool(name):
    """A tool the test compares with: required under COLLOIDSIM_REQUIRE_TOOLS (CI)."""
    if os.environ.get("COLLOIDSIM_REQUIRE_TOOLS"):
        import importlib

        return importlib.import_module(name)
    return pytest.importorskip(name)


BD = dict(method="bd", particles=12, box_length=6.0, dt=1e-3, seed=5)
BD_SCENARIO = {
    "method": "bd",
    "seed": 5,
    "system": {"particles": 12, "box_length": 6.0},
    "run": {"dt": 1e-3, "time": 10.0},
}


def test_an_engine_from_keywords_is_the_engine_of_the_scenario():
    a = colloidsim.BrownianDynamics(**BD)
    b = colloidsim.BrownianDynamics(BD_SCENARIO)
    a.step(30)
    b.step(30)
    assert np.array_equal(a.positions, b.positions)
    assert a.seed == 5 and a.dt == 1e-3
    with pytest.raises(ColloidsimError, match="dtt: not a key of bd scenarios.*did you mean dt"):
        colloidsim.BrownianDynamics(method="bd", particles=12, box_length=6.0, dtt=1e-3)
    with pytest.raises(ColloidsimError, match="hydrodynamics: one of"):
        colloidsim.BrownianDynamics(**BD, hydrodynamics="stokesian")
    with pytest.raises(ColloidsimError, match="method: BrownianDynamics needs method"):
        colloidsim.BrownianDynamics(particles=12)


def test_an_engine_from_arrays_is_the_engine_of_the_scenario_that_reads_them(tmp_path):
    gsd_hoomd = tool("gsd.hoomd")
    rng = np.random.default_rng(1)
    # A lattice of a binary mixture, positions exact in single precision (the GSD file's).
    g = (np.arange(3) - 1.0) * 2.0
    x = np.array([[i, j, k] for i in g for j in g for k in g], dtype=np.float32)[:24]
    x += rng.uniform(-0.25, 0.25, x.shape).astype(np.float32)
    types = np.array([0] * 16 + [1] * 8)
    rng.shuffle(types)
    f = gsd_hoomd.Frame()
    f.configuration.box = [6.0, 6.0, 6.0, 0, 0, 0]
    f.particles.N = len(x)
    f.particles.position = x
    f.particles.types = ["A", "B"]
    f.particles.typeid = types.astype(np.uint32)
    with gsd_hoomd.open(str(tmp_path / "start.gsd"), "w") as t:
        t.append(f)
    sc = {
        "method": "bd",
        "seed": 2,
        "system": {
            "particles": 24,
            "box_length": 6.0,
            "initial": str(tmp_path / "start.gsd"),
            "species": {"diameters": [1.0, 0.6], "counts": [16, 8]},
        },
        "run": {"dt": 1e-3, "time": 10.0},
    }
    a = colloidsim.BrownianDynamics(sc)
    b = colloidsim.BrownianDynamics.from_arrays(
        x.astype(float), box=6.0, types=types, diameters=[1.0, 0.6], method="bd", dt=1e-3, seed=2
    )
    assert np.array_equal(a.positions, b.positions)
    a.step(40)
    b.step(40)
    assert np.array_equal(a.positions, b.positions)
    frame = b.snapshot()
    assert list(frame.particles.types) == ["A", "B"]
    assert np.array_equal(frame.particles.typeid, types)
    np.testing.assert_array_equal(frame.particles.diameter, np.where(types == 0, 1.0, 0.6).astype(np.float32))
    # hs-mc reads its start file too: bitwise the same sweeps.
    mc_sc = {
        "method": "hs-mc",
        "seed": 4,
        "system": {"geometry": "bulk", "particles": 24, "box": 6.0, "diameter": 0.8,
                   "initial": str(tmp_path / "start.gsd")},
    }
    f.particles.typeid = np.zeros(24, dtype=np.uint32)
    f.particles.types = ["A"]
    with gsd_hoomd.open(str(tmp_path / "start.gsd"), "w") as t:
        t.append(f)
    c = colloidsim.MonteCarlo(mc_sc)
    d = colloidsim.MonteCarlo.from_arrays(x.astype(float), box=6.0, diameters=0.8, geometry="bulk", seed=4)
    c.step(5)
    d.step(5)
    assert np.array_equal(c.positions, d.positions)


@pytest.mark.parametrize(
    "cls,keys,at",
    [
        (colloidsim.BrownianDynamics, dict(BD, hydrodynamics={"model": "rpy", "splitting": 2.0}), 3),
        (colloidsim.BrownianDynamics, dict(method="droplet-bd", particles=20, phi0=0.05, dt=1e-4, seed=3), 3),
        (colloidsim.BCD, dict(length=30.0, particles=12, diameter=1.0, dt=1e-3, seed=6), 3),
        # DPD's velocity Verlet carries the last step's forces, which a frame does not hold: a
        # frame of a later step continues with them recomputed (its checkpoints keep them).
        (colloidsim.DPD, dict(box_length=7.0, density=3.0, phi=0.1, kT=0.1, colloid_radius=1.0,
                              dt=1e-3, steps=10, seed=1), 0),
    ],
)
def test_a_run_from_a_gsd_frame_is_the_run_of_the_engine_that_wrote_it(tmp_path, cls, keys, at):
    gsd_hoomd = tool("gsd.hoomd")
    a = cls(**keys)
    a.step(at)
    path = tmp_path / "frame.gsd"
    with gsd_hoomd.open(str(path), "w") as t:
        t.append(a.snapshot())
    b = cls.from_frame(path, **keys)
    assert b.steps == a.steps == at and b.time == a.time
    a.step(20)
    b.step(20)
    assert np.array_equal(a.positions, b.positions)
    if a.velocities is not None:
        assert np.array_equal(a.velocities, b.velocities)


def test_state_set_between_runs():
    a = colloidsim.BCD(length=30.0, particles=12, diameter=1.0, dt=1e-3, seed=6)
    b = colloidsim.BCD(length=30.0, particles=12, diameter=1.0, dt=1e-3, seed=6)
    a.step(100)
    b.step(100)
    # Its own state, set again: the run goes on bitwise.
    b.set_state(positions=b.positions, steps=b.steps, seed=b.seed)
    a.step(100)
    b.step(100)
    assert np.array_equal(a.positions, b.positions)
    # Another seed another path; the seed back, the same path.
    x, s = b.positions, b.steps
    b.seed = 9
    b.step(50)
    y = b.positions
    b.set_state(positions=x, steps=s, seed=6)
    b.step(50)
    a.step(50)
    assert np.array_equal(a.positions, b.positions) and not np.array_equal(y, b.positions)
    # The step sets the time.
    b.steps = 1000
    assert b.time == pytest.approx(1.0)
    # Positions and velocities of MPCD's solvent and DPD's beads.
    d = colloidsim.DPD(box_length=7.0, density=3.0, phi=0.1, kT=0.1, colloid_radius=1.0, dt=1e-3, steps=10)
    v = d.velocities
    d.velocities = 2.0 * v
    assert np.array_equal(d.velocities, 2.0 * v)
    shifted = d.positions + [0.5, 0.0, 0.0]
    d.positions = shifted
    np.testing.assert_allclose(d.positions, shifted, atol=1e-12)


def test_bad_state_raises_naming_the_argument_and_leaves_the_engine_as_it_was():
    bd = colloidsim.BrownianDynamics(**BD)
    x = bd.positions
    cases = [
        (lambda: setattr(bd, "positions", x[:5]), "positions: 12 particles need 12 x 3 = 36 numbers, got 15"),
        (lambda: setattr(bd, "positions", np.where(np.arange(36).reshape(12, 3) == 4, np.nan, x)),
         r"positions: particle 1 has a non-finite value"),
        (lambda: setattr(bd, "velocities", x), "velocities: the bd engine has none"),
        (lambda: setattr(bd, "steps", -1), "steps: a whole number >= 0"),
        (lambda: setattr(bd, "seed", 2**32), "seed:"),
        (lambda: bd.set_state(positions="abc"), "positions: not an array of numbers"),
    ]
    for call, message in cases:
        with pytest.raises(ColloidsimError, match=message):
            call()
        assert np.array_equal(bd.positions, x) and bd.steps == 0 and bd.seed == 5
    mc = colloidsim.MonteCarlo(geometry="bulk", particles=32, volume_fraction=0.3, seed=1)
    y = mc.positions
    overlapping = y.copy()
    overlapping[1] = overlapping[0]
    with pytest.raises(ColloidsimError, match="positions: spheres 0 and 1 overlap"):
        mc.positions = overlapping
    assert np.array_equal(mc.positions, y)
    rods = colloidsim.BCD(length=30.0, particles=12, diameter=1.0, dt=1e-3)
    with pytest.raises(ColloidsimError, match="positions: .*overlap"):
        rods.positions = rods.positions[::-1]


@pytest.mark.parametrize("hydro", [None, {"model": "rpy", "splitting": 2.0}])
def test_a_python_force_moves_particles_as_the_built_in_force(hydro):
    keys = dict(BD) if hydro is None else dict(BD, hydrodynamics=hydro)
    a = colloidsim.BrownianDynamics(**keys, body_force=[2.0, 0.0, -1.0])
    b = colloidsim.BrownianDynamics(**keys)
    calls = []

    def push(e):
        calls.append(e.steps)
        return np.tile([2.0, 0.0, -1.0], (e.particles, 1))

    b.add_force(push)
    a.step(25)
    b.run(25)  # HOOMD's name for step
    assert calls == list(range(25))
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.forces, b.forces)
    # Removed, the engine moves as one without it.
    c = colloidsim.BrownianDynamics(**keys)
    c.set_state(positions=b.positions, steps=b.steps)
    b.remove_force(push)
    b.set_state(positions=b.positions, steps=b.steps)
    b.step(10)
    c.step(10)
    assert np.array_equal(b.positions, c.positions)
    with pytest.raises(ColloidsimError, match=r"force: .* returned shape \(3,\)"):
        b.add_force(lambda e: np.zeros(3))
        b.step(1)
    with pytest.raises(ColloidsimError, match="forces: the hs-mc engine takes no forces"):
        colloidsim.MonteCarlo(geometry="bulk", particles=32, volume_fraction=0.3).add_force(push)
