#!/usr/bin/env python3
"""Time-step error of free-draining BD in the static droplet, Euler against Leimkuhler-Matthews.

Usage: plot_droplet_dt_errors.py docs/data/droplet-dt-errors.csv PICTURE.png [U0]

The relative error of the WCA pair energy per particle against its dt -> 0 value U0 (default
0.22088 kT, the common intercept of the sweep in docs/validation.md), with one standard error, on
log axes; points whose error is below two standard errors are drawn hollow.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    path, picture = sys.argv[1], sys.argv[2]
    u0 = float(sys.argv[3]) if len(sys.argv) > 3 else 0.22088
    rows = list(csv.DictReader(open(path)))
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for name, marker in [("euler", "o"), ("lm", "s")]:
        pts = sorted((float(r["dt"]), float(r["u_pair"]), float(r["se_u_pair"])) for r in rows if r["integrator"] == name)
        dt = [p[0] for p in pts]
        err = [abs(p[1] - u0) / u0 for p in pts]
        se = [p[2] / u0 for p in pts]
        ax.errorbar(dt, err, yerr=se, fmt=marker + "-", capsize=2,
                    label={"euler": "Euler-Maruyama", "lm": "Leimkuhler-Matthews"}[name])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(1e-4, 0.1)
    ax.axhline(0.01, color="0.7", ls=":", lw=0.8)
    ax.set_xlabel("dt (d^2 / D0)")
    ax.set_ylabel("|relative error| of the pair energy")
    ax.set_title("Static droplet, R0 = 6 d, phi = 0.25")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main()
