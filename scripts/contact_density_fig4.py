#!/usr/bin/env python3
"""The hard-rods paper's Fig. 4: the two-particle density at contact of hard rods in the cosine
potential (U0 = 6 kT), sigma = 0.2, 0.5, 0.8 (columns) at mean densities 0.2, 0.5, 0.8 (rows),
BCD beside the exact theory.

Every panel is a set of replicas of examples/bcd/contact-density.toml (seeds 1, 2, ..., with
system.particles = 20, 50, 80 on the ring of L = 100); the errors are standard errors between
replicas (the block errors of one run underestimate those of a contact density: docs/bcd.md,
"Contact density in a potential"). The 6 kT barriers make the wells' occupation relax slowly (a
rod leaves a doubly occupied well about once in 70 time units, a Kramers estimate), so each
replica is first relaxed for --pre time units at dt = 1e-4 (cheap), and its final configuration
starts the run at --dt, which relaxes --equilibrate more before sampling.

What BCD's window estimator (Eq. 27, a window w beyond contact) should read is

    (N - 1)/N [rho2_window + (delta / w) rho2]

with `rho2_window` the exact grand-canonical window average and `rho2` Eq. 24 (both in
contact_density_theory.csv), `(N - 1)/N` the canonical ring's factor (exact for the Tonks gas)
and `delta = 0.5826 sqrt(4 D dt)` the time-step boundary layer at contact (docs/bcd.md,
"Time-step error"). The table gives, per panel, chi^2 per bin against that, the pooled ratio
(sum over the bins) with its error, and the same for Eq. 24 alone.

    python3 scripts/contact_density_fig4.py OUT [--bin target/release/colloidsim]
        [--jobs 2] [--replicas 6] [--pre 400] [--time 100] [--equilibrate 10] [--dt 2e-6]
        [--window 0.02] [--only SIGMA,N]

Writes OUT/sigma-<s>-n-<n>/{pre,run}-<k>/ (the runs), OUT/table.md and OUT/fig4.png.
"""
import argparse
import csv
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = os.path.join(HERE, "examples", "bcd", "contact-density.toml")
SIGMAS = [0.2, 0.5, 0.8]
PARTICLES = [20, 50, 80]
LENGTH = 100.0
SIEGMUND = 0.5825971579390107


