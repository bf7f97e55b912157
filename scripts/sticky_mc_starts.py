#!/usr/bin/env python3
"""A panel of the hard-rods paper's Fig. 6 (sticky rods, sigma = rho, U0 = 6 kT, p = 3, L = 100)
by BCD from equilibrated starts, at one or several time steps, against the exact equilibrium of
the finite well BCD simulates and the eps -> 0 theory.

BCD runs from random starts can stay out of equilibrium for longer than a run: at gamma = 10 a
dense run sits in one of two states (a bound chain across the barrier of the potential or not),
and at sigma = rho = 0.2 the number of bound pairs per well changes only by Kramers hops
(docs/figures.md). Monte Carlo of the same finite well with rigid chain moves
(crates/bcd/examples/sticky_profile_mc.rs) visits those states quickly. So each seed here is one
Monte Carlo run (its last configuration the start, its profile the exact equilibrium) and one
BCD run from that start at each time step (`colloidsim run examples/bcd/sticky-rods.toml` with
the panel's settings, `initial.placement = "file"`). The seeds together sample the slow states
with the weights of equilibrium; the runs of one seed at different steps share the start, so the
dependence on the step is measured seed by seed (paired), and its extrapolation to dt = 0 (a
straight line in dt, one in sqrt(dt), and with four or more steps a quadratic in sqrt(dt)) is
fitted per seed and averaged over the seeds.

    cargo build --release -p colloidsim-cli && \\
        cargo build --release -p colloidsim-bcd --example sticky_profile_mc
    python3 scripts/sticky_mc_starts.py OUT [--sigma 0.8] [--gamma 10] [--dts 1.25e-6]
        [--seeds 32] [--jobs 2] [--equilibrate 1] [--time 5]

Writes OUT/table.md: for Monte Carlo and for BCD at each step the density at the barrier (mean
of the first and last bin), the peak's deviation from the theory (three bins around its
maximum) and chi^2 per bin against Monte Carlo, as mean +- standard error over the seeds; with
two or more steps the extrapolations to dt = 0. Runs whose outputs exist are not run again.
"""
import argparse
import math
import os
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

from sticky_common import COLLOIDSIM, L, SCENARIO, STICKY_MC, U0, peak, rods, table, theory


def monte_carlo(a, k):
    """Seed k's Monte Carlo profile and last configuration (skipped when done)."""
    start = os.path.join(a.out, f"start-{k}.csv")
    mc = os.path.join(a.out, f"mc-{k}.csv")
    if not os.path.exists(mc):
        with open(mc + ".part", "w") as f:
            subprocess.run([a.mc, str(rods(a.sigma)), str(L), str(U0), str(a.sigma), str(a.gamma),
                            str(a.eps), str(int(a.sweeps)), str(k + 100), str(a.bins), start],
                           stdout=f, stderr=subprocess.DEVNULL, check=True)
        os.replace(mc + ".part", mc)
    return table(mc)["rho"]


def bcd(a, dt, k):
    """Seed k's BCD profile at step dt from the Monte Carlo start (skipped when done)."""
    run = os.path.join(a.out, f"bcd-dt{dt:g}-{k}")
    if not os.path.exists(os.path.join(run, "summary.json")):
        start = os.path.abspath(os.path.join(a.out, f"start-{k}.csv"))
        subprocess.run([a.bin, "run", SCENARIO, "--out", run, "--force", "--quiet",
                        "--threads", "1", "--seed", str(k),
                        "--set", f"system.diameter={a.sigma}",
                        "--set", f"system.particles={rods(a.sigma)}",
                        "--set", f"interaction.sticky.gamma={a.gamma}",
                        "--set", f"interaction.sticky.range={a.eps}",
                        "--set", f"run.dt={dt}",
                        "--set", f"run.equilibrate={a.equilibrate}",
                        "--set", f"run.time={a.time}",
                        "--set", f"observe.density.bins={a.bins}",
                        "--set", 'initial.placement="file"',
                        "--set", f'initial.file="{start}"'],
                       check=True)
    return table(os.path.join(run, "density.csv"))["rho"]


