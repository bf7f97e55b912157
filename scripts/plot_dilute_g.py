#!/usr/bin/env python3
"""The dilute pair correlation g(r) = Theta(r - d) of the RPY DDFT against the true hard-sphere
g(r) over the volume fractions the drying reaches (the drying-droplet paper's Fig. S9).

Usage: plot_dilute_g.py OUT PICTURE.png [--bin BINARY] [--phis 0.05,0.1,...] [--sweeps N]

For each phi (default 0.05, 0.1, 0.2, 0.3, 0.4, 0.45; at 0.5, inside the freezing region, the
MC's FCC start stays crystalline: contact 4.28 against Carnahan-Starling's 6.00) runs the hard-sphere Monte Carlo in a
periodic cube (`colloidsim run examples/mc/bulk.toml --set system.volume_fraction=PHI`: N = 2048,
2000 warm-up and 10,000 sampling sweeps, 20 blocks) into OUT/mc-PHI/, and Trokhymchuk et al.'s
g(r; phi) as the DDFT uses it (`cargo run --release -p colloidsim-dft --example pair_table --
OUT/pair PHIS`). Draws the three per phi and writes OUT/table.md: the contact value g(d+) of the
MC (with its block standard error) against Carnahan-Starling, Trokhymchuk and the dilute step's 1,
and the bulk sedimentation coefficient of the radial RPY flux that each g gives,
K = 1 - 5 phi + 12 phi int_1^5 x h(x) dx (h = g - 1, x = r/d; the dilute step: 1 - 5 phi; the MC
and Trokhymchuk both cut at 5 d, the MC's error from its bins' errors as if independent).
"""
import json
import os
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from tables import columns, option  # noqa: E402  (scripts/tables.py)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..")
CUT = 5.0  # diameters: the MC's g(r) range (output.gr_max of examples/mc/bulk.toml)


def k_integral(x, g, err=None):
    """int_1^CUT x (g - 1) dx over the MC's bins (x: bin centres; each bin's average)."""
    total, var = 0.0, 0.0
    width = x[1] - x[0]
    for i in range(len(x)):
        if x[i] < 1.0 or x[i] > CUT:
            continue
        total += x[i] * (g[i] - 1.0) * width
        var += (x[i] * err[i] * width) ** 2
    return total, var ** 0.5


def k_integral_table(x, g):
    """int_1^CUT x (g - 1) dx by the trapezoidal rule on the table's points (x = 1 is one)."""
    total = 0.0
    for i in range(len(x) - 1):
        if x[i] < 1.0 - 1e-9 or x[i + 1] > CUT + 1e-9:
            continue
        total += 0.5 * (x[i] * (g[i] - 1.0) + x[i + 1] * (g[i + 1] - 1.0)) * (x[i + 1] - x[i])
    return total


