#!/usr/bin/env python3
"""The exact equilibrium of the finite-range sticky well that BCD simulates, by Monte Carlo, for
the panels of the hard-rods paper's Fig. 6 (U0 = 6 kT, sigma = rho, p = 3), beside the exact
eps -> 0 (Baxter) theory: how far a profile at eps = 0.05 should lie from the theory, with no
time step involved (docs/figures.md, "All of Fig. 6").

    cargo build --release -p colloidsim-cli && \\
        cargo build --release -p colloidsim-bcd --example sticky_profile_mc
    python3 scripts/sticky_profiles_mc.py OUT [--sweeps 2e6] [--seeds 2] [--jobs 2]

Per panel: two Monte Carlo runs (seeds 1, 2; crates/bcd/examples/sticky_profile_mc.rs, single-rod
and bound-chain moves) and `colloidsim theory` on the same 50 bins; the table gives the peak's
deviation from the theory (three bins around its maximum, as scripts/sticky_profiles_fig6.py),
the density at the barrier (first bin) and chi^2 per bin, errors from the runs' blocks.
Writes OUT/table.md.
"""
import argparse
import math
import os
import subprocess
import sys

from sticky_common import COLLOIDSIM, STICKY_MC, peak, rods, table, theory

PANELS = [(s, g, 0.05) for s in (0.2, 0.5, 0.8) for g in (0.1, 1.0, 10.0)] + [
    (0.8, g, e) for e in (0.025, 0.0125) for g in (0.1, 1.0, 10.0)
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--bin", default=COLLOIDSIM)
    ap.add_argument("--mc", default=STICKY_MC)
    ap.add_argument("--sweeps", type=float, default=2e6)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    for exe in (a.bin, a.mc):
        if not os.access(exe, os.X_OK):
            sys.exit(f"{exe} missing: build it as the docstring says")
    os.makedirs(a.out, exist_ok=True)
    jobs = []
    for sigma, gamma, eps in PANELS:
        n = rods(sigma)
        for seed in range(1, a.seeds + 1):
            path = os.path.join(a.out, f"mc-{sigma}-{gamma}-{eps}-{seed}.csv")
            if not os.path.exists(path):
                jobs.append(([a.mc, str(n), "100", "6", str(sigma), str(gamma), str(eps),
                              str(int(a.sweeps)), str(seed), "50"], path))
    running = []
    for cmd, path in jobs:
        while len(running) >= a.jobs:
            p, f, dst = running.pop(0)
            if p.wait() != 0:
                sys.exit("a Monte Carlo run failed")
            f.close()
            os.replace(dst + ".part", dst)
        print(" ".join(cmd), flush=True)
        f = open(path + ".part", "w")
        running.append((subprocess.Popen(cmd, stdout=f), f, path))
    for p, f, dst in running:
        if p.wait() != 0:
            sys.exit("a Monte Carlo run failed")
        f.close()
        os.replace(dst + ".part", dst)
    lines = [
        f"Monte Carlo of the finite-range sticky well (p = 3) in U0 = 6 kT, L = 100, sigma = rho, "
        f"{a.seeds} runs of {a.sweeps:g} sweeps per panel, 50 bins; deviations from the exact "
        f"eps -> 0 theory; errors from 20 blocks per run.",
        "",
        "| sigma = rho | eps | gamma | peak deviation | rho at the barrier (MC / theory) | chi^2 per bin |",
        "|---|---|---|---|---|---|",
    ]
    for sigma, gamma, eps in PANELS:
        th = theory(a.bin, os.path.join(a.out, f"theory-{sigma}-{gamma}"), sigma, gamma)
        runs = [table(os.path.join(a.out, f"mc-{sigma}-{gamma}-{eps}-{s}.csv"))
                for s in range(1, a.seeds + 1)]
        k = len(runs)
        rho = [sum(r["rho"][b] for r in runs) / k for b in range(len(th))]
        err = [math.sqrt(sum(r["err"][b] ** 2 for r in runs)) / k for b in range(len(th))]
        dev, dev_err = peak(rho, th, err)
        chi2 = sum(((r - t) / e) ** 2 for r, t, e in zip(rho, th, err) if e > 0) / len(th)
        lines.append(
            f"| {sigma} | {eps} | {gamma} | {100 * dev:+.2f} % +- {100 * dev_err:.2f} % | "
            f"{rho[0]:.4f} +- {err[0]:.4f} / {th[0]:.4f} | {chi2:.1f} |"
        )
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
