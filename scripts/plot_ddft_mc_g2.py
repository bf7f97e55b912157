#!/usr/bin/env python3
"""Pictures of the RPY DDFT with the Monte Carlo g2 (crates/mc/examples/ddft_mc_g2.rs output
folders; docs/theory-droplet.md, "The Monte Carlo g2 in the flux").

Usage:
  plot_ddft_mc_g2.py profiles PICTURE.png DIR=LABEL [DIR=LABEL ...]
      volume-fraction profiles against r / R(t) at 25/50/75/100 % of the drying time
      (a run that stopped early contributes the profiles it wrote)
  plot_ddft_mc_g2.py pairs PICTURE.png DIR STAGE
      h = g2 - 1 of pairs in one radial bin against their distance s: the Monte Carlo
      measurement against Eq. 17 (Trokhymchuk's g at the mean packing fraction), in the
      densest bin near the interface and in a bin a third of the way out
  plot_ddft_mc_g2.py bd PICTURE.png DIR=LABEL [DIR=LABEL ...]
      fractions of the particles beyond 0.7 R(t) and 0.85 R(t) against the drying time, with
      the BD+RPY droplet of docs/theory-droplet.md (N = 1000, one droplet, binomial errors)
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# BD+RPY, examples/droplet/drying-rpy.toml (docs/theory-droplet.md, "Against BD+RPY").
BD = {
    0.7: [(0.25, 0.751, 0.014), (0.5, 0.832, 0.012), (0.75, 0.881, 0.010), (1.0, 0.830, 0.012)],
    0.85: [(0.25, 0.455, 0.016), (0.5, 0.589, 0.016), (0.75, 0.708, 0.014), (1.0, 0.607, 0.015)],
}


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def specs(args):
    out = []
    for a in args:
        d, _, label = a.partition("=")
        out.append((d, label or os.path.basename(d)))
    return out


def profiles(picture, args):
    fracs = [0.25, 0.5, 0.75, 1.0]
    fig, axes = plt.subplots(1, 4, figsize=(15, 3.8), sharey=True)
    for d, label in specs(args):
        for ax, f in zip(axes, fracs):
            p = os.path.join(d, f"profile_{f:.2f}.csv")
            if not os.path.exists(p):
                continue
            r = rows(p)
            ax.plot([float(x["r_over_R"]) for x in r], [float(x["phi"]) for x in r], label=label)
    for ax, f in zip(axes, fracs):
        ax.set_title(f"{100 * f:.0f} % of the drying time")
        ax.set_xlabel("r / R(t)")
    axes[0].set_ylabel("volume fraction")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)


def pairs(picture, d, stage):
    r = rows(os.path.join(d, f"g2_stage{stage}.csv"))
    by_r = {}
    for x in r:
        by_r.setdefault(float(x["r"]), []).append(x)
    # Densest bin (largest contact h of Eq. 17 is not a density; use the expected pair count).
    def weight(rr):
        return sum(float(x["expected"]) for x in by_r[rr])

    outer = max(by_r, key=weight)
    inner = min(by_r, key=lambda rr: abs(rr - outer / 3))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for ax, rr in zip(axes, [inner, outer]):
        xs = [x for x in by_r[rr] if float(x["s"]) > 1.0]
        s = [float(x["s"]) for x in xs]
        ax.plot(s, [float(x["h_eq17"]) + 1 for x in xs], "-", label="Eq. 17 (Trokhymchuk g)")
        m = [(float(x["s"]), float(x["h_mc"]) + 1) for x in xs if x["h_mc"]]
        ax.plot([a for a, _ in m], [b for _, b in m], "o", ms=3, label="Monte Carlo")
        ax.axhline(1, color="grey", lw=0.5)
        ax.set_title(f"pairs with r1, r2 in the bin at r = {rr:.2f} d")
        ax.set_xlabel("s / d")
    axes[0].set_ylabel("g2(r, r, s)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)


def bd(picture, args):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, c in zip(axes, [0.7, 0.85]):
        pts = BD[c]
        ax.errorbar([p[0] for p in pts], [p[1] for p in pts], yerr=[p[2] for p in pts], fmt="ko",
                    label="BD+RPY (one droplet)")
        for d, label in specs(args):
            r = rows(os.path.join(d, "fractions.csv"))
            ax.plot([float(x["fraction"]) for x in r], [float(x[f"beyond_{c}R"]) for x in r],
                    label=label)
        ax.set_title(f"particles beyond {c} R(t)")
        ax.set_xlabel("fraction of the drying time")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)


def main():
    kind, picture = sys.argv[1], sys.argv[2]
    if kind == "profiles":
        profiles(picture, sys.argv[3:])
    elif kind == "pairs":
        pairs(picture, sys.argv[3], sys.argv[4])
    elif kind == "bd":
        bd(picture, sys.argv[3:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
