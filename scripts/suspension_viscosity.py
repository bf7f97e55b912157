#!/usr/bin/env python3
"""The shear viscosity of the DPD colloid suspension against its solvent (issue 19): the notes'
colloid model (examples/dpd/colloids-equilibrium.toml: R_c = 1, kT = 0.1, gamma = 4.5,
eta0 = 0.3, contact and squeeze lubrication, dt = 0.001, box 15 rc) sheared by Lees-Edwards
boundaries at `--rate`, at each volume fraction of `--phi` (0 is the pure solvent at the same
density and temperature), `--steps` steps each, the stress averaged over the second half
(`shear_viscosity` of summary.json: <-P_xy> / rate, standard error of 10 block means).

The relative viscosity eta_r = eta(phi) / eta(0) is printed beside the dilute theories:
Einstein (1 + 2.5 phi); 1 + 2.5 phi + 5.2 phi^2, the hydrodynamic pair term at the equilibrium
structure, and 1 + 2.5 phi + 6.2 phi^2 with the Brownian stress, the low-Peclet limit (both
Batchelor 1977); 1 + 2.5 phi + 7.6 phi^2, pure straining at high Peclet (Batchelor & Green
1972); and Krieger-Dougherty (1 - phi / 0.63)^(-2.5 * 0.63). Its error is propagated from the
two block errors (docs/references.md).

With --plot PNG, eta_r against phi with its error bars beside the theories (matplotlib).

A folder whose summary.json says completed is reused, so the script can be stopped and started
again.

Usage (from the repository root):
  python3 scripts/suspension_viscosity.py OUT --bin target/release/colloidsim \\
      --phi 0,0.05,0.1,0.2 --rate 0.2 --steps 100000 --plot docs/img/dpd-suspension-viscosity.png
"""

import argparse
import json
import math
import pathlib
import subprocess
import time

SCENARIO = """method = "dpd"
seed = {seed}
[system]
box_length = {box}
density = 3.0
phi = {phi}
kT = 0.1
colloid_radius = 1.0
[dpd]
gamma = 4.5
repulsion = 25.0
[colloids]
contact = 10000.0
contact_range = 0.001
eta0 = 0.3
lubrication_gap = 0.001
lubrication_noise = "exact"
[run]
dt = 0.001
steps = {steps}
skin = 0.4
shear_rate = {rate}
[observe]
thermo_every = 1000
trajectory_every = 0
msd_every = 0
structure_every = 0
profile_bins = 15
"""