def main():
    args = sys.argv[1:]
    binary = option(args, "--bin", os.path.join(ROOT, "target", "release", "colloidsim"))
    phis = [float(p) for p in option(args, "--phis", "0.05,0.1,0.2,0.3,0.4,0.45").split(",")]
    sweeps = option(args, "--sweeps", None)
    if len(args) != 2:
        sys.exit(__doc__)
    out, picture = args
    os.makedirs(out, exist_ok=True)
    start = time.time()
    subprocess.run(
        ["cargo", "run", "--quiet", "--release", "-p", "colloidsim-dft", "--example", "pair_table",
         "--", os.path.join(out, "pair"), ",".join(str(p) for p in phis)],
        cwd=ROOT, check=True)
    table = columns(os.path.join(out, "pair", "g_r.csv"))
    contact = columns(os.path.join(out, "pair", "contact.csv"))
    print(f"pair table: {time.time() - start:.1f} s")
    mc = {}
    for phi in phis:
        folder = os.path.join(out, f"mc-{phi}")
        cmd = [binary, "run", os.path.join(ROOT, "examples", "mc", "bulk.toml"), "--out", folder,
               "--force", "--quiet", "--set", f"system.volume_fraction={phi}"]
        if sweeps:
            cmd += ["--set", f"mc.sweeps={sweeps}"]
        start = time.time()
        subprocess.run(cmd, check=True)
        seconds = time.time() - start
        with open(os.path.join(folder, "summary.json")) as f:
            summary = json.load(f)
        mc[phi] = (columns(os.path.join(folder, "g_r.csv")), summary, seconds)
        print(f"MC phi = {phi}: {seconds:.1f} s")

    n = len(phis)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.6 * rows), squeeze=False)
    lines = []
    for k, phi in enumerate(phis):
        ax = axes[k // cols][k % cols]
        g, summary, seconds = mc[phi]
        ax.fill_between(g["r"], [a - 2 * e for a, e in zip(g["g"], g["err"])],
                        [a + 2 * e for a, e in zip(g["g"], g["err"])], color="0.75", lw=0)
        ax.plot(g["r"], g["g"], "k.", ms=2.5, label="hard-sphere MC (2 SE band)")
        ax.plot(table["x"], table[f"g_{phi}"], "-", color="tab:red", lw=1.2,
                label="Trokhymchuk et al.")
        ax.plot([0, 1, 1, 4], [0, 0, 1, 1], "--", color="tab:blue", lw=1.2,
                label="dilute: Theta(r - d)")
        ax.set_xlim(0.8, 3.5)
        ax.set_title(f"phi = {phi}")
        ax.set_xlabel("r / d")
        ax.set_ylabel("g(r)")
        if k == 0:
            ax.legend(fontsize=8)
        cv = summary["contact_value"]
        cs = summary["carnahan_starling"]
        eta_col = contact["eta"].index(min(contact["eta"], key=lambda e: abs(e - phi)))
        g_t = contact["trokhymchuk"][eta_col]
        g_cs = contact["carnahan_starling"][eta_col]
        i_mc, e_mc = k_integral(g["r"], g["g"], g["err"])
        x = table["x"]
        i_t = k_integral_table(x, table[f"g_{phi}"])
        k_mc = 1 - 5 * phi + 12 * phi * i_mc
        k_t = 1 - 5 * phi + 12 * phi * i_t
        z = summary["compressibility"]
        lines.append((phi, cv["value"], cv["standard_error"], g_cs, g_t, k_mc, 12 * phi * e_mc,
                      k_t, 1 - 5 * phi, z["value"], z["standard_error"], cs, seconds))
        # The table's plumbing: in the fits' range Trokhymchuk's contact is Kolafa's, within
        # 1.5 % of Carnahan-Starling's.
        if 0.105 <= phi <= 0.471:
            assert abs(g_t / g_cs - 1) < 0.015, (phi, g_t, g_cs)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.suptitle("Fig. S9: the dilute step against the hard-sphere g(r) (MC, N = 2048) and "
                 "Trokhymchuk's fit")
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}")
    with open(os.path.join(out, "table.md"), "w") as f:
        f.write("| phi | g(d+) MC | Carnahan-Starling | Trokhymchuk | dilute | (MC - CS) / SE "
                "| K MC (to 5 d) | K Trokhymchuk (to 5 d) | K dilute 1 - 5 phi | Z MC | Z CS | MC s |\n")
        f.write("|---" * 12 + "|\n")
        for (phi, gc, ge, gcs, gt, kmc, kme, kt, kd, z, ze, cs, s) in lines:
            zcs = cs["compressibility"]
            f.write(f"| {phi} | {gc:.4f} ± {ge:.4f} | {gcs:.4f} | {gt:.4f} | 1 | "
                    f"{(gc - gcs) / ge:+.1f} | {kmc:.3f} ± {kme:.3f} | {kt:.3f} | {kd:.2f} | "
                    f"{z:.4f} ± {ze:.4f} | {zcs:.4f} | {s:.0f} |\n")
    print(open(os.path.join(out, "table.md")).read())


if __name__ == "__main__":
    main()
