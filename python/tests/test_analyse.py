"""`colloidsim analyse` and `colloidsim.analyse` on a trajectory written by the `gsd` package:
the same files from the CLI and from Python, g(r) and the MSD as freud computes them from the
same frames, errors that name the argument."""

import importlib
import os

import numpy as np
import pytest

import colloidsim

N, L, FRAMES, R_MAX, BINS = 400, 10.0, 12, 4.0, 80


def _tool(name):
    if os.environ.get("COLLOIDSIM_REQUIRE_TOOLS"):
        return importlib.import_module(name)  # CI: a missing tool fails, never skips
    return pytest.importorskip(name)


@pytest.fixture(scope="module")
def trajectory(tmp_path_factory):
    """Random walkers of two types in a periodic cube, with image flags: frame k at step
    100 k, float32 positions as HOOMD writes them."""
    gsd_hoomd = _tool("gsd.hoomd")
    rng = np.random.default_rng(7)
    x = rng.uniform(-L / 2, L / 2, (N, 3))
    img = np.zeros((N, 3), dtype=np.int32)
    path = tmp_path_factory.mktemp("traj") / "walk.gsd"
    wrapped, images = [], []
    with gsd_hoomd.open(str(path), "w") as t:
        for k in range(FRAMES):
            f = gsd_hoomd.Frame()
            f.configuration.step = 100 * k
            f.configuration.box = [L, L, L, 0, 0, 0]
            f.particles.N = N
            f.particles.types = ["A", "B"]
            f.particles.typeid = (np.arange(N) % 2).astype(np.uint32)
            f.particles.position = x.astype(np.float32)
            f.particles.image = img
            t.append(f)
            wrapped.append(x.astype(np.float32).copy())
            images.append(img.copy())
            x = x + rng.normal(0.0, 0.4, (N, 3))
            shift = np.floor((x + L / 2) / L).astype(np.int32)
            x -= shift * L
            img = img + shift
    return path, np.array(wrapped), np.array(images)