def mse(v):
    return statistics.fmean(v), statistics.stdev(v) / math.sqrt(len(v))


def fit(xs, ys, degree):
    """Least-squares coefficients `c` of y = c0 + c1 x + ... + c_degree x^degree (normal
    equations, solved by Gaussian elimination; degree + 1 <= len(xs))."""
    m = degree + 1
    a = [[sum(x ** (i + j) for x in xs) for j in range(m)]
         + [sum(y * x ** i for x, y in zip(xs, ys))] for i in range(m)]
    for c in range(m):
        piv = max(range(c, m), key=lambda r: abs(a[r][c]))
        a[c], a[piv] = a[piv], a[c]
        for r in range(m):
            if r != c:
                f = a[r][c] / a[c][c]
                a[r] = [v - f * w for v, w in zip(a[r], a[c])]
    return [a[i][m] / a[i][i] for i in range(m)]


class Panel:
    """The observables of one set of profiles (one per seed) against the theory."""

    def __init__(self, profiles, th):
        self.profiles = profiles
        self.barrier = [0.5 * (p[0] + p[-1]) for p in profiles]
        self.peak = [peak(p, th) for p in profiles]

    def mean_profile(self):
        """Per-bin mean and standard error over the seeds."""
        cols = list(zip(*self.profiles))
        return [mse(c) for c in cols]


def chi2_per_bin(p, q):
    return statistics.fmean((a[0] - b[0]) ** 2 / (a[1] ** 2 + b[1] ** 2)
                            for a, b in zip(p.mean_profile(), q.mean_profile()))


