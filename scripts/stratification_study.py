#!/usr/bin/env python3
"""Does hydrodynamics decide stratification? The study of issue 43 (docs/stratification.md).

A droplet of two hard-sphere sizes (size ratio alpha = d_l / d_s, equal volumes of small and large
spheres, examples/droplet/bidisperse-bd.toml scaled) dried at a small-sphere Peclet number Pe_s
from phi0 to phi = 0.5, on a grid of Pe_s and phi0 (phi_s = phi0 / 2), by each method:

  bd-fd      free-draining Brownian dynamics (droplet-bd), REPLICAS droplets per point
  bd-rpy     Brownian dynamics with the unequal-radius RPY mobility (direct free-space sums)
  ddft-fd    the binary White Bear FMT DDFT with free-draining fluxes (colloidsim theory)
  ddft-rpy   the same DDFT with the pairwise unequal-radius RPY flux (--hydrodynamics rpy)
  eq         the binary FMT equilibrium reference: the DDFT dried at Pe_s = EQ_PECLET, slow
             enough that every profile is the static one at its radius

The measure is the difference of the species' mean centre distances over R at the end of
drying, Delta = <r>_s / R - <r>_l / R (colloidsim_analysis::stratification). A mixed droplet
has Delta > 0 already, because a small centre reaches (d_l - d_s) / 2 closer to the surface;
so each run is compared with the equilibrium droplet of the same radius: S = Delta - Delta_eq.
S > 0 is small-on-top, S < 0 large-on-top. The threshold of small-on-top is the Pe_s phi_s at
which S turns positive (interpolated in log Pe_s between grid points at each phi0).

Each point is one folder RUNS/<method>/phi<phi0>-pe<Pe_s>; a folder whose summary.json says the
run completed is skipped, so the script can be stopped and started again.

Outputs: DATA/stratification_study.csv (one row per method and point: Delta and its standard
error over the droplets, Delta_eq, S, the shell enrichment, wall seconds), DATA/thresholds.csv,
IMG/stratification-diagram.png (S on the Pe_s x phi_s plane per method, with the lines
Pe_s phi_s = 1/alpha^2 and 1), IMG/stratification-vs-pephi.png (S against Pe_s phi_s), and a
markdown table on stdout.

Usage (from the repository root):
  python3 scripts/stratification_study.py --bin target/release/colloidsim --runs /tmp/strat \\
      [--methods bd-fd,ddft-fd,ddft-rpy,eq] [--peclet 1,3,10,30,100] [--phi0 0.05,0.1,0.2] \\
      [--replicas 4] [--particles 900] [--threads 2] [--analyse-only]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

ALPHA = 2.0
EQ_PECLET = 0.01
BASE = "examples/droplet/bidisperse-bd.toml"
DDFT_DX = "0.05"


def scenario(pe, phi0, replicas, method, particles=900):
    """The example with this Peclet number, initial volume fraction, replicas, mobility and
    number of spheres (8 small per large: equal volumes at alpha = 2)."""
    with open(BASE) as f:
        lines = f.read().splitlines()
    out = []
    for line in lines:
        key = line.split("=")[0].strip()
        if key == "peclet":
            line = f"peclet = {pe}"
        elif key == "phi0":
            line = f"phi0 = {phi0}"
        elif key == "replicas":
            line = f"replicas = {replicas}"
        elif key == "particles":
            line = f"particles = {particles}"
        elif key == "counts":
            large = particles // 9
            line = f"counts = [{particles - large}, {large}]"
        out.append(line)
    text = "\n".join(out) + "\n"
    if method == "bd-rpy":
        text += '\n[hydrodynamics]\nmodel = "rpy"\nmethod = "direct"\n'
    return text


def completed(folder):
    try:
        with open(os.path.join(folder, "summary.json")) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return False
    if "completed" in s:  # colloidsim run
        return s["completed"] is True
    return s.get("status") == "ok"  # colloidsim theory


def points(args, method):
    if method == "eq":
        return [(EQ_PECLET, phi0) for phi0 in args.phi0]
    return [(pe, phi0) for phi0 in args.phi0 for pe in args.peclet]


def folder_of(runs, method, pe, phi0):
    return os.path.join(runs, method, f"phi{phi0:g}-pe{pe:g}")


def run_point(args, method, pe, phi0, log):
    folder = folder_of(args.runs, method, pe, phi0)
    if completed(folder):
        return
    os.makedirs(os.path.dirname(folder), exist_ok=True)
    scen = folder + ".toml"
    with open(scen, "w") as f:
        f.write(scenario(pe, phi0, args.replicas, method, args.particles))
    if method.startswith("bd"):
        cmd = [args.bin, "run", scen, "--out", folder, "--force", "--quiet",
               "--threads", str(args.threads)]
    else:
        cmd = [args.bin, "theory", scen, "--out", folder, "--force", "--dx", DDFT_DX]
        if method == "ddft-rpy":
            cmd += ["--hydrodynamics", "rpy"]
    t0 = time.time()
    res = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    ok = res.returncode == 0 and completed(folder)
    print(f"{method} phi0={phi0} Pe={pe}: {'ok' if ok else 'FAILED'} {wall:.0f} s "
          f"{' '.join(cmd)}", file=log, flush=True)
    if not ok:
        print(res.stderr[-2000:], file=log, flush=True)
        return
    with open(folder + ".wall", "w") as f:
        f.write(f"{wall:.1f}\n")


def last_stratification(folder):
    """(Delta, its standard error or None, shell enrichment, its error, final radius)."""
    with open(os.path.join(folder, "summary.json")) as f:
        s = json.load(f)
    st = s["stratification"]
    if isinstance(st, list):  # the theory: one entry per profile time, no errors
        last = st[-1]
        return last["radius_difference"], None, None, None, last["radius"]
    d = st["radius_difference"]
    e = st["shell_enrichment"]
    return d["mean"], d["err"], e["mean"], e["err"], None


def analyse(args):
    rows = []
    eq = {}
    for phi0 in args.phi0:
        f = folder_of(args.runs, "eq", EQ_PECLET, phi0)
        if completed(f):
            eq[phi0] = last_stratification(f)[0]
    for method in args.methods:
        if method == "eq":
            continue
        for pe, phi0 in points(args, method):
            f = folder_of(args.runs, method, pe, phi0)
            if not completed(f):
                continue
            delta, err, shell, shell_err, _ = last_stratification(f)
            wall = None
            if os.path.exists(f + ".wall"):
                with open(f + ".wall") as w:
                    wall = float(w.read())
            base = eq.get(phi0)
            rows.append({
                "method": method, "phi0": phi0, "phi_s": phi0 / 2, "pe_s": pe,
                "pe_phi_s": pe * phi0 / 2, "delta": delta, "delta_err": err,
                "delta_eq": base, "S": None if base is None else delta - base,
                "shell_enrichment": shell, "shell_err": shell_err, "wall_s": wall,
            })
    return rows, eq


def thresholds(rows, methods, phi0s):
    """Pe_s phi_s where S turns positive, per method and phi0 (log-linear interpolation)."""
    out = []
    for method in methods:
        for phi0 in phi0s:
            pts = sorted((r["pe_s"], r["S"]) for r in rows
                         if r["method"] == method and r["phi0"] == phi0 and r["S"] is not None)
            if not pts:
                continue
            value, note = None, ""
            if pts[0][1] > 0:
                note = f"small-on-top at every Pe_s: below {pts[0][0] * phi0 / 2:g}"
            elif all(s <= 0 for _, s in pts):
                note = f"never small-on-top: above {pts[-1][0] * phi0 / 2:g}"
            else:
                for (p0, s0), (p1, s1) in zip(pts, pts[1:]):
                    if s0 <= 0 < s1:
                        x = math.log(p0) + (math.log(p1) - math.log(p0)) * (-s0) / (s1 - s0)
                        value = math.exp(x) * phi0 / 2
                        break
            out.append({"method": method, "phi0": phi0, "threshold_pe_phi_s": value, "note": note})
    return out


def write_csv(path, rows):
    if not rows:
        return
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})


def figures(rows, methods, img):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    shown = [m for m in methods if m != "eq" and any(r["method"] == m for r in rows)]
    if not shown or all(r["S"] is None for r in rows):
        return
    smax = max(abs(r["S"]) for r in rows if r["S"] is not None) or 1.0
    norm = TwoSlopeNorm(vmin=-smax, vcenter=0.0, vmax=smax)
    fig, axes = plt.subplots(1, len(shown), figsize=(3.6 * len(shown) + 1.0, 3.6),
                             sharey=True, squeeze=False)
    for ax, m in zip(axes[0], shown):
        rs = [r for r in rows if r["method"] == m and r["S"] is not None]
        sc = ax.scatter([r["pe_s"] for r in rs], [r["phi_s"] for r in rs],
                        c=[r["S"] for r in rs], cmap="coolwarm", norm=norm, s=140,
                        edgecolors="k")
        pe = [0.5, 300]
        ax.plot(pe, [1 / ALPHA**2 / p for p in pe], "k--", lw=1,
                label=r"$Pe_s\phi_s = 1/\alpha^2$")
        ax.plot(pe, [1 / p for p in pe], "k:", lw=1, label=r"$Pe_s\phi_s = 1$")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(0.6, 200)
        ax.set_ylim(0.015, 0.15)
        ax.set_title(m)
        ax.set_xlabel(r"$Pe_s$")
    axes[0][0].set_ylabel(r"$\phi_s$ (initial)")
    axes[0][0].legend(fontsize=7, loc="lower left")
    fig.colorbar(sc, ax=axes[0].tolist(),
                 label=r"$S = \Delta - \Delta_{eq}$ ($>0$: small-on-top)")
    fig.savefig(os.path.join(img, "stratification-diagram.png"), dpi=130)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    marks = {0.05: "o", 0.1: "s", 0.2: "^"}
    for k, m in enumerate(shown):
        for phi0 in sorted({r["phi0"] for r in rows}):
            rs = sorted((r for r in rows if r["method"] == m and r["phi0"] == phi0
                         and r["S"] is not None), key=lambda r: r["pe_s"])
            if not rs:
                continue
            ax.errorbar([r["pe_phi_s"] for r in rs], [r["S"] for r in rs],
                        yerr=[r["delta_err"] or 0.0 for r in rs], color=f"C{k}",
                        marker=marks.get(phi0, "o"), ms=5, lw=1, capsize=2,
                        label=f"{m}, $\\phi_0$ = {phi0:g}")
    ax.axhline(0, color="k", lw=0.8)
    ax.axvline(1 / ALPHA**2, color="k", ls="--", lw=0.8)
    ax.axvline(1.0, color="k", ls=":", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel(r"$Pe_s \phi_s$")
    ax.set_ylabel(r"$S = \Delta - \Delta_{eq}$")
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(img, "stratification-vs-pephi.png"), dpi=130)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="target/release/colloidsim")
    ap.add_argument("--runs", required=True)
    ap.add_argument("--data", default="docs/data")
    ap.add_argument("--img", default="docs/img")
    ap.add_argument("--methods", default="eq,ddft-fd,ddft-rpy,bd-fd")
    ap.add_argument("--peclet", default="1,3,10,30,100")
    ap.add_argument("--phi0", default="0.05,0.1,0.2")
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--particles", type=int, default=900)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--analyse-only", action="store_true")
    args = ap.parse_args()
    args.methods = args.methods.split(",")
    args.peclet = [float(x) for x in args.peclet.split(",")]
    args.phi0 = [float(x) for x in args.phi0.split(",")]
    if not args.analyse_only:
        os.makedirs(args.runs, exist_ok=True)
        with open(os.path.join(args.runs, "log.txt"), "a") as log:
            for method in args.methods:
                for pe, phi0 in points(args, method):
                    run_point(args, method, pe, phi0, log)
    rows, eq = analyse(args)
    os.makedirs(args.data, exist_ok=True)
    os.makedirs(args.img, exist_ok=True)
    write_csv(os.path.join(args.data, "stratification_study.csv"), rows)
    th = thresholds(rows, [m for m in args.methods if m != "eq"], args.phi0)
    write_csv(os.path.join(args.data, "stratification_thresholds.csv"), th)
    figures(rows, args.methods, args.img)
    print("| method | phi0 | Pe_s | Pe_s phi_s | Delta | Delta_eq | S | wall (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        err = f" ± {r['delta_err']:.3f}" if r["delta_err"] is not None else ""
        fmt = lambda x: "n/a" if x is None else f"{x:.3f}"
        print(f"| {r['method']} | {r['phi0']:g} | {r['pe_s']:g} | {r['pe_phi_s']:.3g} | "
              f"{r['delta']:.3f}{err} | {fmt(r['delta_eq'])} | {fmt(r['S'])} | "
              f"{fmt(r['wall_s'])} |")
    for t in th:
        v = t["threshold_pe_phi_s"]
        print(f"threshold {t['method']} phi0={t['phi0']:g}: "
              f"{'%.3g' % v if v is not None else t['note']}")


if __name__ == "__main__":
    sys.exit(main())
