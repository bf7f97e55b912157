"""colloidsim.hydro: the libMobility-shaped mobility operators, against independent formulas
(the RPY tensor written here in numpy, Hasimoto's periodic self-mobility), against the engine's
Brownian step, and their noise's covariance against M within its statistical error."""

import math

import numpy as np
import pytest

import colloidsim
from colloidsim import ColloidsimError
from conftest import EXAMPLES
from colloidsim.hydro import NBody, PSE, SelfMobility

ETA = 0.7


def rpy_block(d, ai, aj, eta):
    """The 3x3 RPY block M_ij for the separation d = x_i - x_j (Rotne & Prager 1969, Yamakawa
    1970; unequal radii, overlapping and one inside the other: Zuk, Wajnryb, Mizerski &
    Szymczak 2014), written from the papers' formulas."""
    r = float(np.linalg.norm(d))
    eye = np.eye(3)
    if r == 0.0 or r <= abs(ai - aj):
        return eye / (6 * math.pi * eta * max(ai, aj))
    rr = np.outer(d, d) / r**2
    if r > ai + aj:
        s = ai**2 + aj**2
        return ((1 + s / (3 * r**2)) * eye + (1 - s / r**2) * rr) / (8 * math.pi * eta * r)
    if ai == aj:
        a = ai
        return ((1 - 9 * r / (32 * a)) * eye + (3 * r / (32 * a)) * rr) / (6 * math.pi * eta * a)
    t1 = (16 * r**3 * (ai + aj) - ((ai - aj) ** 2 + 3 * r**2) ** 2) / (32 * r**3)
    t2 = 3 * ((ai - aj) ** 2 - r**2) ** 2 / (32 * r**3)
    return (t1 * eye + t2 * rr) / (6 * math.pi * eta * ai * aj)


def rpy_matrix(x, radii, eta):
    n = len(x)
    m = np.zeros((3 * n, 3 * n))
    for i in range(n):
        for j in range(n):
            m[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] = rpy_block(x[i] - x[j], radii[i], radii[j], eta)
    return m


def dense(solver, n):
    """The 3N x 3N matrix of a solver, column by column from Mdot."""
    cols = []
    for k in range(3 * n):
        e = np.zeros(3 * n)
        e[k] = 1.0
        cols.append(solver.Mdot(e)[0])
    return np.array(cols).T


def cluster(n, spread, seed=1):
    rng = np.random.default_rng(seed)
    return rng.uniform(-spread, spread, size=(n, 3))


def test_nbody_product_equals_the_rpy_formula_with_overlapping_pairs():
    x = cluster(13, 1.5)
    # Pairs at contact, overlapping (r < 2a) and on top of each other.
    x[1] = x[0] + [0.3, 0.1, -0.2]
    x[2] = x[0] + [1.0, 0.0, 0.0]
    x[3] = x[0]
    a = 0.5
    solver = NBody("open", "open", "open")
    solver.setParameters(algorithm="advise")
    solver.initialize(viscosity=ETA, hydrodynamicRadius=a)
    solver.setPositions(x)
    want = rpy_matrix(x, [a] * 13, ETA)
    r = np.linalg.norm(x[:, None] - x[None], axis=-1)
    assert np.sum((r > 0) & (r < 2 * a)) >= 4  # the overlapping branch is tested
    f = np.random.default_rng(2).normal(size=(13, 3))
    u, w = solver.Mdot(forces=f)
    assert w is None and u.shape == (13, 3) and u.dtype == np.float64
    ref = (want @ f.reshape(-1)).reshape(13, 3)
    assert np.max(np.abs(u - ref)) <= 1e-10 * np.max(np.abs(ref))
    # Flat (3N,) arrays in, flat out; the dense matrix column by column, to 1e-10.
    flat, _ = solver.Mdot(f.reshape(-1))
    assert flat.shape == (39,) and np.array_equal(flat, u.reshape(-1))
    m = dense(solver, 13)
    assert np.max(np.abs(m - want)) <= 1e-10 * np.max(np.abs(want))


