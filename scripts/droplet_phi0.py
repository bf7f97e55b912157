#!/usr/bin/env python3
"""Free-draining BD beside the radial DDFT for drying droplets at several initial volume
fractions (the drying-droplet paper's Figs. 2b and S1, scaled to examples/droplet/drying-bd.toml):

    python3 scripts/droplet_phi0.py OUT [--bin target/release/colloidsim] [--phi0 0.05,0.1,0.2]

For each phi0 it runs `colloidsim run` and `colloidsim theory` of the example with
`system.phi0` set (into OUT/phi0-<x>/, skipped when already there), then compares the BD and DDFT
profiles on the same bins: per fraction of the drying time, the rms difference over the outer
half of the droplet and chi^2 per bin with the BD bins' counting errors (a bin's centres summed
over the replicas are Poisson, so its standard error is phi / sqrt(counts)). Writes
OUT/phi0-table.md and OUT/phi0-profiles.png. BD starts from random insertion, the DDFT from the
equilibrium at R0 (as the paper's DDFT), so the two differ at the start where the equilibrium is
layered (phi0 >= 0.1) until the drying has renewed the interface layer.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = os.path.join(HERE, "examples", "droplet", "drying-bd.toml")


def read_profile(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [float(r["r"]) for r in rows], [float(r["phi"]) for r in rows]


def run_pair(binary, folder, phi0):
    os.makedirs(folder, exist_ok=True)
    run_dir = os.path.join(folder, "drying-bd")
    if not os.path.exists(os.path.join(run_dir, "summary.json")):
        subprocess.run([binary, "run", SCENARIO, "--quiet", "--set", f"system.phi0={phi0}"],
                       cwd=folder, check=True)
    theory_dir = os.path.join(folder, "drying-bd-theory")
    if not os.path.exists(os.path.join(theory_dir, "summary.json")):
        subprocess.run([binary, "theory", SCENARIO, "--set", f"system.phi0={phi0}"],
                       cwd=folder, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    return run_dir, theory_dir, summary


def compare(run_dir, theory_dir, summary, diameter=1.0):
    p = summary["parameters"]
    replicas = p.get("replicas", 1)
    rows = []
    for frac, step in zip(p["fractions"], p["profile_steps"]):
        name = f"profile_{frac:.2f}.csv"
        r, bd = read_profile(os.path.join(run_dir, name))
        rt, dd = read_profile(os.path.join(theory_dir, name))
        t = step * p["dt"]
        radius = math.sqrt(p["r0"] ** 2 - p["alpha"] * t / (4 * math.pi))
        width = r[1] - r[0]
        outer, chi2, n, peak = [], 0.0, 0, (0.0, 0.0)
        for ri, b, d in zip(r, bd, dd):
            if ri < 0.5 * radius:
                continue
            peak = (max(peak[0], b), max(peak[1], d))
            shell = 4.0 / 3.0 * math.pi * ((ri + width / 2) ** 3 - (ri - width / 2) ** 3)
            counts = b * shell / (math.pi * diameter**3 / 6) * replicas
            outer.append(b - d)
            if counts >= 10:
                err = b / math.sqrt(counts)
                chi2 += ((b - d) / err) ** 2
                n += 1
        rms = math.sqrt(sum(x * x for x in outer) / len(outer))
        rows.append((frac, radius, rms, chi2 / max(n, 1), n) + peak)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--bin", default=os.path.join(HERE, "target", "release", "colloidsim"))
    ap.add_argument("--phi0", default="0.05,0.1,0.2")
    a = ap.parse_args()
    binary = os.path.abspath(a.bin)
    if not os.access(binary, os.X_OK):
        sys.exit(f"no colloidsim binary at {binary}: cargo build --release -p colloidsim-cli")
    values = [float(x) for x in a.phi0.split(",")]
    fig, axes = plt.subplots(1, len(values), figsize=(5 * len(values), 4.2), squeeze=False)
    lines = ["| phi0 | fraction of drying | R / d | rms BD - DDFT, outer half | chi^2 per bin (bins) | peak phi BD / DDFT, outer half |",
             "|---|---|---|---|---|---|"]
    for ax, phi0 in zip(axes[0], values):
        folder = os.path.join(a.out, f"phi0-{phi0}")
        run_dir, theory_dir, summary = run_pair(binary, folder, phi0)
        for frac, radius, rms, chi2, n, pb, pd in compare(run_dir, theory_dir, summary):
            lines.append(f"| {phi0} | {frac:.2f} | {radius:.2f} | {rms:.4f} | {chi2:.2f} ({n}) | {pb:.3f} / {pd:.3f} |")
        p = summary["parameters"]
        for k, frac in enumerate(p["fractions"]):
            name = f"profile_{frac:.2f}.csv"
            colour = f"C{k}"
            r, bd = read_profile(os.path.join(run_dir, name))
            rt, dd = read_profile(os.path.join(theory_dir, name))
            # Leave out the innermost shells, where a bin expects fewer than 10 centres (over the
            # replicas, from the DDFT's phi): one particle there reads as a large phi.
            width = r[1] - r[0]
            keep = [
                i for i, ri in enumerate(r)
                if dd[i] * 4.0 / 3.0 * math.pi * ((ri + width / 2) ** 3 - max(ri - width / 2, 0) ** 3)
                / (math.pi / 6) * p.get("replicas", 1) >= 10
            ]
            ax.plot([r[i] for i in keep], [bd[i] for i in keep], "o", ms=3, color=colour,
                    label=f"BD {100 * frac:.0f}%")
            ax.plot(rt, dd, "-", color=colour, label=f"DDFT {100 * frac:.0f}%")
        ax.set_title(f"phi0 = {phi0}, N = {p.get('particles', '')}")
        ax.set_xlabel("r (d)")
        ax.set_ylabel("phi (centres)")
        ax.set_ylim(bottom=0)
    fig.suptitle("BD (points; bins expecting < 10 centres left out) and DDFT (lines), Pe = 10", fontsize=10)
    axes[0][-1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "phi0-profiles.png"), dpi=110)
    with open(os.path.join(a.out, "phi0-table.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
