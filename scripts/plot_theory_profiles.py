#!/usr/bin/env python3
"""Radial DDFT profiles of several `colloidsim theory` folders of one droplet, one panel per output
time, against r / R(t) (e.g. free draining, RPY with the dilute g, RPY with Trokhymchuk's g).

Usage: plot_theory_profiles.py PICTURE.png FOLDER=LABEL [FOLDER=LABEL ...]

A folder whose solve stopped early (status "unphysical") contributes the profiles it wrote.
R(t)^2 = R0^2 - alpha t / (4 pi).
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
        s = json.load(f)
    p = s["parameters"]
    out = {}
    for frac, t in zip(sorted(p["fractions"]), s["profile_times"]):
        path = os.path.join(folder, f"profile_{frac:.2f}.csv")
        if not os.path.exists(path):
            continue
        radius = math.sqrt(p["r0"] ** 2 - p["alpha"] * t / (4 * math.pi))
        with open(path) as f:
            rows = [(float(r["r"]) / radius, float(r["rho_v"])) for r in csv.DictReader(f)]
        out[frac] = rows
    return s, out


def main():
    picture, specs = sys.argv[1], sys.argv[2:]
    runs = []
    for spec in specs:
        folder, label = spec.split("=", 1)
        s, profiles = load(folder)
        if s.get("status") != "ok":
            label += f" ({s.get('status')})"
        runs.append((label, profiles))
    fracs = sorted({f for _, p in runs for f in p})
    fig, axes = plt.subplots(1, len(fracs), figsize=(3.2 * len(fracs), 3.4), sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, frac in zip(axes, fracs):
        for k, (label, profiles) in enumerate(runs):
            if frac in profiles:
                x, y = zip(*profiles[frac])
                ax.plot(x, y, label=label, color=colours[k % len(colours)])
        ax.set_title(f"{100 * frac:.0f} % of the drying time")
        ax.set_xlabel("r / R(t)")
    axes[0].set_ylabel("phi (bin average)")
    handles = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    axes[0].legend(handles.values(), handles.keys(), fontsize=7)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main()
