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

It also prints, per run and fraction, the fraction of the colloids beyond the bin edge nearest
0.8 R(t) (one minus the centres counted inside it, so that centres beyond R count as outer), with
its binomial standard error over N x replicas colloids, and each run's difference from the first
(a single droplet's colloids are correlated; the binomial error is a guide, not a bound).
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from tables import columns  # noqa: E402  (scripts/tables.py)


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


def outer_fraction(c, summary, fr, cut=0.8):
    """(edge / R, fraction of the colloids beyond the edge, binomial standard error)."""
    p = summary["parameters"]
    n, reps, d = p["particles"], p.get("replicas", 1), p["diameter"]
    vp = math.pi * d**3 / 6
    r = c["r"]
    dr = r[1] - r[0] if len(r) > 1 else 2 * r[0]
    big_r = radius(summary, fr)
    k = round(cut * len(r))
    inside = sum(
        c["rho_v"][j] * 4 * math.pi / 3 * ((r[j] + dr / 2) ** 3 - (r[j] - dr / 2) ** 3) / vp
        for j in range(k)
    )
    q = 1 - inside / n
    return (r[k - 1] + dr / 2) / big_r, q, math.sqrt(max(q * (1 - q), 0) / (n * reps))


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
            x, phi = merged(c["r"], c["rho_v"], merge)
            ax.plot([v / r for v in x], phi, label=label, lw=1.4, marker="o", ms=3)
    for ax, fr in zip(axes, fractions):
        ax.set_title(f"t = {fr:.0%} of the drying time")
        ax.set_xlabel("r / R(t)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("volume fraction phi(r)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    rows = {}
    for label, folder in runs:
        with open(os.path.join(folder, "summary.json")) as f:
            summary = json.load(f)
        for fr in fractions:
            path = os.path.join(folder, f"profile_{fr:.2f}.csv")
            if os.path.exists(path):
                rows.setdefault(label, {})[fr] = outer_fraction(columns(path), summary, fr)
    first = runs[0][0]
    print("| run | " + " | ".join(f"{fr:.0%}" for fr in fractions) + " |")
    print("|---" * (len(fractions) + 1) + "|")
    for label, _ in runs:
        cells = []
        for fr in fractions:
            if fr not in rows.get(label, {}):
                cells.append("")
                continue
            edge, q, e = rows[label][fr]
            cell = f"{q:.3f} ± {e:.3f}"
            if label != first and fr in rows.get(first, {}):
                _, q0, e0 = rows[first][fr]
                z = (q - q0) / math.hypot(e, e0) if e or e0 else 0.0
                cell += f" ({z:+.1f})"
            cells.append(cell)
        print(f"| {label} | " + " | ".join(cells) + " |")
    edges = sorted({round(v[0], 3) for r in rows.values() for v in r.values()})
    print(f"(fraction of the colloids beyond {edges} R(t); in brackets the difference from "
          f"{first} in combined binomial errors)")


if __name__ == "__main__":
    main()
