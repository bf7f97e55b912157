#!/usr/bin/env python3
"""Free draining against RPY: the radial profiles of two droplet-bd runs at the same fractions of
the drying time in one picture (the paper's Fig. 3a), and the mean volume fraction of the outer
shells and of the centre at the end.

Usage: compare-profiles.py FREE_DRAINING_OUT RPY_OUT PICTURE.png

Both folders are `colloidsim run` outputs of the same droplet (same N, phi0, Pe, final phi and
time step); the profiles are plotted against r / R(t), R(t)^2 = R0^2 - alpha t / (4 pi).
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        p = json.load(f)["parameters"]
    out = []
    for frac, step in zip(p["fractions"], p["profile_steps"]):
        t = step * p["dt"]
        radius = math.sqrt(p["r0"] ** 2 - p["alpha"] * t / (4 * math.pi))
        with open(os.path.join(folder, f"profile_{frac:.2f}.csv")) as f:
            rows = [(float(r["r"]), float(r["rho_v"])) for r in csv.DictReader(f)]
        out.append((frac, t, radius, rows))
    return p, out


def shell_mean(rows, radius, lo, hi):
    """Volume-weighted mean phi of the bins with lo <= r / R < hi."""
    num = den = 0.0
    dr = rows[1][0] - rows[0][0]
    for r, phi in rows:
        if lo <= r / radius < hi:
            v = (r + dr / 2) ** 3 - (r - dr / 2) ** 3
            num += phi * v
            den += v
    return num / den if den else float("nan")


def main():
    fd_dir, rpy_dir, picture = sys.argv[1:4]
    pf, fd = load(fd_dir)
    pr, rpy = load(rpy_dir)
    for k in ("particles", "phi0", "peclet", "dt", "r0", "alpha", "steps"):
        if pf[k] != pr[k]:
            sys.exit(f"the runs differ in {k}: {pf[k]} vs {pr[k]}")
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, ((frac, t, radius, a), (_, _, _, b)) in enumerate(zip(fd, rpy)):
        c = f"C{i}"
        ax.plot([r / radius for r, _ in a], [x for _, x in a], "--", color=c, lw=1.2)
        ax.plot([r / radius for r, _ in b], [x for _, x in b], "-", color=c, lw=1.6,
                label=f"t = {t:.1f} ({frac:.0%})")
    ax.plot([], [], "k--", label=f"free draining ({pf['replicas']} droplets)")
    ax.plot([], [], "k-", label=f"RPY ({pr['replicas']} droplet(s))")
    ax.set_xlim(0, 1.1)
    ax.set_ylim(0, 1.0)
    ax.set_xlabel("r / R(t)")
    ax.set_ylabel("volume fraction phi(r)")
    ax.set_title(f"Drying droplet, N = {pf['particles']}, Pe = {pf['peclet']:g}: "
                 "free draining (dashed) vs RPY (solid)", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print("fraction  t  R  | phi(r/R < 0.5)  FD  RPY | phi(0.8 <= r/R < 1.05)  FD  RPY")
    for (frac, t, radius, a), (_, _, _, b) in zip(fd, rpy):
        print(f"{frac:.2f} {t:.2f} {radius:.3f} | {shell_mean(a, radius, 0, 0.5):.4f} "
              f"{shell_mean(b, radius, 0, 0.5):.4f} | {shell_mean(a, radius, 0.8, 1.05):.4f} "
              f"{shell_mean(b, radius, 0.8, 1.05):.4f}")


if __name__ == "__main__":
    main()