def table(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def compare(folders, n, dt, w):
    """The replicas' mean contact density with its standard error, against the expectation."""
    runs = [table(os.path.join(f, "contact_density.csv"))["rho2"] for f in folders]
    th = table(os.path.join(folders[0], "contact_density_theory.csv"))
    k = len(runs)
    mean = [sum(r[b] for r in runs) / k for b in range(len(th["x"]))]
    err = [
        math.sqrt(sum((r[b] - mean[b]) ** 2 for r in runs) / (k - 1) / k)
        for b in range(len(mean))
    ]
    delta = SIEGMUND * math.sqrt(4.0 * dt)
    canonical = (n - 1) / n
    expected = [canonical * (a + delta / w * c) for a, c in zip(th["rho2_window"], th["rho2"])]
    z = [(m - t) / e for m, t, e in zip(mean, expected, err) if e > 0]
    sums = [sum(r) for r in runs]
    pooled = sum(sums) / k
    pooled_err = math.sqrt(sum((x - pooled) ** 2 for x in sums) / (k - 1) / k)
    return {
        "chi2": sum(v * v for v in z) / len(z),
        "worst": max(abs(v) for v in z),
        "ratio": pooled / sum(expected),
        "ratio_err": pooled_err / sum(expected),
        "ratio24": pooled / sum(th["rho2"]),
        "sim": {"x": th["x"], "rho2": mean, "rho2_err": err},
        "theory": th,
        "expected": expected,
    }


def run_all(jobs, width):
    """Run the command lines of `jobs` (lists of arguments), `width` at a time."""
    running = []
    for cmd in jobs:
        while len(running) >= width:
            running.pop(0).wait()
        print(" ".join(cmd), flush=True)
        running.append(subprocess.Popen(cmd, stderr=subprocess.DEVNULL))
    for p in running:
        if p.wait() != 0:
            sys.exit("a run failed")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--bin", default=os.path.join(HERE, "target", "release", "colloidsim"))
    ap.add_argument("--jobs", type=int, default=2, help="runs at once")
    ap.add_argument("--replicas", type=int, default=6)
    ap.add_argument("--pre", type=float, default=400.0,
                    help="relaxation at dt = 1e-4 before the run (several times the wells' "
                         "occupation time)")
    ap.add_argument("--time", type=float, default=100.0, help="sampled time per replica")
    ap.add_argument("--equilibrate", type=float, default=10.0,
                    help="time at --dt before sampling")
    ap.add_argument("--dt", type=float, default=2e-6)
    ap.add_argument("--window", type=float, default=0.02)
    ap.add_argument("--only", default="",
                    help="one panel, SIGMA,N (e.g. 0.5,50): its runs and its table row only")
    a = ap.parse_args()
    binary = os.path.abspath(a.bin)
    if not os.access(binary, os.X_OK):
        sys.exit(f"no colloidsim binary at {binary}: cargo build --release -p colloidsim-cli")
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    panels = [(sigma, n) for sigma in SIGMAS for n in PARTICLES]
    if a.only:
        sigma, n = a.only.split(",")
        panels = [(float(sigma), int(n))]
        if panels[0] not in [(s, m) for s in SIGMAS for m in PARTICLES]:
            sys.exit(f"--only {a.only}: not one of the panels {SIGMAS} x {PARTICLES}")
    folder = {
        (sigma, n, kind, k): os.path.join(out, f"sigma-{sigma}-n-{n}", f"{kind}-{k}")
        for sigma, n in panels
        for kind in ("pre", "run")
        for k in range(a.replicas)
    }

    def command(sigma, n, kind, k):
        common = [
            binary, "run", SCENARIO, "--out", folder[(sigma, n, kind, k)], "--quiet",
            "--threads", "1", "--seed", str(k + 1),
            "--set", f"system.diameter={sigma}",
            "--set", f"system.particles={n}",
            "--set", "potential.cosine.amplitude=6.0",
            "--set", f"observe.contact_density.window={a.window}",
        ]
        if kind == "pre":
            return common + [
                "--set", "run.dt=1e-4", "--set", f"run.equilibrate={a.pre}",
                "--set", "run.time=0.01", "--set", "observe.every=10",
            ]
        start = os.path.join(folder[(sigma, n, "pre", k)], "final_configuration.csv")
        return common + [
            "--set", 'initial.placement="file"', "--set", f'initial.file="{start}"',
            "--set", f"run.dt={a.dt}", "--set", f"run.equilibrate={a.equilibrate}",
            "--set", f"run.time={a.time}",
            "--set", f"observe.every={max(1, round(1e-4 / a.dt))}",
        ]

    for kind in ("pre", "run"):
        jobs = [
            command(sigma, n, kind, k)
            for sigma, n in panels
            for k in range(a.replicas)
            if not os.path.exists(os.path.join(folder[(sigma, n, kind, k)], "summary.json"))
        ]
        run_all(jobs, a.jobs)
    results = {
        (sigma, n): compare(
            [folder[(sigma, n, "run", k)] for k in range(a.replicas)], n, a.dt, a.window
        )
        for sigma, n in panels
    }
    delta = SIEGMUND * math.sqrt(4.0 * a.dt)
    lines = [
        f"Hard rods in U0 = 6 kT, L = {LENGTH:g}, window {a.window}, dt {a.dt:g} (boundary layer "
        f"delta / w = {delta / a.window:.3f}), {a.replicas} replicas per panel, each relaxed "
        f"{a.pre:g} time units at dt = 1e-4, then {a.equilibrate:g} at dt and {a.time:g} sampled; "
        f"50 bins; errors: standard error between replicas. Expected: (N - 1)/N [rho2_window + "
        f"(delta / w) rho2].",
        "",
        "| sigma | rho | chi^2 per bin | largest deviation (SE) | pooled / expected | pooled / Eq. 24 |",
        "|---|---|---|---|---|---|",
    ]
    for (sigma, n), r in results.items():
        lines.append(
            f"| {sigma} | {n / LENGTH:g} | {r['chi2']:.2f} | {r['worst']:.1f} | "
            f"{r['ratio']:.3f} +- {r['ratio_err']:.3f} | {r['ratio24']:.3f} |"
        )
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text)
    print(text)
    if a.only:
        return
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no picture")
        return
    fig, axes = plt.subplots(3, 3, figsize=(10, 8.5), sharex=True)
    for c, sigma in enumerate(SIGMAS):
        for row, n in enumerate(PARTICLES):
            ax = axes[row][c]
            r = results[(sigma, n)]
            ax.plot(r["theory"]["x"], r["theory"]["rho2"], "k-", lw=1, label="exact (Eq. 24)")
            ax.plot(r["theory"]["x"], r["expected"], "--", color="tab:red", lw=1,
                    label="exact for the window, dt and N")
            ax.errorbar(r["sim"]["x"], r["sim"]["rho2"], yerr=r["sim"]["rho2_err"], fmt="o",
                        ms=3, mfc="none", color="k", label="BCD")
            if row == 0:
                ax.set_title(f"sigma = {sigma}")
            if c == 0:
                ax.set_ylabel(f"rho = {n / LENGTH:g}\nrho2(x, x + sigma)")
            if row == 2:
                ax.set_xlabel("x (lambda)")
    axes[0][0].legend(fontsize=7)
    fig.suptitle("Hard rods in U0 = 6 kT: two-particle density at contact (hard-rods paper Fig. 4)")
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "fig4.png"), dpi=110)
    print(f"wrote {os.path.join(a.out, 'fig4.png')}")


if __name__ == "__main__":
    main()
