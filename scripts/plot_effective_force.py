#!/usr/bin/env python3
"""The effective force on the particles of the drying droplet (the drying-droplet paper's
Fig. S10): beta F_eff(r) = -d/dr [ln rho + beta mu_ex + beta V] of Eq. 16, zero at the
equilibrium start and growing as the drying drives the suspension out of equilibrium.

Usage: plot_effective_force.py OUT PICTURE.png [--bin BINARY] [--scenario TOML] [--dx DX] [--reuse]

Runs `colloidsim theory` on the scenario (default examples/droplet/drying-bd-paper.toml, the
paper's droplet: N = 6250, R0 = 25 d, phi0 = 0.05, Pe = 10, dried to phi 0.5) with output every
5 % of the drying time, three times: free draining, RPY with the dilute g (stops when particles
are ejected) and RPY with Trokhymchuk's g, into OUT/<model>/ (force_<f>.csv: r, force in kT/d,
phi; summary.json: effective_force). Draws the force profiles at 0, 25, 50, 75 and 100 % for
free draining and RPY with Trokhymchuk's g, and the particle-weighted mean force and the largest
|F| against the fraction of the drying time for all three; writes OUT/table.md. --reuse keeps
the runs already in OUT (their summary.json) and only draws.
"""
import json
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from tables import columns, option  # noqa: E402  (scripts/tables.py)

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = [
    ("free-draining", "free draining", ["--hydrodynamics", "free-draining"]),
    ("rpy-dilute", "RPY, dilute g", ["--hydrodynamics", "rpy", "--pair", "dilute"]),
    ("rpy-trokhymchuk", "RPY, Trokhymchuk g", ["--hydrodynamics", "rpy", "--pair", "trokhymchuk"]),
]
FRACTIONS = [round(0.05 * k, 2) for k in range(21)]


def main():
    args = sys.argv[1:]
    binary = option(args, "--bin", os.path.join(HERE, "..", "target", "release", "colloidsim"))
    scenario = option(
        args, "--scenario", os.path.join(HERE, "..", "examples", "droplet", "drying-bd-paper.toml")
    )
    dx = option(args, "--dx", "0.02")
    reuse = "--reuse" in args
    if reuse:
        args.remove("--reuse")
    if len(args) != 2:
        sys.exit(__doc__)
    out, picture = args
    os.makedirs(out, exist_ok=True)
    fractions = "[" + ", ".join(str(f) for f in FRACTIONS) + "]"
    results = {}
    for name, label, flags in MODELS:
        folder = os.path.join(out, name)
        if not (reuse and os.path.exists(os.path.join(folder, "summary.json"))):
            cmd = [binary, "theory", scenario, "--dx", dx, "--out", folder, "--force"]
            cmd += ["--set", f"observe.profile.fractions={fractions}"] + flags
            # The dilute RPY run stops (non-zero exit) once particles are ejected; its summary
            # says so.
            subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL)
        with open(os.path.join(folder, "summary.json")) as f:
            summary = json.load(f)
        seconds = summary["wall_seconds"]
        results[name] = (label, summary, seconds)
        print(f"{name}: {summary['status']} in {seconds:.1f} s {summary['message']}")

    fig, (a, b, c) = plt.subplots(1, 3, figsize=(16, 4.6))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, name, style in ((a, "free-draining", "-"), (a, "rpy-trokhymchuk", "--")):
        label, summary, _ = results[name]
        for k, f in enumerate([0.0, 0.25, 0.5, 0.75, 1.0]):
            path = os.path.join(out, name, "force_%.2f.csv" % f)
            if not os.path.exists(path):
                continue
            t = columns(path)
            ax.plot(t["r"], t["force"], style, color=colours[k], lw=1.2,
                    label=f"{label}, {100 * f:.0f} %")
    a.axhline(0.0, color="0.6", lw=0.8)
    a.set_xlabel("r / d")
    a.set_ylabel("beta F_eff d  (kT / d)")
    a.set_title("Effective force -d/dr [ln rho + beta mu_ex + beta V]")
    a.legend(fontsize=7, loc="lower right")
    rows = []
    for k, (name, label, _) in enumerate(MODELS):
        _, summary, _ = results[name]
        ef = summary["effective_force"]
        x = [100 * e["fraction"] for e in ef]
        b.plot(x, [e["mean_kT_per_d"] for e in ef], "o-", ms=3, color=colours[k], label=label)
        c.semilogy(x, [max(e["max_abs_kT_per_d"], 1e-14) for e in ef], "o-", ms=3,
                   color=colours[k], label=label)
        rows.append((name, label, ef))
    b.axhline(0.0, color="0.6", lw=0.8)
    b.set_xlabel("% of the drying time")
    b.set_ylabel("particle-weighted mean of beta F_eff d")
    b.set_title("Mean force (free draining: (d<r>/dt) / D0)")
    b.legend(fontsize=8)
    c.set_xlabel("% of the drying time")
    c.set_ylabel("max |beta F_eff d|")
    c.set_title("Largest force (0 % : equilibrium, ~1e-11)")
    c.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}")

    with open(os.path.join(out, "table.md"), "w") as f:
        f.write("Effective force of Eq. 16, kT/d: particle-weighted mean / largest |F| "
                f"(`{os.path.basename(scenario)}`, dx = {dx})\n\n")
        f.write("| % of drying | " + " | ".join(r[1] for r in rows) + " |\n")
        f.write("|---" * (len(rows) + 1) + "|\n")
        for frac in [0.0, 0.05, 0.25, 0.5, 0.75, 1.0]:
            cells = []
            for _, _, ef in rows:
                e = [e for e in ef if abs(e["fraction"] - frac) < 1e-9]
                cells.append("%.3g / %.3g" % (e[0]["mean_kT_per_d"], e[0]["max_abs_kT_per_d"])
                             if e else "(ejected)")
            f.write(f"| {100 * frac:.0f} | " + " | ".join(cells) + " |\n")
        f.write("\n")
        for name, label, _ in MODELS:
            _, summary, seconds = results[name]
            f.write(f"- {label}: {summary['status']}, {seconds:.1f} s. {summary['message']}\n")
    print(open(os.path.join(out, "table.md")).read())


if __name__ == "__main__":
    main()
