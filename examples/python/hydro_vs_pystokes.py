"""Time the free-space RPY product M F of colloidsim.hydro.NBody against pystokes'
(`pystokes.unbounded.Rbm.mobilityTT`) from Python, on the same spheres (non-overlapping, volume
fraction 0.1); the two codes alternate, and each time is the median of the repeats.

    nice python examples/python/hydro_vs_pystokes.py 1000 10000 --repeats 7

docs/python-hydro.md has the table. colloidsim uses every core rayon finds (set
RAYON_NUM_THREADS=1 for one); pystokes runs OpenMP threads (OMP_NUM_THREADS).
"""

import argparse
import math
import time

import numpy as np

from colloidsim.hydro import NBody

try:
    import pystokes
except ImportError:  # the table then has colloidsim's column only
    pystokes = None


def spheres(n, a, phi=0.1, seed=1):
    """n spheres of radius a without overlaps at volume fraction phi (random insertion)."""
    box = (n * 4 / 3 * math.pi * a**3 / phi) ** (1 / 3)
    rng = np.random.default_rng(seed)
    x = np.empty((n, 3))
    cell = {}
    k = 0
    while k < n:
        p = rng.uniform(0, box, 3)
        c = tuple((p // (2 * a)).astype(int))
        near = [
            j
            for dx in (-1, 0, 1)
            for dy in (-1, 0, 1)
            for dz in (-1, 0, 1)
            for j in cell.get((c[0] + dx, c[1] + dy, c[2] + dz), [])
        ]
        if all(np.sum((x[j] - p) ** 2) >= 4 * a * a for j in near):
            x[k] = p
            cell.setdefault(c, []).append(k)
            k += 1
    return x


def median_time(f, repeats):
    f()
    t = []
    for _ in range(repeats):
        s = time.perf_counter()
        f()
        t.append(time.perf_counter() - s)
    return float(np.median(t))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", type=int, nargs="+")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    a, eta = 0.5, 1.0
    print(f"pystokes {getattr(pystokes, '__version__', 'not installed')}")
    print("| N | colloidsim Mdot (median) | pystokes mobilityTT (median) | pystokes / colloidsim | max |dU| / max |U| |")
    print("|---|---|---|---|---|")
    for n in args.n:
        x = spheres(n, a)
        f = np.random.default_rng(2).normal(size=(n, 3))
        s = NBody("open", "open", "open")
        s.initialize(viscosity=eta, hydrodynamicRadius=a)
        s.setPositions(x)
        ours, theirs, diff = [], [], float("nan")
        if pystokes is not None:
            rbm = pystokes.unbounded.Rbm(radius=a, particles=n, viscosity=eta)
            r = np.ascontiguousarray(x.T.ravel())
            ft = np.ascontiguousarray(f.T.ravel())
            v = np.zeros(3 * n)

            def peer():
                v[:] = 0.0
                rbm.mobilityTT(v, r, ft)

        for _ in range(args.rounds):
            ours.append(median_time(lambda: s.Mdot(f), args.repeats))
            if pystokes is not None:
                theirs.append(median_time(peer, args.repeats))
        u = s.Mdot(f)[0]
        if pystokes is not None:
            diff = np.max(np.abs(v.reshape(3, n).T - u)) / np.max(np.abs(u))
        us = " / ".join(f"{t * 1e3:.3g} ms" for t in ours)
        them = " / ".join(f"{t * 1e3:.3g} ms" for t in theirs) or "-"
        ratio = " / ".join(f"{p / q:.2f}" for p, q in zip(theirs, ours)) or "-"
        print(f"| {n} | {us} | {them} | {ratio} | {diff:.1e} |")


if __name__ == "__main__":
    main()