def pct(m):
    return f"{100 * m[0]:+.2f} % +- {100 * m[1]:.2f} %"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--bin", default=COLLOIDSIM)
    ap.add_argument("--mc", default=STICKY_MC)
    ap.add_argument("--sigma", type=float, default=0.8, help="rod length = mean density")
    ap.add_argument("--gamma", type=float, default=10.0, help="stickiness (Baxter)")
    ap.add_argument("--eps", type=float, default=0.05, help="width of the well")
    ap.add_argument("--dts", default="1.25e-6", help="time steps, comma separated")
    ap.add_argument("--seeds", type=int, default=32)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--sweeps", type=float, default=2e6, help="Monte Carlo sweeps per seed")
    ap.add_argument("--equilibrate", type=float, default=1.0, help="BCD time before sampling")
    ap.add_argument("--time", type=float, default=5.0, help="BCD time sampled")
    ap.add_argument("--bins", type=int, default=50)
    a = ap.parse_args()
    for exe in (a.bin, a.mc):
        if not os.access(exe, os.X_OK):
            sys.exit(f"{exe} missing: build it as the docstring says")
    if a.seeds < 2:
        sys.exit("--seeds must be at least 2 (errors are taken between seeds)")
    if not 0 < a.sigma < 1:
        sys.exit(f"--sigma must lie in (0, 1) (rods of length sigma at density sigma), got {a.sigma}")
    try:
        dts = sorted({float(x) for x in a.dts.split(",")}, reverse=True)
    except ValueError:
        sys.exit(f"--dts must be numbers separated by commas, got {a.dts!r}")
    if not dts or min(dts) <= 0:
        sys.exit(f"--dts must be positive, got {a.dts!r}")
    seeds = range(1, a.seeds + 1)
    os.makedirs(a.out, exist_ok=True)
    with ThreadPoolExecutor(a.jobs) as pool:
        mc = list(pool.map(lambda k: monte_carlo(a, k), seeds))
        runs = {dt: pool.map(lambda k, dt=dt: bcd(a, dt, k), seeds) for dt in dts}
        runs = {dt: list(r) for dt, r in runs.items()}
    th = theory(a.bin, os.path.join(a.out, "theory"), a.sigma, a.gamma, a.bins)
    mcp = Panel(mc, th)
    panels = {dt: Panel(runs[dt], th) for dt in dts}
    th_bar = 0.5 * (th[0] + th[-1])
    mb, mp = mse(mcp.barrier), mse(mcp.peak)
    lines = [
        f"Sticky rods, sigma = rho = {a.sigma}, gamma = {a.gamma}, eps = {a.eps}, U0 = {U0} kT, "
        f"L = {L} ({rods(a.sigma)} rods): {a.seeds} seeds, each a Monte Carlo run of the finite well "
        f"({a.sweeps:g} sweeps) and BCD runs from its last configuration ({a.equilibrate:g} + "
        f"{a.time:g} time units, {a.bins} bins); mean +- standard error over the seeds. The "
        f"theory is the eps -> 0 limit.",
        "",
        "| | barrier density | peak against the theory | BCD - MC (peak, errors) "
        "| chi^2 per bin against MC |",
        "|---|---|---|---|---|",
        f"| eps -> 0 theory | {th_bar:.4f} | 0 | | |",
        f"| Monte Carlo of the finite well | {mb[0]:.4f} +- {mb[1]:.4f} | {pct(mp)} | | |",
    ]
    for dt in dts:
        p = panels[dt]
        bb, bp = mse(p.barrier), mse(p.peak)
        lines.append(
            f"| BCD, dt = {dt:g} | {bb[0]:.4f} +- {bb[1]:.4f} | {pct(bp)} | "
            f"{(bp[0] - mp[0]) / math.hypot(bp[1], mp[1]):+.1f} | {chi2_per_bin(p, mcp):.2f} |")
    if len(dts) >= 2:
        lines += ["", "Extrapolation of the peak to dt = 0, fitted seed by seed through all "
                  "steps and averaged over the seeds; the residual at each step in standard "
                  "errors over the seeds:", "",
                  "| model | peak at dt = 0 | minus MC (errors) | residuals |", "|---|---|---|---|"]
        models = [("linear in dt", lambda x: x, 1), ("linear in sqrt(dt)", math.sqrt, 1)]
        if len(dts) >= 4:  # with three steps it would pass through every point
            models.append(("quadratic in sqrt(dt)", math.sqrt, 2))
        for name, f, degree in models:
            xs = [f(dt) for dt in dts]
            fits = [fit(xs, [panels[dt].peak[i] for dt in dts], degree) for i in range(a.seeds)]
            a0 = mse([c[0] for c in fits])
            res = [mse([panels[dt].peak[i] - sum(ck * x ** k for k, ck in enumerate(fits[i]))
                        for i in range(a.seeds)]) for dt, x in zip(dts, xs)]
            lines.append(
                f"| {name} | {pct(a0)} | {(a0[0] - mp[0]) / math.hypot(a0[1], mp[1]):+.1f} | "
                + ", ".join(f"{r[0] / r[1]:+.1f}" if r[1] > 0 else "0" for r in res) + " |")
    lines += ["", "Barrier density per seed, Monte Carlo: "
              + ", ".join(f"{b:.4f}" for b in mcp.barrier)]
    for dt in dts:
        lines += ["", f"Barrier density per seed, BCD at dt = {dt:g}: "
                  + ", ".join(f"{b:.4f}" for b in panels[dt].barrier)]
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text)
    # For plots: dt = 0 is the Monte Carlo of the finite well.
    with open(os.path.join(a.out, "peaks.csv"), "w") as f:
        f.write("dt,peak,peak_err,barrier,barrier_err\n")
        for dt, p in [(0.0, mcp)] + [(dt, panels[dt]) for dt in dts]:
            (pm, pe), (bm, be) = mse(p.peak), mse(p.barrier)
            f.write(f"{dt:g},{pm:.6g},{pe:.3g},{bm:.6g},{be:.3g}\n")
    print(text)


if __name__ == "__main__":
    main()
