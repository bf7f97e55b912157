#!/usr/bin/env python3
"""The hard-rods paper's Fig. 6: sticky-rod density profiles in the cosine potential (U0 = 6 kT)
for gamma = 0.1, 1, 10 (rows) and sigma = rho = 0.2, 0.5, 0.8 (columns), with eps = 0.025 beside
eps = 0.05 in the right column, each against the exact eps -> 0 (Baxter) theory.

Each column is one `colloidsim ensemble` of examples/bcd/sticky-rods.toml (replicas with seeds
seed, seed + 1, ..., and --vary interaction.sticky.gamma=[0.1, 1, 10]); the errors are the
standard errors between replicas that the ensemble writes (`rho_err`).

    python3 scripts/sticky_profiles_fig6.py OUT [--bin target/release/colloidsim]
        [--mpirun "mpirun -n 2"] [--replicas 4] [--time 20] [--equilibrate 20] [--dt 5e-6]

Writes OUT/<column>/ (the ensembles), OUT/table.md (per panel: the largest deviation in standard
errors over the bins, chi^2 per bin, and the peak's deviation) and OUT/fig6.png.
"""
import argparse
import os
import shlex
import subprocess
import sys

from sticky_common import COLLOIDSIM, SCENARIO, peak, rods, table

GAMMAS = [0.1, 1.0, 10.0]


def compare(folder):
    """Largest |z|, chi^2 per bin and the peak's relative deviation (three bins around the
    theory's maximum) with its error, of one sweep point's averaged profile."""
    sim = table(os.path.join(folder, "density.csv"))
    th = table(os.path.join(folder, "density_theory.csv"))
    z = [
        (r - t) / e
        for r, t, e in zip(sim["rho"], th["rho"], sim["rho_err"])
        if e > 0
    ]
    dev, dev_err = peak(sim["rho"], th["rho"], sim["rho_err"])
    return {
        "worst": max(abs(v) for v in z),
        "chi2": sum(v * v for v in z) / len(z),
        "bins": len(z),
        "peak": dev,
        "peak_err": dev_err,
        "sim": sim,
        "theory": th,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--bin", default=COLLOIDSIM)
    ap.add_argument("--mpirun", default="", help='e.g. "mpirun -n 2" (an MPI build of --bin)')
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--time", type=float, default=20.0, help="sampled time per replica")
    ap.add_argument("--equilibrate", type=float, default=20.0,
                    help="time before sampling (the example's 2 leaves dense and sticky "
                         "profiles unrelaxed)")
    ap.add_argument("--dt", type=float, default=5e-6,
                    help="time step at eps = 0.05; halved at 0.025 (mu max|f| dt / eps of "
                         "Eq. 34: 0.03 and 0.07)")
    a = ap.parse_args()
    binary = os.path.abspath(a.bin)
    if not os.access(binary, os.X_OK):
        sys.exit(f"no colloidsim binary at {binary}: cargo build --release -p colloidsim-cli")
    os.makedirs(a.out, exist_ok=True)
    columns = [(0.2, 0.05), (0.5, 0.05), (0.8, 0.05), (0.8, 0.025)]
    results = {}
    for sigma, eps in columns:
        name = f"sigma-{sigma}-eps-{eps}"
        folder = os.path.join(a.out, name)
        dt = a.dt * eps / 0.05
        if not os.path.exists(os.path.join(folder, "summary.json")):
            cmd = shlex.split(a.mpirun) + [
                binary, "ensemble", SCENARIO, "--out", folder, "--quiet",
                "--replicas", str(a.replicas),
                "--vary", "interaction.sticky.gamma=[" + ", ".join(map(str, GAMMAS)) + "]",
                "--set", f"system.diameter={sigma}",
                "--set", f"system.particles={rods(sigma)}",
                "--set", f"interaction.sticky.range={eps}",
                "--set", f"run.dt={dt}",
                "--set", f"run.time={a.time}",
                "--set", f"run.equilibrate={a.equilibrate}",
                "--set", "observe.density.bins=50",
            ]
            print(" ".join(cmd), flush=True)
            subprocess.run(cmd, check=True)
        for p, gamma in enumerate(GAMMAS):
            results[(sigma, eps, gamma)] = compare(os.path.join(folder, f"point-{p}"))
    lines = [
        f"Sticky rods in U0 = 6 kT, p = 3, L = 100, {a.replicas} replicas x {a.time} time units "
        f"after {a.equilibrate} of equilibration per panel, 50 bins; errors: standard error "
        f"between replicas.",
        "",
        "| sigma = rho | eps | dt | gamma | largest deviation (SE) | chi^2 per bin | peak deviation |",
        "|---|---|---|---|---|---|---|",
    ]
    for (sigma, eps, gamma), r in results.items():
        dt = a.dt * eps / 0.05
        lines.append(
            f"| {sigma} | {eps} | {dt:.3g} | {gamma} | {r['worst']:.1f} | {r['chi2']:.2f} | "
            f"{100 * r['peak']:+.2f} % +- {100 * r['peak_err']:.2f} % |"
        )
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text)
    print(text)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no picture")
        return
    fig, axes = plt.subplots(3, 3, figsize=(10, 8.5), sharex=True)
    for c, sigma in enumerate([0.2, 0.5, 0.8]):
        for row, gamma in enumerate(GAMMAS):
            ax = axes[row][c]
            r = results[(sigma, 0.05, gamma)]
            ax.semilogy(r["theory"]["x"], r["theory"]["rho"], "k-", lw=1, label="exact (eps -> 0)")
            ax.errorbar(r["sim"]["x"], r["sim"]["rho"], yerr=r["sim"]["rho_err"], fmt="o",
                        ms=3, mfc="none", color="k", label="BCD, eps = 0.05")
            if (sigma, 0.025, gamma) in results:
                q = results[(sigma, 0.025, gamma)]
                ax.errorbar(q["sim"]["x"], q["sim"]["rho"], yerr=q["sim"]["rho_err"], fmt="o",
                            ms=3, color="tab:blue", label="BCD, eps = 0.025")
            if row == 0:
                ax.set_title(f"sigma = rho = {sigma}")
            if c == 2:
                ax.yaxis.set_label_position("right")
                ax.set_ylabel(f"gamma = {gamma}")
            elif c == 0:
                ax.set_ylabel("density")
            if row == 2:
                ax.set_xlabel("x")
    axes[0][2].legend(fontsize=7, loc="lower center")
    fig.suptitle("Sticky rods in U0 cos(2 pi x), U0 = 6 kT (hard-rods paper Fig. 6)")
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "fig6.png"), dpi=110)
    print("wrote", os.path.join(a.out, "fig6.png"))


if __name__ == "__main__":
    main()
