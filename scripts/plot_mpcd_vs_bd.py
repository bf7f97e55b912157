#!/usr/bin/env python3
"""MPCD with the three solvent boundaries beside BD+RPY at the same fractions of the drying time
(the drying-droplet paper's Fig. 4, scaled down).

Usage: plot_mpcd_vs_bd.py PICTURE.png [--merge K] LABEL=RUN_DIR [LABEL=RUN_DIR ...]

Each RUN_DIR is the output folder of `colloidsim run` on a droplet-mpcd or droplet-bd scenario
with the same N, phi0, Pe and final volume fraction (e.g. examples/droplet/drying-mpcd.toml with
boundary none / slip / no-slip, and its BD+RPY twin); its profile_F.csv files (columns r, phi)
are drawn against r / R(t) with R(t) from summary.json, one panel per fraction. ``--merge K``
joins K neighbouring shells (volume-weighted) first: a single droplet of tens of colloids is
noisy at the bins of its run.
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def columns(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def radius(summary, fraction):
    """R at a fraction of the drying time, from the resolved parameters of either method."""
    p = summary["parameters"]
    t_end = p["t_end"]
    return math.sqrt(max(p["r0"] ** 2 - p["alpha"] * fraction * t_end / (4 * math.pi), 0.0))


def merged(r, phi, k):
    """Shells of equal width joined k at a time, phi weighted by the shell volumes."""
    dr = r[1] - r[0] if len(r) > 1 else 2 * r[0]
    out_r, out_phi = [], []
    for i in range(0, len(r) - k + 1, k):
        lo = [r[j] - dr / 2 for j in range(i, i + k)]
        vol = [(x + dr) ** 3 - x**3 for x in lo]
        out_phi.append(sum(v * p for v, p in zip(vol, phi[i : i + k])) / sum(vol))
        out_r.append((lo[0] + lo[-1] + dr) / 2)
    return out_r, out_phi


def main():
    args = sys.argv[2:]
    merge = 1
    if args and args[0] == "--merge":
        merge, args = int(args[1]), args[2:]
    picture, runs = sys.argv[1], [a.split("=", 1) for a in args]
    fractions = [0.25, 0.5, 0.75, 1.0]
    fig, axes = plt.subplots(1, len(fractions), figsize=(4 * len(fractions), 3.6), sharey=True)
    for label, folder in runs:
        with open(os.path.join(folder, "summary.json")) as f:
            summary = json.load(f)
        for ax, fr in zip(axes, fractions):
            path = os.path.join(folder, f"profile_{fr:.2f}.csv")
            if not os.path.exists(path):
                continue
            c = columns(path)
            r = radius(summary, fr)
            x, phi = merged(c["r"], c["phi"], merge)
            ax.plot([v / r for v in x], phi, label=label, lw=1.4, marker="o", ms=3)
    for ax, fr in zip(axes, fractions):
        ax.set_title(f"t = {fr:.0%} of the drying time")
        ax.set_xlabel("r / R(t)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("volume fraction phi(r)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)


if __name__ == "__main__":
    main()