def test_nbody_unequal_radii_equal_zuk_formula_in_all_three_branches():
    radii = np.array([0.5, 1.2, 0.8, 0.5, 2.0])
    x = np.array(
        [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [3.5, 0.0, 0.3], [-4.0, 1.0, 1.0], [-4.3, 1.2, 1.1]]
    )
    solver = NBody("open", "open", "open")
    solver.initialize(viscosity=ETA, hydrodynamicRadius=radii)
    solver.setPositions(x)
    r = np.linalg.norm(x[:, None] - x[None], axis=-1)
    s = radii[:, None] + radii[None]
    dif = np.abs(radii[:, None] - radii[None])
    off = ~np.eye(5, dtype=bool)
    # Far, overlapping and inside pairs are all present.
    assert np.any(off & (r > s)) and np.any(off & (r < s) & (r > dif)) and np.any(off & (r <= dif))
    want = rpy_matrix(x, radii, ETA)
    m = dense(solver, 5)
    assert np.max(np.abs(m - want)) <= 1e-10 * np.max(np.abs(want))


def test_self_mobility_is_free_draining():
    s = SelfMobility("open", "open", "open")
    s.setParameters(parameter=1.0)
    s.initialize(viscosity=2.0, hydrodynamicRadius=0.25)
    s.setPositions(np.zeros(6))
    u, _ = s.Mdot(np.arange(6.0))
    assert np.allclose(u, np.arange(6.0) / (6 * math.pi * 2.0 * 0.25), rtol=1e-14)
    assert np.array_equal(s.divM()[0], np.zeros(6))


def pse(n_box, psi=1.0, radius=0.5, tolerance=1e-5, seed=None):
    s = PSE(periodicityX="periodic", periodicityY="periodic", periodicityZ="periodic")
    s.setParameters(psi=psi, Lx=n_box, Ly=n_box, Lz=n_box)
    s.initialize(viscosity=ETA, hydrodynamicRadius=radius, tolerance=tolerance, seed=seed)
    return s


def test_pse_self_mobility_is_hasimotos():
    a = 0.5
    mu0 = 1 / (6 * math.pi * ETA * a)
    for box in (6.0, 10.0):
        s = pse(box, psi=2.0, radius=a, tolerance=1e-6)
        s.setPositions([[0.3, -1.0, 2.0]])
        u, _ = s.Mdot([[1.0, 0.0, 0.0]])
        e = a / box
        # Hasimoto (1959) for the periodic RPY sphere: the (a/L)^6 term is below 2e-6 here.
        want = 1 - 2.837297 * e + 4 * math.pi / 3 * e**3
        assert abs(u[0, 0] / mu0 - want) < 1e-5, (box, u[0, 0] / mu0, want)
        assert abs(u[0, 1]) < 1e-6 * mu0 and abs(u[0, 2]) < 1e-6 * mu0


def test_pse_is_symmetric_positive_definite_and_tends_to_free_rpy_in_large_boxes():
    n, a = 6, 0.5
    x = cluster(n, 1.2, seed=4)
    x[1] = x[0] + [0.4, 0.2, 0.0]  # an overlapping pair
    mu0 = 1 / (6 * math.pi * ETA * a)
    free = rpy_matrix(x, [a] * n, ETA)
    residual = []
    for box in (20.0, 40.0):
        s = pse(box, psi=0.5, radius=a, tolerance=1e-6)
        s.setPositions(x + 7 * box)  # any periodic image
        m = dense(s, n)
        assert np.max(np.abs(m - m.T)) < 1e-6 * mu0
        assert np.min(np.linalg.eigvalsh(0.5 * (m + m.T))) > 0
        # In a box much larger than the cluster, each block is the free RPY block shifted by
        # the images' uniform backflow, Hasimoto's -2.837297 / (6 pi eta L) I (the self blocks
        # by (4 pi / 3) (a/L)^3 mu0 more), up to terms in r^2 / (eta L^3): what is left falls
        # as L^-3 (halving the box multiplies it by 8), where a wrong near field or backflow
        # would leave an L^-1 or L^0 residual.
        shift = np.kron(np.ones((n, n)), np.eye(3)) * (-2.837297 / (6 * math.pi * ETA * box))
        shift += np.eye(3 * n) * (4 * math.pi / 3) * (a / box) ** 3 * mu0
        residual.append(np.max(np.abs(m - free - shift)) / mu0)
    assert residual[1] < 1e-3, residual
    assert 5 < residual[0] / residual[1] < 12, residual
    # u.M v = v.M u with the products themselves.
    rng = np.random.default_rng(5)
    u, v = rng.normal(size=(2, n, 3))
    assert abs(np.vdot(u, s.Mdot(v)[0]) - np.vdot(v, s.Mdot(u)[0])) < 1e-6 * mu0 * n


