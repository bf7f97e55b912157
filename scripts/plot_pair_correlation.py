#!/usr/bin/env python3
"""The pair correlation of the RPY DDFT and what it does to the bulk sedimentation coefficient.

Usage: plot_pair_correlation.py DATA_DIR PICTURE.png

DATA_DIR holds g_r.csv and sedimentation.csv written by
`cargo run --release -p colloidsim-dft --example pair_table -- DATA_DIR`.
Left: Trokhymchuk et al.'s g(r) at several packing fractions (the fits cover eta <= 0.471;
0.55 is extrapolated). Right: K(phi) of the radial RPY flux with the dilute g (1 - 5 phi) and
with Trokhymchuk's g (1 - 5 phi + 12 phi int_1^8 x h dx).
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from tables import columns  # noqa: E402  (scripts/tables.py)


def main():
    data, picture = sys.argv[1], sys.argv[2]
    g = columns(os.path.join(data, "g_r.csv"))
    k = columns(os.path.join(data, "sedimentation.csv"))
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for name in g:
        if name == "x":
            continue
        eta = float(name[2:])
        style = "--" if eta > 0.4712 else "-"
        a.plot(g["x"], g[name], style, label=f"eta = {eta}" + (" (extrapolated)" if style == "--" else ""))
    a.set_xlabel("r / d")
    a.set_ylabel("g(r)")
    a.set_title("Trokhymchuk et al. (2005) hard-sphere g(r)")
    a.axhline(1.0, color="0.7", lw=0.8)
    a.legend(fontsize=8)
    b.plot(k["phi"], k["k_dilute"], label="dilute g = step: 1 - 5 phi")
    b.plot(k["phi"], k["k_trokhymchuk"], label="Trokhymchuk g")
    b.axhline(0.0, color="0.5", lw=0.8)
    b.axvline(0.4712, color="0.7", ls=":", lw=0.8)
    b.set_xlabel("phi")
    b.set_ylabel("K = sedimentation velocity / single-sphere velocity")
    b.set_title("Bulk sedimentation with the radial RPY flux")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main()