def test_the_cli_and_python_write_the_same_files(trajectory, cli, tmp_path):
    path, _, _ = trajectory
    args = dict(r_max=R_MAX, bins=BINS, dt=0.01, frames="0:11:1", centre=(0.5, 0, 0))
    r = colloidsim.analyse(path, out=tmp_path / "py", **args)
    cli("analyse", path, "--out", tmp_path / "cli", "--r-max", R_MAX, "--bins", BINS,
        "--dt", 0.01, "--frames", "0:11:1", "--centre", "0.5,0,0")
    for name in ["gr.csv", "sq.csv", "msd.csv", "profile.csv", "clusters.csv", "coordination.csv"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert r.summary["analysis"]["frames"] == FRAMES
    assert set(r.files) >= {"gr.png", "msd.png", "profile.png"}
    # A Python slice leaves its stop out, as Python's do.
    s = colloidsim.analyse(path, out=tmp_path / "slice", frames=slice(2, 8, 3))
    assert s.summary["analysis"]["steps"] == [200, 500]


def test_g_of_r_is_freuds(trajectory, tmp_path):
    freud = _tool("freud")
    path, wrapped, _ = trajectory
    r = colloidsim.analyse(path, out=tmp_path / "a", r_max=R_MAX, bins=BINS)
    rdf = freud.density.RDF(bins=BINS, r_max=R_MAX)
    box = freud.box.Box.cube(L)
    for x in wrapped:
        rdf.compute(system=(box, x), reset=False)
    np.testing.assert_allclose(r.gr.r, rdf.bin_centers, rtol=1e-6)
    # freud works in float32: its g carries relative round-off of about 1e-6, and a pair
    # within round-off of a bin edge may fall on either side (one pair moved changes g by
    # `one` in its bin, about 1e-4 of g here).
    shell = 4.0 / 3.0 * np.pi * np.diff(rdf.bin_edges**3)
    one = 2.0 / (FRAMES * N * (N / L**3) * shell)
    diff = np.abs(r.gr.g - rdf.rdf)
    assert np.all(diff <= 2.0 * one), np.max(diff / one)
    assert np.mean(diff <= 1e-5 * rdf.rdf) > 0.95
    # The walkers are an ideal gas at every frame: g = (N - 1) / N within its error.
    mid = r.gr.r > 1.0
    z = (r.gr.g[mid] - (N - 1) / N) / r.gr.err[mid]
    assert np.mean(np.abs(z) < 3.0) > 0.95


def test_msd_is_freuds(trajectory, tmp_path):
    freud = _tool("freud")
    path, wrapped, images = trajectory
    r = colloidsim.analyse(path, out=tmp_path / "a", dt=0.5)
    msd = freud.msd.MSD(freud.box.Box.cube(L), mode="window")
    msd.compute(positions=wrapped, images=images)
    np.testing.assert_allclose(r.msd.msd, msd.msd[1:], rtol=1e-5)
    np.testing.assert_array_equal(r.msd.lag_steps, 100.0 * np.arange(1, FRAMES))
    np.testing.assert_allclose(r.msd.time, 50.0 * np.arange(1, FRAMES))
    # Steps of variance 0.4^2 per axis per frame: 3 * 0.16 per lag.
    np.testing.assert_allclose(r.msd.msd[:3], 0.48 * np.arange(1, 4), rtol=0.05)


def test_types_select_particles(trajectory, tmp_path):
    path, _, _ = trajectory
    r = colloidsim.analyse(path, out=tmp_path / "b", types=["B"], frames="0:3")
    assert r.summary["analysis"]["particles"] == N // 2
    assert r.summary["analysis"]["types"] == ["B"]


@pytest.mark.parametrize(
    "kwargs, named",
    [
        (dict(r_max=6.0), "r_max"),
        (dict(bins=0), "bins"),
        (dict(frames="5:2"), "frames"),
        (dict(frames="0:99"), "frames"),
        (dict(centre="middle"), "centre"),
        (dict(types=["C"]), "types"),
        (dict(dt=-1.0), "dt"),
        (dict(contact_gap=float("nan")), "contact_gap"),
    ],
)
def test_bad_arguments_raise_naming_them(trajectory, tmp_path, kwargs, named):
    path, _, _ = trajectory
    with pytest.raises(colloidsim.ColloidsimError, match=named):
        colloidsim.analyse(path, out=tmp_path / "c", **kwargs)
    assert not (tmp_path / "c" / "summary.json").exists()


def test_functions_on_arrays_equal_the_analysis_of_one_frame(trajectory, tmp_path):
    import colloidsim.analysis as ca

    gsd_hoomd = _tool("gsd.hoomd")
    path, wrapped, images = trajectory
    one = colloidsim.analyse(path, out=tmp_path / "one", frames="3", r_max=R_MAX, bins=BINS,
                             centre="com", profile_bins=20)
    r, g = ca.rdf((L, wrapped[3]), r_max=R_MAX, bins=BINS)
    np.testing.assert_array_equal(g, one.gr.g)
    np.testing.assert_array_equal(r, one.gr.r)
    with gsd_hoomd.open(str(path)) as t:
        frame = t[3]
    np.testing.assert_array_equal(ca.rdf(frame, r_max=R_MAX, bins=BINS)[1], one.gr.g)
    q, s = ca.structure_factor(r, g, rho=N / L**3)
    np.testing.assert_allclose(q, one.sq.q, rtol=1e-14)
    np.testing.assert_allclose(s, one.sq.S, rtol=1e-12)
    rp, phi, dens = ca.radial_profile(frame, centre="com", bins=20)
    np.testing.assert_allclose(phi, one.profile.phi, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(dens, one.profile.number_density, rtol=1e-12, atol=1e-15)
    all_frames = colloidsim.analyse(path, out=tmp_path / "all")
    np.testing.assert_allclose(ca.msd(wrapped, images, box=L), all_frames.msd.msd, rtol=1e-12)


def test_contacts_and_clusters_against_a_double_loop():
    import colloidsim.analysis as ca

    rng = np.random.default_rng(3)
    box, n, gap = 6.0, 150, 0.1
    x = rng.uniform(-box / 2, box / 2, (n, 3))
    d = rng.uniform(0.5, 1.0, n)
    bonds = ca.contacts((box, x), gap=gap, diameters=d)
    want = []
    for i in range(n):
        dx = x[i + 1:] - x[i]
        dx -= box * np.round(dx / box)
        h = np.linalg.norm(dx, axis=1) - 0.5 * (d[i] + d[i + 1:])
        want += [(i, i + 1 + j) for j in np.nonzero(h < gap)[0]]
    assert [tuple(b) for b in bonds] == want
    z = ca.coordination(n, bonds)
    assert z.sum() == 2 * len(want)
    labels = ca.cluster_labels(5, [(0, 1), (3, 4)])
    assert list(labels) == [0, 0, 1, 2, 2]


@pytest.mark.parametrize(
    "call, named",
    [
        (lambda ca: ca.rdf((4.0, np.zeros((5, 3))), r_max=3.0), "r_max"),
        (lambda ca: ca.rdf((4.0, np.zeros((5, 2)))), "positions"),
        (lambda ca: ca.rdf(([4.0, 4, 4, 0.1, 0, 0], np.zeros((5, 3)))), "box"),
        (lambda ca: ca.rdf((4.0, np.full((5, 3), np.nan))), "positions"),
        (lambda ca: ca.contacts((4.0, np.zeros((5, 3))), diameters=[1.0] * 4), "diameters"),
        (lambda ca: ca.cluster_labels(3, [(0, 7)]), "bonds"),
        (lambda ca: ca.msd(np.zeros((1, 5, 3))), "positions"),
        (lambda ca: ca.radial_profile((4.0, np.zeros((5, 3))), centre="middle"), "centre"),
        (lambda ca: ca.structure_factor([0.1, 0.2, 0.4], [1.0, 1.0, 1.0], 0.5), "r"),
    ],
)
def test_array_functions_name_bad_arguments(call, named):
    import colloidsim.analysis as ca

    with pytest.raises(colloidsim.ColloidsimError, match=named):
        call(ca)