def test_pse_unequal_radii_are_symmetric_and_positive():
    radii = np.array([0.5, 0.5, 1.0, 1.0])
    s = PSE("periodic", "periodic", "periodic")
    s.setParameters(psi=0.8, Lx=12.0, Ly=12.0, Lz=12.0)
    s.initialize(viscosity=1.0, hydrodynamicRadius=radii, tolerance=1e-5)
    x = np.array([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0], [0.0, 1.7, 0.0], [3.0, 3.0, 3.0]])
    s.setPositions(x)
    m = dense(s, 4)
    assert np.max(np.abs(m - m.T)) < 1e-5 * np.max(np.abs(m))
    assert np.min(np.linalg.eigvalsh(0.5 * (m + m.T))) > 0
    assert m[6, 6] < m[0, 0]  # the larger sphere is the slower


def covariance_check(solver, m, samples):
    """Sample covariance of sqrtMdotW against M within its statistical error: every entry to
    5 standard errors, sqrt((M_ii M_jj + M_ij^2) / S) for Gaussian noise, and the whitened
    norm E[w.M^-1 w] = 3N to 5 standard errors, sqrt(6N / S)."""
    w = np.array([solver.sqrtMdotW(prefactor=1.0)[0].reshape(-1) for _ in range(samples)])
    c = w.T @ w / samples
    d = np.diag(m)
    se = np.sqrt((np.outer(d, d) + m**2) / samples)
    assert np.all(np.abs(c - m) < 5 * se), np.max(np.abs(c - m) / se)
    k = m.shape[0]
    q = np.einsum("si,ij,sj->s", w, np.linalg.inv(m), w)
    assert abs(q.mean() - k) < 5 * math.sqrt(2 * k / samples), (q.mean(), k)


def test_nbody_noise_covariance_is_m():
    x = np.array([[0.0, 0.0, 0.0], [0.7, 0.2, 0.0], [2.5, -0.5, 1.0]])
    s = NBody("open", "open", "open")
    s.initialize(viscosity=ETA, hydrodynamicRadius=np.array([0.5, 0.5, 0.9]), tolerance=1e-8, seed=11)
    s.setPositions(x)
    covariance_check(s, dense(s, 3), 4000)
    # Reproducible from the seed and the noise step; the prefactor scales it.
    s.noiseStep = 3
    a, _ = s.sqrtMdotW(2.0)
    s.noiseStep = 3
    b, _ = s.sqrtMdotW()
    assert s.noiseStep == 4 and np.array_equal(a, 2.0 * b)


def test_pse_noise_covariance_is_m():
    s = pse(6.0, psi=2.0, radius=0.5, tolerance=1e-4, seed=12)
    s.setPositions(np.array([[0.0, 0.0, 0.0], [0.9, 0.0, 0.3]]))
    covariance_check(s, dense(s, 2), 3000)


def test_langevin_velocities_equal_the_engines_brownian_step():
    # A bd engine with RPY by PSE: its first step's displacements are the PSE solver's
    # LangevinVelocities times dt at the engine's positions, forces and seed (noise step 0),
    # to round-off.
    box, seed, dt = 6.0, 5, 1e-3
    bd = colloidsim.BrownianDynamics(
        {
            "method": "bd",
            "seed": seed,
            "system": {"particles": 12, "box_length": box, "viscosity": ETA},
            "run": {"dt": dt, "time": 1.0},
            "hydrodynamics": {"model": "rpy", "splitting": 1.5, "tolerance": 1e-4},
        }
    )
    x0, f0 = bd.positions.copy(), bd.forces.copy()
    bd.step(1)
    dx = bd.positions - x0
    dx -= box * np.round(dx / box)
    s = pse(box, psi=1.5, radius=0.5, tolerance=1e-4, seed=seed)
    s.setPositions(x0)
    v, _ = s.LangevinVelocities(dt=dt, kbt=1.0, forces=f0)
    assert np.max(np.abs(v * dt - dx)) < 1e-12 * np.max(np.abs(dx))
    # Without noise it is M F.
    assert np.allclose(s.LangevinVelocities(dt=dt, kbt=0.0, forces=f0)[0], s.Mdot(f0)[0], rtol=0, atol=0)


