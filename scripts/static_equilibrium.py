#!/usr/bin/env python3
"""Static droplet equilibrium (the paper's Fig. 2a): BD and hard-sphere Monte Carlo radial
profiles beside the radial Rosenfeld-FMT equilibrium of the same N, at mean volume fractions 0.05
to 0.5, in a droplet of R0 = 8 d (examples/droplet/static-equilibrium.toml; the MC samples the
same harmonic interface, method = "hs-mc" with geometry = "interface").

Usage: static_equilibrium.py COLLOIDSIM WORKDIR PICTURE.png [--reuse] [PHI ...]

--reuse keeps the runs whose summary.json is already in WORKDIR (to redraw the picture).

For phi <= 0.3 the static run starts from random insertion; above, the droplet is first dried
slowly (Pe = 1) from phi = 0.25 to 1.06 x the target in a stiffer interface (500 kT/d^2) and the static run starts from its last frame
(`system.initial`). BD: `profile_mean.csv` (the mean of the profiles after the first, with its
standard error from their scatter); FMT: `colloidsim theory` of the same scenario
(`equilibrium_1.00.csv`, same bins).
"""
import csv
import os
import re
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE = os.path.join(HERE, "..", "examples", "droplet", "static-equilibrium.toml")
R0 = 8.0


REUSE = False

MC = """method = "hs-mc"
seed = 1
[system]
geometry = "interface"
particles = {n}
radius = {r0}
diameter = 1.0
[interface]
stiffness = 50.0
range = 0.5
offset = -0.5
[mc]
sweeps = 20000
warmup_sweeps = 2000
sample_every = 20
blocks = 20
[output]
profile_bins = 40
"""


def run(binary, *args):
    out = args[args.index("--out") + 1]
    if REUSE and os.path.exists(os.path.join(out, "summary.json")):
        return
    subprocess.run([binary, *args], check=True)


def table(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def main():
    global REUSE
    binary, work, picture = sys.argv[1], sys.argv[2], sys.argv[3]
    rest = sys.argv[4:]
    REUSE = "--reuse" in rest
    phis = [float(x) for x in rest if x != "--reuse"] or [0.05, 0.1, 0.2, 0.3, 0.4, 0.5]
    os.makedirs(work, exist_ok=True)
    results = []
    for phi in phis:
        n = round(8 * phi * R0**3)
        tag = f"phi{phi:.2f}"
        sets = ["--set", f"system.particles={n}", "--set", f"system.phi0={phi}"]
        if phi > 0.3:
            # The drying stage: the example with its duration replaced by the target.
            dry = os.path.join(work, f"{tag}-dry")
            text = open(EXAMPLE).read()
            text = re.sub(r"(?m)^peclet = .*$", "peclet = 1", text)
            # A little beyond the target, so that the last frame lies within R0.
            # A little beyond the target and with a stiffer interface, so that the last frame
            # lies within R0 + offset + range of the static run.
            text = re.sub(r"(?m)^duration = .*$", f"final_volume_fraction = {1.06 * phi:.4f}", text)
            text = re.sub(r"(?m)^stiffness = .*$", "stiffness = 500.0", text)
            scenario = os.path.join(work, f"{tag}-dry.toml")
            with open(scenario, "w") as f:
                f.write(text)
            run(binary, "run", scenario, "--out", dry, "--force", "--quiet",
                "--set", f"system.particles={n}", "--set", "system.phi0=0.25",
                "--set", "replicas=1", "--set", "observe.trajectory.every=500",
                "--set", "observe.profile.fractions=[0, 1.0]")
            sets += ["--set", f"system.initial={os.path.abspath(os.path.join(dry, 'trajectory.gsd'))}"]
        bd = os.path.join(work, f"{tag}-bd")
        th = os.path.join(work, f"{tag}-theory")
        run(binary, "run", EXAMPLE, "--out", bd, "--force", "--quiet", *sets)
        run(binary, "theory", EXAMPLE, "--out", th, "--force", "--dx", "0.02", *sets)
        mc_scenario = os.path.join(work, f"{tag}-mc.toml")
        with open(mc_scenario, "w") as f:
            f.write(MC.format(n=n, r0=R0))
        mc = os.path.join(work, f"{tag}-mc")
        run(binary, "run", mc_scenario, "--out", mc, "--force", "--quiet")
        results.append((phi, table(os.path.join(bd, "profile_mean.csv")),
                        table(os.path.join(mc, "profile_mean.csv")),
                        table(os.path.join(th, "equilibrium_1.00.csv"))))
    cols = 3
    rows = (len(results) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), squeeze=False)
    for ax, (phi, bd, mc, th) in zip(axes.flat, results):
        ax.errorbar(bd["r"], bd["rho_v"], yerr=bd["rho_v_err"], fmt="o", ms=3, label="BD (WCA)")
        ax.errorbar(mc["r"], mc["rho_v"], yerr=mc["rho_v_err"], fmt="s", ms=2.5, label="hard-sphere MC")
        ax.plot(th["r"], th["rho_v"], "-", color="k", lw=1, label="Rosenfeld FMT equilibrium")
        ax.set_ylim(0.0, 1.35 * max(th["rho_v"]))
        ax.set_title(f"mean phi = {phi}")
        ax.set_xlabel("r / d")
        ax.set_ylabel("phi (bin average)")
    axes.flat[0].legend(fontsize=8)
    for ax in list(axes.flat)[len(results):]:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main()
