#!/usr/bin/env python3
"""The dense, strongly sticky panel of the hard-rods paper's Fig. 6 (sigma = rho = 0.8,
gamma = 10, eps = 0.05, U0 = 6 kT) by BCD from many equilibrated starts.

One BCD run of a few time units sits in one of two states (a bound chain across the barrier of
the potential or not) and does not leave it, while Monte Carlo of the same finite well with
rigid chain moves visits both (docs/data/sticky-fig6/gamma10-dense-mc-starts.md). So each seed
here is one Monte Carlo run of the finite well (crates/bcd/examples/sticky_profile_mc.rs; its
last configuration the start) and one BCD run from it (`colloidsim run
examples/bcd/sticky-rods.toml` with the panel's settings, `initial.placement = "file"`); the
BCD runs together sample the two states with the weights of equilibrium, and their mean
profile, with errors between seeds, is compared with the Monte Carlo runs' (the equilibrium
of the finite well) and with the eps -> 0 theory.

    cargo build --release -p colloidsim-cli && \\
        cargo build --release -p colloidsim-bcd --example sticky_profile_mc
    python3 scripts/sticky_gamma10_mc_starts.py OUT [--seeds 32] [--jobs 2] [--dt 1.25e-6]

Writes OUT/table.md: the density at the barrier (mean of the first and last of 50 bins) and
the peak's deviation from the theory (three bins around its maximum), for Monte Carlo and for
BCD, as mean +- standard error over the seeds, and each seed's barrier density. A seed whose
outputs exist is not run again.
"""
import argparse
import csv
import math
import os
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = os.path.join(HERE, "examples", "bcd", "sticky-rods.toml")
N, L, U0, SIGMA, GAMMA, EPS, BINS = 80, 100, 6, 0.8, 10.0, 0.05, 50


def column(path, name):
    with open(path) as f:
        return [float(r[name]) for r in csv.DictReader(f)]


def one_seed(a, k):
    """Monte Carlo start and BCD run of seed k (both skipped when done)."""
    start = os.path.join(a.out, f"start-{k}.csv")
    mc = os.path.join(a.out, f"mc-{k}.csv")
    if not os.path.exists(mc):
        with open(mc + ".part", "w") as f:
            subprocess.run([a.mc, str(N), str(L), str(U0), str(SIGMA), str(GAMMA), str(EPS),
                            str(int(a.sweeps)), str(k + 100), str(BINS), start],
                           stdout=f, stderr=subprocess.DEVNULL, check=True)
        os.replace(mc + ".part", mc)
    run = os.path.join(a.out, f"bcd-{k}")
    if not os.path.exists(os.path.join(run, "summary.json")):
        subprocess.run([a.bin, "run", SCENARIO, "--out", run, "--force", "--quiet",
                        "--threads", "1", "--seed", str(k),
                        "--set", f"system.diameter={SIGMA}",
                        "--set", f"system.particles={N}",
                        "--set", f"interaction.sticky.gamma={GAMMA}",
                        "--set", f"run.dt={a.dt}",
                        "--set", f"run.equilibrate={a.equilibrate}",
                        "--set", f"run.time={a.time}",
                        "--set", f"observe.density.bins={BINS}",
                        "--set", 'initial.placement="file"',
                        "--set", f'initial.file="{os.path.abspath(start)}"'],
                       check=True)
    return column(mc, "rho"), column(os.path.join(run, "density.csv"), "rho")


def summary(profiles, theory):
    """Barrier density and peak deviation of each profile; their means and standard errors."""
    top = max(range(len(theory)), key=lambda i: theory[i])
    window = [(top + j) % len(theory) for j in (-1, 0, 1)]
    pt = sum(theory[i] for i in window)
    barrier = [0.5 * (p[0] + p[-1]) for p in profiles]
    peak = [sum(p[i] for i in window) / pt - 1.0 for p in profiles]

    def mse(v):
        return statistics.fmean(v), statistics.stdev(v) / math.sqrt(len(v))

    return barrier, mse(barrier), mse(peak)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--bin", default=os.path.join(HERE, "target", "release", "colloidsim"))
    ap.add_argument("--mc", default=os.path.join(HERE, "target", "release", "examples",
                                                 "sticky_profile_mc"))
    ap.add_argument("--seeds", type=int, default=32)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--sweeps", type=float, default=2e6)
    ap.add_argument("--dt", type=float, default=1.25e-6)
    ap.add_argument("--equilibrate", type=float, default=1.0)
    ap.add_argument("--time", type=float, default=5.0)
    a = ap.parse_args()
    for exe in (a.bin, a.mc):
        if not os.access(exe, os.X_OK):
            sys.exit(f"{exe} missing: build it as the docstring says")
    if a.seeds < 2:
        sys.exit("--seeds must be at least 2 (errors are taken between seeds)")
    os.makedirs(a.out, exist_ok=True)
    with ThreadPoolExecutor(a.jobs) as pool:
        results = list(pool.map(lambda k: one_seed(a, k), range(1, a.seeds + 1)))
    theory_dir = os.path.join(a.out, "theory")
    if not os.path.exists(os.path.join(theory_dir, "density.csv")):
        subprocess.run([a.bin, "theory", SCENARIO, "--out", theory_dir, "--force",
                        "--set", f"system.diameter={SIGMA}",
                        "--set", f"system.particles={N}",
                        "--set", f"interaction.sticky.gamma={GAMMA}",
                        "--set", f"observe.density.bins={BINS}"],
                       check=True, stdout=subprocess.DEVNULL)
    theory = column(os.path.join(theory_dir, "density.csv"), "rho")
    mc_b, mc_bar, mc_peak = summary([r[0] for r in results], theory)
    bcd_b, bcd_bar, bcd_peak = summary([r[1] for r in results], theory)
    th_bar = 0.5 * (theory[0] + theory[-1])
    lines = [
        f"Sticky rods, sigma = rho = {SIGMA}, gamma = {GAMMA}, eps = {EPS}, U0 = {U0} kT, "
        f"L = {L}: {a.seeds} seeds, each a Monte Carlo run of the finite well ({a.sweeps:g} "
        f"sweeps) and a BCD run from its last configuration (dt = {a.dt:g}, "
        f"{a.equilibrate:g} + {a.time:g} time units, {BINS} bins); mean +- standard error over "
        f"the seeds.",
        "",
        "| | barrier density | peak against the eps -> 0 theory |",
        "|---|---|---|",
        f"| eps -> 0 theory | {th_bar:.4f} | 0 |",
        f"| Monte Carlo of the finite well | {mc_bar[0]:.4f} +- {mc_bar[1]:.4f} | "
        f"{100 * mc_peak[0]:+.2f} % +- {100 * mc_peak[1]:.2f} % |",
        f"| BCD from the Monte Carlo starts | {bcd_bar[0]:.4f} +- {bcd_bar[1]:.4f} | "
        f"{100 * bcd_peak[0]:+.2f} % +- {100 * bcd_peak[1]:.2f} % |",
        "",
        "BCD minus Monte Carlo: barrier "
        f"{(bcd_bar[0] - mc_bar[0]) / math.hypot(bcd_bar[1], mc_bar[1]):+.1f} combined errors, "
        f"peak {(bcd_peak[0] - mc_peak[0]) / math.hypot(bcd_peak[1], mc_peak[1]):+.1f}.",
        "",
        "Barrier density per seed, BCD: " + ", ".join(f"{b:.4f}" for b in bcd_b),
        "",
        "Barrier density per seed, Monte Carlo: " + ", ".join(f"{b:.4f}" for b in mc_b),
    ]
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