def test_nbody_langevin_velocities_equal_the_droplet_engines_brownian_step():
    # A drying droplet with free-space RPY (direct sums), 30 spheres: its first step is the
    # NBody solver's LangevinVelocities times dt at the engine's positions, forces (interface
    # and WCA) and seed, to round-off.
    bd = colloidsim.BrownianDynamics(
        EXAMPLES / "droplet/drying-rpy.toml",
        overrides={"system.particles": 30, "system.viscosity": ETA, "seed": 9},
    )
    x0, f0 = bd.positions.copy(), bd.forces.copy()
    assert np.max(np.abs(f0)) > 0.1  # the forces take part
    bd.step(1)
    dx = bd.positions - x0
    s = NBody("open", "open", "open")
    s.initialize(viscosity=ETA, hydrodynamicRadius=0.5, tolerance=1e-3, seed=9)
    s.setPositions(x0)
    v, _ = s.LangevinVelocities(dt=bd.dt, kbt=1.0, forces=f0)
    assert np.max(np.abs(v * bd.dt - dx)) < 1e-12 * np.max(np.abs(dx))


def test_thermal_drift_is_the_random_finite_difference_and_averages_to_zero():
    radii = np.array([0.5, 0.9, 0.5])
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.3, 0.0], [0.4, 0.6, 0.5]])
    s = NBody("open", "open", "open")
    s.setParameters(delta=1e-3)
    s.initialize(viscosity=ETA, hydrodynamicRadius=radii, seed=21)
    s.setPositions(x)
    # One sample: (M(x + d W/2) W - M(x - d W/2) W) / d, W from PCG64([seed, noise step]).
    s.noiseStep = 7
    got, _ = s.thermalDrift(prefactor=2.0)
    w = np.random.Generator(np.random.PCG64([21, 7])).standard_normal(9)
    d = 1e-3 * 0.5
    plus = rpy_matrix(x + 0.5 * d * w.reshape(3, 3), radii, ETA) @ w
    minus = rpy_matrix(x - 0.5 * d * w.reshape(3, 3), radii, ETA) @ w
    want = 2.0 * (plus - minus) / d
    assert np.max(np.abs(got.reshape(-1) - want)) < 1e-6 * np.max(np.abs(want))
    # The positions are restored.
    assert np.array_equal(s.Mdot(np.ones(9))[0], NBody_product(x, radii))
    # div M = 0 (RPY is divergence-free): the samples average to zero within their error.
    samples = np.array([s.thermalDrift()[0].reshape(-1) for _ in range(2000)])
    mean, se = samples.mean(axis=0), samples.std(axis=0) / math.sqrt(2000)
    assert np.all(np.abs(mean) < 5 * se), np.max(np.abs(mean) / se)
    assert np.array_equal(s.divM()[0], np.zeros((3, 3)))


def NBody_product(x, radii):
    t = NBody("open", "open", "open")
    t.initialize(viscosity=ETA, hydrodynamicRadius=radii)
    t.setPositions(x)
    return t.Mdot(np.ones(9))[0]


def test_lanczos_callback_and_precision():
    seen = []
    s = NBody("open", "open", "open")
    s.initialize(viscosity=1.0, hydrodynamicRadius=0.5, lanczos_callback=lambda i, e: seen.append((i, e)))
    s.setPositions(cluster(5, 2.0))
    s.sqrtMdotW()
    assert len(seen) == 1 and seen[0][0] >= 1 and seen[0][1] <= 1e-4
    assert NBody.precision == "double"


BAD = [
    (lambda: NBody("periodic", "open", "open"), "periodicityX"),
    (lambda: NBody("open", "open", "single_wall"), "periodicityZ"),
    (lambda: NBody("open", "open", "nonsense"), "periodicityZ"),
    (lambda: PSE("periodic", "open", "periodic"), "periodicityY"),
]


@pytest.mark.parametrize("call,name", BAD)
def test_bad_construction_names_the_argument(call, name):
    with pytest.raises(ColloidsimError, match=f"^{name}:"):
        call()


def nbody():
    s = NBody("open", "open", "open")
    s.initialize(viscosity=1.0, hydrodynamicRadius=0.5)
    s.setPositions(np.zeros((2, 3)))
    return s


