#!/usr/bin/env python3
"""The time-step error of BCD's sticky contact in the hard-rods paper's Fig. 6: the peak of the
density profile against dt, beside the exact equilibrium of the finite well (Monte Carlo, drawn
at dt = 0) and the eps -> 0 theory (zero).

    python3 scripts/plot_sticky_dt.py PICTURE.png "TITLE=OUT" ["TITLE=OUT" ...]

Each OUT is a folder of scripts/sticky_mc_starts.py (its peaks.csv); one panel each, with the
BCD points against sqrt(dt), where BCD's error is a straight line (weighted least squares, drawn
to dt = 0; docs/figures.md), and the straight line in dt for comparison.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def line(xs, ys, es):
    """Weighted least-squares intercept and slope."""
    w = [1 / e ** 2 for e in es]
    sw = sum(w)
    mx = sum(wi * x for wi, x in zip(w, xs)) / sw
    my = sum(wi * y for wi, y in zip(w, ys)) / sw
    b = sum(wi * (x - mx) * (y - my) for wi, x, y in zip(w, xs, ys)) / sum(
        wi * (x - mx) ** 2 for wi, x in zip(w, xs))
    return my - b * mx, b


def main():
    if len(sys.argv) < 3 or any("=" not in a for a in sys.argv[2:]):
        sys.exit(__doc__)
    picture, panels = sys.argv[1], [a.rsplit("=", 1) for a in sys.argv[2:]]
    fig, axes = plt.subplots(1, len(panels), figsize=(4 * len(panels), 3.6), squeeze=False)
    for ax, (title, out) in zip(axes[0], panels):
        rows = list(csv.DictReader(open(os.path.join(out, "peaks.csv"))))
        mc = next(r for r in rows if float(r["dt"]) == 0)
        bcd = sorted((float(r["dt"]) * 1e6, 100 * float(r["peak"]), 100 * float(r["peak_err"]))
                     for r in rows if float(r["dt"]) > 0)
        dts, ys, es = zip(*bcd)
        xs = [d ** 0.5 for d in dts]
        ax.errorbar(xs, ys, yerr=es, fmt="o", capsize=2, label="BCD")
        if len(xs) >= 2:
            a, b = line(xs, ys, es)
            ax.plot([0, max(xs)], [a, a + b * max(xs)], "C0--", lw=0.8, label="line in sqrt(dt)")
            a, b = line(dts, ys, es)
            grid = [max(xs) * k / 50 for k in range(51)]
            ax.plot(grid, [a + b * x * x for x in grid], "C2:", lw=0.8, label="line in dt")
        m, e = 100 * float(mc["peak"]), 100 * float(mc["peak_err"])
        ax.errorbar([0], [m], yerr=[e], fmt="s", color="C3", capsize=2,
                    label="finite well (Monte Carlo)")
        ax.axhline(0, color="0.5", lw=0.8, ls=":", label="eps -> 0 theory")
        ax.set_xlim(left=-0.1)
        ax.set_xlabel("sqrt(dt / (1e-6 sigma^2 / D))")
        ax.set_ylabel("peak against the theory (%)")
        ax.set_title(title, fontsize=10)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)


if __name__ == "__main__":
    main()