def run(args, phi):
    out = args.out / f"phi{phi}"
    summary = out / "summary.json"
    if summary.exists():
        s = json.loads(summary.read_text())
        if s.get("completed"):
            return s, None
    args.out.mkdir(parents=True, exist_ok=True)
    sc = args.out / f"phi{phi}.toml"
    sc.write_text(
        SCENARIO.format(
            seed=args.seed, box=args.box, phi=phi, steps=args.steps, rate=args.rate
        )
    )
    t0 = time.time()
    cmd = [str(args.bin), "run", str(sc), "--out", str(out), "--quiet", "--force"]
    if args.threads:
        cmd += ["--threads", str(args.threads)]
    subprocess.run(cmd, check=True)
    return json.loads(summary.read_text()), time.time() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=pathlib.Path)
    ap.add_argument("--bin", type=pathlib.Path, default="target/release/colloidsim")
    ap.add_argument("--phi", default="0,0.05,0.1,0.2")
    ap.add_argument("--rate", type=float, default=0.2)
    ap.add_argument("--steps", type=int, default=100000)
    ap.add_argument("--box", type=float, default=15.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--plot", type=pathlib.Path)
    args = ap.parse_args()
    phis = [float(x) for x in args.phi.split(",")]
    if 0.0 not in phis:
        phis = [0.0] + phis
    rows = []
    for phi in phis:
        s, wall = run(args, phi)
        rows.append((phi, s, wall))
    eta0, err0 = rows[0][1]["shear_viscosity"], rows[0][1]["shear_viscosity_error"]
    tau_d = None
    print(
        f"# shear rate {args.rate}, {args.steps} steps (dt 0.001), box {args.box}, seed {args.seed}"
    )
    print(
        "| phi | colloids | eta | eta_r | Einstein | + 5.2 phi^2 | + 6.2 phi^2 | + 7.6 phi^2 | Krieger-Dougherty | T solvent | T colloids | profile slope / rate | wall s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for phi, s, wall in rows:
        eta, err = s["shear_viscosity"], s["shear_viscosity_error"]
        r = eta / eta0
        r_err = r * math.hypot(err / eta, err0 / eta0) if phi > 0 else 0.0
        temps = s.get("final_temperature_by_type") or [float("nan")]
        t_col = s.get("mean_colloid_temperature_second_half")
        p = s["parameters"]
        tau_d = p.get("diffusion_time_tau", tau_d)
        kd = (1 - phi / 0.63) ** (-2.5 * 0.63)
        print(
            f"| {phi} | {p.get('colloids', '-')} | {eta:.4f} +- {err:.4f} | {r:.3f} +- {r_err:.3f} "
            f"| {1 + 2.5 * phi:.3f} | {1 + 2.5 * phi + 5.2 * phi**2:.3f} | {1 + 2.5 * phi + 6.2 * phi**2:.3f} "
            f"| {1 + 2.5 * phi + 7.6 * phi**2:.3f} "
            f"| {kd:.3f} | {s.get('mean_temperature_second_half', temps[0]):.4f} "
            f"| {t_col if t_col is None else round(t_col, 4)} "
            f"| {s['velocity_profile_slope'] / args.rate:.4f} | {'-' if wall is None else round(wall)} |"
        )
    if tau_d:
        print(f"# Peclet number rate * tau_D = {args.rate * tau_d:.1f} (tau_D = {tau_d:.1f})")
    parts_table(rows)
    if args.plot:
        plot(args, rows, eta0, err0, tau_d)


def parts_table(rows):
    """Each part of the viscosity (summary.json's shear_stress_parts / rate, in units of the
    solvent's total viscosity) for every phi, and what it adds over the solvent run."""
    parts0 = rows[0][1].get("shear_stress_parts") or {}
    names = [k for k in parts0 if k != "note"]
    if not names:
        return
    eta0 = rows[0][1]["shear_viscosity"]
    print()
    print("# the viscosity by part, eta_part / eta_solvent (error): " + ", ".join(names))
    print("| phi | " + " | ".join(names) + " | sum |")
    print("|---|" + "---|" * (len(names) + 1))
    for phi, s, _ in rows:
        parts = s.get("shear_stress_parts") or {}
        if not all(n in parts for n in names):
            print(f"| {phi} | " + " | ".join("-" for _ in names) + " | - |")
            continue
        cells = [
            f"{parts[n]['viscosity'] / eta0:.4f} ({parts[n]['viscosity_error'] / eta0:.4f})"
            for n in names
        ]
        total = sum(parts[n]["viscosity"] for n in names) / eta0
        print(f"| {phi} | " + " | ".join(cells) + f" | {total:.4f} |")


def plot(args, rows, eta0, err0, tau_d):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    phi = [r[0] for r in rows]
    eta_r, err = [], []
    for p, s, _ in rows:
        e, se = s["shear_viscosity"], s["shear_viscosity_error"]
        eta_r.append(e / eta0)
        err.append(e / eta0 * math.hypot(se / e, err0 / eta0) if p > 0 else 0.0)
    x = [i * max(phi) / 100 for i in range(101)]
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.plot(x, [1 + 2.5 * v for v in x], "k:", label="Einstein, 1 + 2.5 phi")
    for k, style in [(5.2, "--"), (6.2, "-."), (7.6, (0, (1, 1)))]:
        ax.plot(x, [1 + 2.5 * v + k * v * v for v in x], ls=style, color="grey",
                label=f"1 + 2.5 phi + {k} phi^2")
    ax.plot(x, [(1 - v / 0.63) ** (-2.5 * 0.63) for v in x], "b-", lw=0.8,
            label="Krieger-Dougherty (phi_m = 0.63)")
    ax.errorbar(phi, eta_r, yerr=err, fmt="o", color="C3", capsize=3,
                label=f"DPD colloids, Lees-Edwards, rate {args.rate}")
    ax.set_xlabel("colloid volume fraction phi")
    ax.set_ylabel("relative viscosity eta / eta_solvent")
    pe = f", Pe = {args.rate * tau_d:.0f}" if tau_d else ""
    ax.set_title(f"DPD suspension (notes' model, box {args.box:g} rc{pe})", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.plot, dpi=120)


if __name__ == "__main__":
    main()