def test_bad_arguments_name_the_argument():
    cases = [
        (lambda s: s.initialize(viscosity=-1.0, hydrodynamicRadius=0.5), "viscosity"),
        (lambda s: s.initialize(viscosity=1.0, hydrodynamicRadius=0.0), "hydrodynamicRadius"),
        (lambda s: s.initialize(viscosity=1.0, hydrodynamicRadius=[0.5, np.nan]), "hydrodynamicRadius"),
        (lambda s: s.initialize(viscosity=1.0, hydrodynamicRadius=0.5, tolerance=0.5), "tolerance"),
        (lambda s: s.initialize(viscosity=1.0, hydrodynamicRadius=0.5, includeAngular=True), "includeAngular"),
        (lambda s: s.initialize(viscosity=1.0, hydrodynamicRadius=0.5, seed=-3), "seed"),
        (lambda s: s.initialize(viscosity=1.0, hydrodynamicRadius=0.5, maxIterations=0), "maxIterations"),
        (lambda s: s.setPositions(np.zeros((2, 2))), "positions"),
        (lambda s: s.setPositions([[0.0, 0.0, np.inf]]), "positions"),
        (lambda s: s.Mdot(np.zeros(9)), "forces"),
        (lambda s: s.Mdot(np.zeros(6), torques=np.zeros(6)), "torques"),
        (lambda s: s.Mdot(), "forces"),
        (lambda s: s.sqrtMdotW(prefactor=float("nan")), "prefactor"),
        (lambda s: s.LangevinVelocities(dt=0.0, kbt=1.0), "dt"),
        (lambda s: s.LangevinVelocities(dt=1.0, kbt=-1.0), "kbt"),
        (lambda s: s.setParameters(Nbatch=3), "Nbatch"),
        (lambda s: s.setParameters(wallHeight=1.0), "wallHeight"),
        (lambda s: s.setParameters(algorithm="magic"), "algorithm"),
    ]
    for call, name in cases:
        with pytest.raises(ColloidsimError, match=f"^{name}:"):
            call(nbody())
    fresh = NBody("open", "open", "open")
    with pytest.raises(ColloidsimError, match="^initialize:"):
        fresh.setPositions(np.zeros(3))
    radii = NBody("open", "open", "open")
    radii.initialize(viscosity=1.0, hydrodynamicRadius=[0.5, 0.5, 0.5])
    with pytest.raises(ColloidsimError, match="^hydrodynamicRadius:"):
        radii.setPositions(np.zeros((2, 3)))
    with pytest.raises(ColloidsimError, match="^positions:"):
        NBody("open", "open", "open").sqrtMdotW()
    p = PSE("periodic", "periodic", "periodic")
    with pytest.raises(ColloidsimError, match="^setParameters:"):
        p.initialize(viscosity=1.0, hydrodynamicRadius=0.5)
    for kwargs, name in [
        (dict(psi=0.0, Lx=8.0, Ly=8.0, Lz=8.0), "psi"),
        (dict(psi=1.0, Lx=8.0, Ly=9.0, Lz=8.0), "Ly"),
        (dict(psi=1.0, Lx=8.0, Ly=8.0, Lz=7.0), "Lz"),
        (dict(psi=1.0, Lx=8.0, Ly=8.0, Lz=8.0, shearStrain=0.1), "shearStrain"),
    ]:
        with pytest.raises(ColloidsimError, match=f"^{name}:"):
            p.setParameters(**kwargs)
    # The engine's own checks, renamed to the arguments: a box below 4 radii, a splitting
    # whose real-space part overreaches half the box.
    for (psi, box), name in [((1.0, 1.5), "Lx"), ((0.1, 8.0), "psi")]:
        q = pse(box, psi=psi)
        with pytest.raises(ColloidsimError, match=f"^{name}:"):
            q.setPositions(np.zeros((2, 3)))
    assert issubclass(ColloidsimError, RuntimeError)  # libMobility raises RuntimeError


def test_initialize_again_keeps_the_positions_and_shapes_follow_the_input():
    s = NBody("open", "open", "open")
    s.initialize(viscosity=1.0, hydrodynamicRadius=0.5, seed=3)
    x = cluster(4, 2.0).reshape(-1)
    s.setPositions(x)
    assert s.numberParticles == 4 and s.sqrtMdotW()[0].shape == (12,)
    s.initialize(viscosity=2.0, hydrodynamicRadius=0.5, seed=3)
    u, _ = s.Mdot(np.ones((4, 3)))
    assert u.shape == (4, 3)
    assert np.allclose(u.reshape(-1), rpy_matrix(x.reshape(4, 3), [0.5] * 4, 2.0) @ np.ones(12), rtol=1e-12)
    assert s.divM()[0].shape == (12,) and s.thermalDrift()[0].shape == (12,)
