#!/usr/bin/env python3
"""Does hydrodynamics decide stratification? The study of issue 43 (docs/stratification.md).

A droplet of two hard-sphere sizes (size ratio alpha = d_l / d_s, equal volumes of small and large
spheres, examples/droplet/bidisperse-bd.toml scaled) dried at a small-sphere Peclet number Pe_s
from phi0 to phi = 0.5, on a grid of Pe_s and phi0 (phi_s = phi0 / 2), by each method:

  bd-fd      free-draining Brownian dynamics (droplet-bd), REPLICAS droplets per point
  bd-rpy     Brownian dynamics with the unequal-radius RPY mobility (direct free-space sums)
  ddft-fd    the binary White Bear FMT DDFT with free-draining fluxes (colloidsim theory)
  ddft-rpy   the same DDFT with the pairwise unequal-radius RPY flux (--hydrodynamics rpy)
             and the dilute pair correlation
  ddft-rpy-tk
             the same with the dense pair correlation (--pair trokhymchuk: Trokhymchuk's h
             scaled to each pair's contact distance and BMCSL contact value)
  eq         the binary FMT equilibrium reference: the DDFT dried at Pe_s = EQ_PECLET, slow
             enough that every profile is the static one at its radius
  mpcd-slip, mpcd-noslip
             droplet-mpcd (explicit SRD solvent, discrete-particle colloids of diameters 2 and
             4 cells, examples/droplet/bidisperse-mpcd.toml scaled) with a slip or no-slip
             boundary for the solvent at the moving interface; droplet-mpcd has no replicas, so
             each point runs REPLICAS seeds (folders seed1, seed2, ... of the point)

and any of them with `-k<stiffness>` appended (`bd-rpy-k500`): the same in an interface of that
stiffness (kT/d^2, d the small diameter) instead of the example's (100 kT/d^2; the MPCD
example's 100 kT/cell^2 = 400 kT/d^2 for the mpcd methods), to see whether the interface held
the colloids; `-hard` (`bd-fd-hard`, `bd-rpy-hard`, `mpcd-slip-hard`, `mpcd-noslip-hard`): a hard
wall instead (`interface.hard`, the limit of an infinitely stiff interface).

The measure is the difference of the species' mean centre distances over R, Delta =
<r>_s / R - <r>_l / R (colloidsim_analysis::stratification), at 50, 75 and 100 % of the drying
time. A mixed droplet has Delta > 0 already, because a small centre reaches (d_l - d_s) / 2
closer to the surface; so each run is compared with the uniform mixture at the same radius
(Delta_ideal: each species' centres distributed as exp(-beta V_k) in its own interface, no
correlations): S = Delta - Delta_ideal > 0 is small-on-top, S < 0 large-on-top. The threshold
of small-on-top is the Pe_s phi_s from which S stays positive (interpolated in log Pe_s between
grid points at each phi0). The binary FMT equilibrium at the same radius (Delta_eq, from the
`eq` runs) is the second reference: S_eq = Delta - Delta_eq says how far from equilibrium the
droplet is (at phi = 0.5 the equilibrium has the large spheres layered at the wall).

Each point is one folder RUNS/<method>/phi<phi0>-pe<Pe_s>; a folder whose summary.json says the
run completed (or the theory stopped) is skipped, so the script can be stopped and started
again.

Outputs: DATA/stratification_study.csv (one row per method, point and profile time, at 50, 75
and 100 % of the drying time: R, Delta and its standard error over the droplets, Delta_ideal,
S, Delta_eq, S_eq, the fraction of centres left beyond R at the end, wall seconds),
DATA/stratification_thresholds.csv, IMG/stratification-diagram-t075.png and -t100.png (S on the
Pe_s x phi_s plane per method, with the lines Pe_s phi_s = 1/alpha^2 and 1),
IMG/stratification-vs-pephi-t075.png and -t100.png (S against Pe_s phi_s), and a markdown table
on stdout; IMG/stratification-profiles-pe<Pe_s>-phi<phi0>.png (--profiles-at, default 30:0.2):
both species' profiles at the end, every method side by side. A droplet-bd run that ends with more than LEFT_BEHIND of its centres beyond
R (the interface left them behind: droplet-bd warns) did not compact; its end is drawn hollow
and left out of the thresholds. A theory run that stopped early (particles ejected through the
interface: the DDFT with the RPY flux and the dilute pair correlation does, as the paper's did)
is kept, and its profile times up to the stop are used. --tag is appended to every file name.

Usage (from the repository root):
  python3 scripts/stratification_study.py --bin target/release/colloidsim --runs /tmp/strat \\
      [--methods bd-fd,ddft-fd,ddft-rpy,eq] [--peclet 0.3,1,3,10,30,100] [--phi0 0.05,0.1,0.2] \\
      [--replicas 4] [--particles 900] [--threads 2] [--analyse-only] [--tag=-n450] \
      [--panels ddft-fd,bd-fd]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

# The size ratio d_l / d_s (--alpha).
ALPHA = 2.0
EQ_PECLET = 0.01
# The profile times compared (fractions of the drying time), and those drawn.
FRACTIONS = (0.5, 0.75, 1.0)
DRAWN = (0.75, 1.0)
# As droplet-bd's warning: a droplet with more of its centres beyond R at the end did not compact.
LEFT_BEHIND = 0.01
# Interfaces stiffer than this (kT/d^2) get a shorter time step than droplet-bd's default.
STIFF = 500.0
BASE = "examples/droplet/bidisperse-bd.toml"
MPCD_BASE = "examples/droplet/bidisperse-mpcd.toml"
# The small colloids of the MPCD droplet are 2 cells across: a stiffness in kT/d^2 is 4 times
# that in kT/cell^2.
MPCD_CELLS_PER_D = 2.0
MPCD_BOUNDARY = {"mpcd-slip": "slip", "mpcd-noslip": "no-slip"}
# The MPCD example's interface, 100 kT/cell^2, in kT/d^2.
MPCD_BASE_STIFFNESS = 100.0 * MPCD_CELLS_PER_D**2
DDFT_DX = "0.05"


def split(method):
    """A method name and its interface stiffness: `bd-rpy-k500` is bd-rpy in an interface of
    500 kT/d^2 (None: the example's 100; math.inf: `bd-fd-hard`, a hard wall)."""
    if method.endswith("-hard"):
        return method[: -len("-hard")], math.inf
    base, _, k = method.rpartition("-k")
    return (base, float(k)) if base and k.isdigit() else (method, None)


def large_count(particles):
    """Large spheres among `particles` for equal volumes of both sizes (1 per alpha^3 small)."""
    return int(particles // (1 + ALPHA**3))


def is_mpcd(method):
    return split(method)[0] in MPCD_BOUNDARY


def rewritten(path, new):
    """The scenario file at `path` with the line of each key of `new` replaced by
    `key = value` (a key `"[section] key"` only in that section; None leaves the line)."""
    out, section = [], ""
    with open(path) as f:
        for line in f.read().splitlines():
            if line.startswith("["):
                section = line
            key = line.split("=")[0].strip()
            value = new.get(f"{section} {key}", new.get(key))
            out.append(line if value is None or line.startswith(("[", "#")) else f"{key} = {value}")
    return "\n".join(out) + "\n"


def mpcd_scenario(pe, phi0, method, particles, seed):
    """The MPCD example with this Peclet number, initial volume fraction, number of colloids
    (alpha^3 small per large), boundary, seed and interface stiffness, dried to phi = 0.5 as the BD
    droplets, with profiles at the study's times."""
    method, stiffness = split(method)
    large = large_count(particles)
    text = rewritten(MPCD_BASE, {
        "peclet": pe, "phi0": phi0, "seed": seed, "boundary": f'"{MPCD_BOUNDARY[method]}"',
        "particles": particles, "diameters": f"[{MPCD_CELLS_PER_D}, {MPCD_CELLS_PER_D * ALPHA}]",
        "counts": f"[{particles - large}, {large}]", "final_volume_fraction": 0.5,
        "stiffness": None if stiffness in (None, math.inf) else stiffness / MPCD_CELLS_PER_D**2,
        "[observe.profile] bins": 20,
        "[observe.profile] fractions": "[0.0, 0.25, 0.5, 0.75, 1.0]",
    })
    if stiffness == math.inf:
        # A hard wall in place of the example's spring (its stiffness and range lines).
        text = hard_wall(text)
    return text


def hard_wall(text):
    """A scenario's `[interface]` spring (its stiffness and range lines) replaced by
    `hard = true`."""
    out = []
    for line in text.split("\n"):
        if line.startswith("stiffness"):
            out.append("hard = true")
        elif not line.startswith("range"):
            out.append(line)
    return "\n".join(out)


def scenario(pe, phi0, replicas, method, particles=900):
    """The example with this Peclet number, initial volume fraction, replicas, mobility,
    interface stiffness, number of spheres and size ratio ALPHA (alpha^3 small per large:
    equal volumes)."""
    method, stiffness = split(method)
    large = large_count(particles)
    text = rewritten(BASE, {
        "peclet": pe, "phi0": phi0, "replicas": replicas, "particles": particles,
        "diameters": f"[1.0, {ALPHA}]", "counts": f"[{particles - large}, {large}]",
        "stiffness": None if stiffness == math.inf else stiffness,
    })
    if stiffness == math.inf:
        # A hard wall in place of the spring (the example's stiffness line), default step.
        text = hard_wall(text)
    elif stiffness is not None and stiffness > STIFF:
        # The default step 2e-4 d^2/D0 keeps k D0 dt / kT at 0.1 up to STIFF kT/d^2; above,
        # a step that keeps it there (D0 = kT / (3 pi eta d) with kT = eta = d = 1).
        text += f"\n[run]\ndt = {0.1 / stiffness * 3 * math.pi:.6g}\n"
    if method == "bd-rpy":
        text += '\n[hydrodynamics]\nmodel = "rpy"\nmethod = "direct"\n'
    return text


def seeds_of(folder):
    """The seed folders of an MPCD point (its droplets), in order; [] for other methods."""
    if not os.path.isdir(folder):
        return []
    names = [n for n in os.listdir(folder) if n.startswith("seed") and n[4:].isdigit()]
    return [os.path.join(folder, n) for n in sorted(names, key=lambda n: int(n[4:]))]


def state(folder, replicas=None):
    """'done' (completed), 'stopped' (the theory stopped early, e.g. on ejection, with the
    profiles up to then: kept and used up to where it got) or None (run it). An MPCD point is
    done when `replicas` of its seeds are (any number of them when `replicas` is None)."""
    seeds = seeds_of(folder)
    if seeds:
        done = [f for f in seeds if state(f) == "done"]
        return "done" if done and (replicas is None or len(done) >= replicas) else None
    try:
        with open(os.path.join(folder, "summary.json")) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return None
    if "completed" in s:  # colloidsim run
        return "done" if s["completed"] is True else None
    return {"ok": "done", "failed": "stopped", "unphysical": "stopped"}.get(s.get("status"))


def points(args, method):
    if method == "eq":
        return [(EQ_PECLET, phi0) for phi0 in args.phi0]
    return [(pe, phi0) for phi0 in args.phi0 for pe in args.peclet]


def folder_of(runs, method, pe, phi0):
    return os.path.join(runs, method, f"phi{phi0:g}-pe{pe:g}")


def run_command(cmd, folder, log, what):
    """Runs one colloidsim command into `folder`, logs it and records its wall time."""
    t0 = time.time()
    res = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    got = state(folder)
    print(f"{what}: {got or 'FAILED'} {wall:.0f} s {' '.join(cmd)}", file=log, flush=True)
    if got != "done":
        print(res.stderr[-2000:], file=log, flush=True)
    if got is None:
        return
    with open(folder + ".wall", "w") as f:
        f.write(f"{wall:.1f}\n")


def run_point(args, method, pe, phi0, log):
    folder = folder_of(args.runs, method, pe, phi0)
    if is_mpcd(method):
        for seed in range(1, args.replicas + 1):
            one = os.path.join(folder, f"seed{seed}")
            if state(one):
                continue
            os.makedirs(folder, exist_ok=True)
            with open(one + ".toml", "w") as f:
                f.write(mpcd_scenario(pe, phi0, method, args.particles, seed))
            cmd = [args.bin, "run", one + ".toml", "--out", one, "--force", "--quiet",
                   "--threads", str(args.threads)]
            run_command(cmd, one, log, f"{method} phi0={phi0} Pe={pe} seed={seed}")
        return
    if state(folder):
        return
    os.makedirs(os.path.dirname(folder), exist_ok=True)
    scen = folder + ".toml"
    with open(scen, "w") as f:
        f.write(scenario(pe, phi0, args.replicas, method, args.particles))
    if split(method)[0].startswith("bd"):
        cmd = [args.bin, "run", scen, "--out", folder, "--force", "--quiet",
               "--threads", str(args.threads)]
    else:
        cmd = [args.bin, "theory", scen, "--out", folder, "--force", "--dx", DDFT_DX]
        if split(method)[0] == "ddft-rpy":
            cmd += ["--hydrodynamics", "rpy"]
        elif split(method)[0] == "ddft-rpy-tk":
            cmd += ["--hydrodynamics", "rpy", "--pair", "trokhymchuk"]
    run_command(cmd, folder, log, f"{method} phi0={phi0} Pe={pe}")


def mpcd_parameters(p):
    """droplet-mpcd's parameters in the names droplet-bd's have (ideal_delta reads them)."""
    k, rng, offset = p["interface"]
    return {"stiffness": k, "range": rng, "offset": offset, "kt": p["solvent"]["srd"]["kt"],
            "diameter": p["diameter"], "species": p["species"], "particles": p["particles"],
            "hard_interface": p.get("hard_interface", False), "replicas": 1}


def measures(folder):
    """{fraction: (Delta, its standard error over the droplets or None, R)} at each profile
    time the run reached (stratification.csv of colloidsim run, summary.json of the theory),
    and the run's parameters. An MPCD point: the mean over its seeds (the standard error from
    their scatter), its parameters with `replicas` the number of seeds."""
    seeds = [f for f in seeds_of(folder) if state(f) == "done"]
    if seeds:
        runs = [measures(f) for f in seeds]
        params = dict(runs[0][1], replicas=len(runs))
        out = {}
        for fraction in runs[0][0]:
            got = [r[0][fraction] for r in runs if r[0].get(fraction, (None,))[0] is not None]
            if not got:
                continue
            d = [g[0] for g in got]
            mean = sum(d) / len(d)
            err = (math.sqrt(sum((x - mean) ** 2 for x in d) / (len(d) - 1) / len(d))
                   if len(d) > 1 else None)
            out[fraction] = (mean, err, got[0][2])
        return out, params
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    path = os.path.join(folder, "stratification.csv")
    if os.path.exists(path):
        with open(path) as f:
            rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
        head, out = rows[0], {}
        i, j = head.index("radius_difference"), head.index("radius_difference_err")
        num = lambda x: float(x) if x not in ("", "null", "NaN", "nan") else None
        for r in rows[1:]:
            out[round(float(r[0]), 6)] = (num(r[i]), num(r[j]), float(r[head.index("R")]))
        p = summary["parameters"]
        return out, (mpcd_parameters(p) if summary.get("method") == "droplet-mpcd" else p)
    st = summary["stratification"]
    out = {round(x["fraction"], 6): (x["radius_difference"], None, x["radius"]) for x in st}
    return out, summary["parameters"]


def ideal_delta(p, radius):
    """Delta of the uniform (ideal) mixture at droplet radius R: each species' centres
    distributed as exp(-beta V_k(r)) in its own interface (wall at R + offset - (d_k - d)/2,
    harmonic of stiffness k over `range`, linear beyond), no correlations. A mixed droplet has
    Delta > 0 only because small centres reach (d_l - d_s)/2 closer to the surface."""
    kt = p.get("kt", 1.0)
    k, rng = p["stiffness"] / kt, p["range"]
    hard = p.get("hard_interface", False)
    diam = p["species"]["diameters"]
    means = []
    for d in diam:
        wall = radius + p["offset"] - 0.5 * (d - p["diameter"])
        # A hard wall: uniform up to the wall (the integral ends there).
        n, h = 4000, (wall if hard else wall + rng + 60.0 / (k * rng)) / 4000
        num = den = 0.0
        for i in range(n):
            r = (i + 0.5) * h
            s_ = r - wall
            v = 0.0 if s_ < 0 else (0.5 * k * s_ * s_ if s_ < rng else
                                    0.5 * k * rng * rng + k * rng * (s_ - rng))
            w = r * r * math.exp(-v)
            num += r * w
            den += w
        means.append(num / den / radius)
    small, large = diam.index(min(diam)), diam.index(max(diam))
    return means[small] - means[large]


def analyse(args):
    """One row per method, point and profile time in FRACTIONS: Delta, S_eq = Delta - Delta_eq
    (the binary FMT equilibrium at the same R) and S = Delta - Delta_ideal (the uniform mixture
    at the same R: the measure of small-on-top)."""
    rows = []
    eq = {}
    for phi0 in args.phi0:
        f = folder_of(args.runs, "eq", EQ_PECLET, phi0)
        if state(f) == "done":
            eq[phi0] = measures(f)[0]
    for method in args.methods:
        if method == "eq":
            continue
        for pe, phi0 in points(args, method):
            f = folder_of(args.runs, method, pe, phi0)
            if not state(f):
                continue
            got, params = measures(f)
            wall, beyond = run_costs(f)
            left = None if beyond is None else beyond / (params["particles"] * params["replicas"])
            for fraction, (delta, err, radius) in sorted(got.items()):
                if fraction not in FRACTIONS or delta is None:
                    continue
                base = eq.get(phi0, {}).get(fraction, (None,))[0]
                ideal = ideal_delta(params, radius)
                rows.append({
                    "method": method, "alpha": ALPHA, "fraction": fraction, "phi0": phi0,
                    "phi_s": phi0 / 2,
                    "pe_s": pe, "pe_phi_s": pe * phi0 / 2, "R": radius, "delta": delta,
                    "delta_err": err, "delta_ideal": ideal, "S": delta - ideal,
                    "delta_eq": base, "S_eq": None if base is None else delta - base,
                    "left_behind": left if fraction == 1.0 else None, "wall_s": wall,
                })
    return rows, eq


def run_costs(folder):
    """The wall seconds of a point (summed over an MPCD point's seeds) and the centres beyond R
    at its end (summed over the droplets; None where the run does not say)."""
    wall = beyond = None
    for f in [g for g in seeds_of(folder) if state(g) == "done"] or [folder]:
        if os.path.exists(f + ".wall"):
            with open(f + ".wall") as w:
                wall = (wall or 0.0) + float(w.read())
        with open(os.path.join(f, "summary.json")) as fs:
            s = json.load(fs)
        b = s.get("centres_beyond_R_at_end", (s.get("colloids") or {}).get("centres_beyond_R_at_end"))
        if b is not None:
            beyond = (beyond or 0) + b
    return wall, beyond


def held_badly(row):
    """More than LEFT_BEHIND of the centres beyond R at the end: the interface did not hold
    the colloids (droplet-bd warns), so the droplet did not compact and its end is no measure."""
    return (row["left_behind"] or 0.0) > LEFT_BEHIND


def crossing(pts, phi0):
    """Pe_s phi_s from which S stays positive along (Pe_s, S) points sorted by Pe_s:
    interpolated in log Pe_s after the last point with S <= 0; or a bound with the reason."""
    if not pts:
        return None, "no points"
    if all(s > 0 for _, s in pts):
        return None, f"small-on-top at every Pe_s: below {pts[0][0] * phi0 / 2:g}"
    if pts[-1][1] <= 0:
        return None, f"not small-on-top at the largest Pe_s: above {pts[-1][0] * phi0 / 2:g}"
    k = max(i for i, (_, s) in enumerate(pts) if s <= 0)
    (p0, s0), (p1, s1) = pts[k], pts[k + 1]
    x = math.log(p0) + (math.log(p1) - math.log(p0)) * (-s0) / (s1 - s0)
    return math.exp(x) * phi0 / 2, ""


def thresholds(rows, methods, phi0s):
    """Pe_s phi_s from which S stays positive, per method, profile time and phi0, with the range
    that S - err and S + err give (the crossing's uncertainty from the droplets' scatter)."""
    out = []
    for method in methods:
        for fraction in FRACTIONS:
            for phi0 in phi0s:
                sel = sorted((r for r in rows
                              if r["method"] == method and r["phi0"] == phi0
                              and r["fraction"] == fraction and r["S"] is not None
                              and not held_badly(r)), key=lambda r: r["pe_s"])
                if not sel:
                    continue
                value, note = crossing([(r["pe_s"], r["S"]) for r in sel], phi0)
                err = [r["delta_err"] or 0.0 for r in sel]
                late, _ = crossing([(r["pe_s"], r["S"] - e) for r, e in zip(sel, err)], phi0)
                early, _ = crossing([(r["pe_s"], r["S"] + e) for r, e in zip(sel, err)], phi0)
                out.append({"method": method, "fraction": fraction, "phi0": phi0,
                            "threshold_pe_phi_s": value, "from": early, "to": late,
                            "note": note})
    return out


def write_csv(path, rows):
    if not rows:
        return
    # The columns of every row, in the order first seen (data files of older versions lack
    # `alpha`: their rows leave it empty, the default size ratio).
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})


def figures(all_rows, methods, img, fraction, tag=""):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    rows = [r for r in all_rows if r["fraction"] == fraction and r["method"] in methods]
    when = "end of drying" if fraction == 1.0 else f"{fraction:.0%} of the drying time"
    tag = f"t{int(round(100 * fraction)):03d}{tag}"
    shown = [m for m in methods if m != "eq" and any(r["method"] == m for r in rows)]
    if not shown or all(r["S"] is None for r in rows):
        return
    smax = max((abs(r["S"]) for r in rows if r["S"] is not None and not held_badly(r)),
               default=0.0) or 1.0
    norm = TwoSlopeNorm(vmin=-smax, vcenter=0.0, vmax=smax)
    fig, axes = plt.subplots(1, len(shown), figsize=(3.4 * len(shown) + 1.4, 3.6),
                             sharey=True, squeeze=False, layout="constrained")
    for ax, m in zip(axes[0], shown):
        rs = [r for r in rows if r["method"] == m and r["S"] is not None]
        good = [r for r in rs if not held_badly(r)]
        bad = [r for r in rs if held_badly(r)]
        sc = ax.scatter([r["pe_s"] for r in good], [r["phi_s"] for r in good],
                        c=[r["S"] for r in good], cmap="coolwarm", norm=norm, s=140,
                        edgecolors="k")
        if bad:
            ax.scatter([r["pe_s"] for r in bad], [r["phi_s"] for r in bad], s=140,
                       facecolors="none", edgecolors="0.5", linestyles="--",
                       label="interface did not hold")
        pe = [0.1, 300]
        ax.plot(pe, [1 / ALPHA**2 / p for p in pe], "k--", lw=1,
                label=r"$Pe_s\phi_s = 1/\alpha^2$")
        ax.plot(pe, [1 / p for p in pe], "k:", lw=1, label=r"$Pe_s\phi_s = 1$")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(0.2, 200)
        ax.set_ylim(0.015, 0.15)
        ax.set_xticks([0.3, 1, 3, 10, 30, 100], ["0.3", "1", "3", "10", "30", "100"])
        ax.set_yticks([0.025, 0.05, 0.1], ["0.025", "0.05", "0.1"])
        ax.minorticks_off()
        ax.set_title(f"{m} ({when})", fontsize=9)
        ax.set_xlabel(r"$Pe_s$")
    axes[0][0].set_ylabel(r"$\phi_s$ (initial)")
    for ax in axes[0]:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="lower left")
    fig.colorbar(sc, ax=axes[0].tolist(),
                 label=r"$S = \Delta - \Delta_{ideal}$ ($>0$: small-on-top)")
    fig.savefig(os.path.join(img, f"stratification-diagram-{tag}.png"), dpi=130)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8.0, 4.0), layout="constrained")
    marks = {0.05: "o", 0.1: "s", 0.2: "^"}
    for k, m in enumerate(shown):
        for phi0 in sorted({r["phi0"] for r in rows}):
            rs = sorted((r for r in rows if r["method"] == m and r["phi0"] == phi0
                         and r["S"] is not None and not held_badly(r)),
                        key=lambda r: r["pe_s"])
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
    ax.set_ylabel(r"$S = \Delta - \Delta_{ideal}$ ($>0$: small-on-top)")
    ax.set_title(when, fontsize=9)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.savefig(os.path.join(img, f"stratification-vs-pephi-{tag}.png"), dpi=130)
    plt.close(fig)


def read_rows(paths):
    """The rows of the data files `paths` (numbers as numbers, empty as None)."""
    def value(k, v):
        if k == "method":
            return v
        return float(v) if v != "" else None
    rows = []
    for p in paths:
        with open(p) as f:
            rows += [{k: value(k, v) for k, v in r.items()} for r in csv.DictReader(f)]
    return rows


def from_csv(paths, methods):
    """The rows of `methods` in the data files `paths`, in the order of `methods`, each
    method's by phi0, Pe_s and time (the order of a run's own data file); a point found in
    more than one file is taken from the last."""
    point = lambda r: (r["method"], r["phi0"], r["pe_s"], r["fraction"])
    latest = {point(r): r for r in read_rows(paths)}
    # The equilibrium reference depends on the droplet alone (phi0 and the time): rows written
    # without it (runs analysed without `eq`) take it from the rows that have it.
    reference = {(r["phi0"], r["fraction"], r.get("alpha") or 2.0): r["delta_eq"]
                 for r in latest.values() if r.get("delta_eq") is not None}
    for r in latest.values():
        eq = reference.get((r["phi0"], r["fraction"], r.get("alpha") or 2.0))
        if r.get("delta_eq") is None and eq is not None:
            r["delta_eq"], r["S_eq"] = eq, r["delta"] - eq
    return [r for m in methods
            for r in sorted((r for r in latest.values() if r["method"] == m),
                            key=lambda r: (r["phi0"], r["pe_s"], r["fraction"]))]


def alpha_figure(paths, path, fraction=1.0, methods=None):
    """S against Pe_s at each phi0 for the data files of several size ratios (their `alpha`
    column; the files of --tag runs), of `methods` only when given: does the threshold move as
    1 / alpha^2?"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in read_rows(paths) if r["fraction"] == fraction
            and (methods is None or r["method"] in methods)]
    fig, ax = plt.subplots(figsize=(7.5, 4.0), layout="constrained")
    marks = {0.05: "o", 0.1: "s", 0.2: "^"}
    groups = sorted({(r["method"], (r.get("alpha") or 2.0)) for r in rows})
    for k, (m, alpha) in enumerate(groups):
        for phi0 in sorted({r["phi0"] for r in rows}):
            rs = sorted((r for r in rows if r["method"] == m
                         and (r.get("alpha") or 2.0) == alpha
                         and r["phi0"] == phi0), key=lambda r: r["pe_s"])
            if not rs:
                continue
            ax.errorbar([r["pe_s"] for r in rs], [r["S"] for r in rs],
                        yerr=[(r["delta_err"] or 0.0) for r in rs], color=f"C{k}",
                        marker=marks.get(phi0, "o"), ms=5, lw=1, capsize=2,
                        label=f"{m}, $\\alpha$ = {alpha:g}, $\\phi_0$ = {phi0:g}")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel(r"$Pe_s$")
    ax.set_ylabel(r"$S = \Delta - \Delta_{ideal}$ ($>0$: small-on-top)")
    when = "end of drying" if fraction == 1.0 else f"{fraction:.0%} of the drying time"
    ax.set_title(f"size ratios side by side ({when})", fontsize=9)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.savefig(path, dpi=130)
    plt.close(fig)


def stiffness_figure(paths, path, peclets, base_stiffness, methods=None, fraction=1.0):
    """S against the interface's stiffness, one panel per Pe_s in `peclets`, a line per method
    and phi0, from the data files `paths`: methods `bd-fd`, `bd-rpy`, `mpcd-slip`,
    `mpcd-noslip` with a `-k<stiffness>` or `-hard` suffix (none: the example's, `base_stiffness`
    for BD, MPCD_BASE_STIFFNESS for MPCD; `methods`: those to draw, default the two BD ones).
    The hard wall is drawn right of the stiffest spring: does S reach its hard-wall limit?"""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in read_rows(paths) if r["fraction"] == fraction]
    kinds = {"bd-fd": ("free draining", "C0"), "bd-rpy": ("RPY", "C3"),
             "mpcd-slip": ("MPCD slip", "C2"), "mpcd-noslip": ("MPCD no-slip", "C4")}
    kinds = {b: kinds[b] for b in methods or ["bd-fd", "bd-rpy"]}
    # The example's stiffness of each method (the MPCD example's 100 kT/cell^2 in kT/d^2).
    base_of = lambda b: MPCD_BASE_STIFFNESS if b in MPCD_BOUNDARY else base_stiffness
    finite = [base_of(b) if k is None else k for r in rows for b, k in [split(r["method"])]
              if b in kinds and k != math.inf]
    hard_x = 2.5 * max(finite)
    stiffness = lambda b, k: base_of(b) if k is None else (hard_x if k == math.inf else k)
    marks = {0.05: "o", 0.1: "s", 0.2: "^"}
    fig, axes = plt.subplots(1, len(peclets), figsize=(4.2 * len(peclets), 3.6),
                             layout="constrained", sharey=True, squeeze=False)
    for ax, pe in zip(axes[0], peclets):
        for base, (label, colour) in kinds.items():
            for phi0 in sorted({r["phi0"] for r in rows}):
                pts = sorted((stiffness(b, k), r["S"], r["delta_err"] or 0.0)
                             for r in rows for b, k in [split(r["method"])]
                             if b == base and r["pe_s"] == pe and r["phi0"] == phi0)
                if not pts:
                    continue
                x, y, e = zip(*pts)
                ax.errorbar(x, y, yerr=e, color=colour, marker=marks.get(phi0, "o"), ms=5,
                            lw=1, capsize=2, label=f"{label}, $\\phi_s$ = {phi0 / 2:g}")
        ax.axhline(0, color="k", lw=0.8)
        ax.axvline(math.sqrt(max(finite) * hard_x), color="0.6", lw=0.8, ls=":")
        ax.set_xscale("log")
        ticks = sorted(set(finite)) + [hard_x]
        ax.set_xticks(ticks, [f"{t:g}" for t in ticks[:-1]] + ["hard"], fontsize=7,
                      rotation=90)
        ax.minorticks_off()
        ax.set_xlabel(r"interface stiffness ($kT/d^2$)")
        ax.set_title(f"$Pe_s$ = {pe:g}", fontsize=9)
    axes[0][0].set_ylabel(r"$S = \Delta - \Delta_{ideal}$ ($>0$: small-on-top)")
    axes[0][-1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.savefig(path, dpi=130)
    plt.close(fig)


# The profiles are drawn from this r / R on.
X_FROM = 0.4


def profile_figure(args, methods, pe, phi0, fraction, path):
    """Both species' volume-fraction profiles against r/R at one point of the grid, every
    method side by side (species_profile_<f>.csv of each run, errors where there are)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.6), sharey=True, layout="constrained")
    name = f"species_profile_{fraction:.2f}.csv"
    drawn, top = False, 0.0
    for k, method in enumerate(m for m in methods if m != "eq"):
        point = folder_of(args.runs, method, pe, phi0)
        if not state(point):
            continue
        # An MPCD point's droplets are its seeds: their mean, the error from their scatter.
        files = [os.path.join(f, name) for f in seeds_of(point) if state(f) == "done"]
        files = [f for f in files or [os.path.join(point, name)] if os.path.exists(f)]
        runs = []
        for f in files:
            with open(f) as fh:
                runs.append([r for r in csv.DictReader(fh)])
        radius = measures(point)[0].get(round(fraction, 6), (0, 0, None))[2]
        if not runs or not runs[0] or not radius:
            continue
        x = [float(r["r"]) / radius for r in runs[0]]
        for ax, sp in zip(axes, ("A", "B")):
            if len(runs) > 1:
                cols = list(zip(*[[float(r[f"rho_v_{sp}"]) for r in rs] for rs in runs]))
                y = [sum(c) / len(c) for c in cols]
                e = [math.sqrt(sum((v - m) ** 2 for v in c) / (len(c) - 1) / len(c))
                     for c, m in zip(cols, y)]
            else:
                y = [float(r[f"rho_v_{sp}"]) for r in runs[0]]
                e = [float(r[f"err_{sp}"]) if r.get(f"err_{sp}") not in (None, "") else 0.0
                     for r in runs[0]]
            ax.errorbar(x, y, yerr=e, color=f"C{k}", lw=1.2, capsize=1.5, label=method)
            top = max([top] + [a + b for xi, a, b in zip(x, y, e) if xi >= X_FROM])
            drawn = True
    if not drawn:
        plt.close(fig)
        return
    for ax, what in zip(axes, ("small spheres (A, d)", f"large spheres (B, {ALPHA:g}d)")):
        ax.set_title(f"{what}: Pe_s = {pe:g}, phi0 = {phi0:g}, t = {fraction:.0%}", fontsize=9)
        ax.set_xlabel("r / R(t)")
        # The inner shells hold a sphere or two: their profile is noise.
        ax.set_xlim(X_FROM, 1.0)
        ax.set_ylim(0.0, 1.05 * top)
    # A histogram of centres times the sphere's volume (not the sphere-shell overlap): it
    # exceeds close packing in a shell thinner than the sphere where the centres layer.
    axes[0].set_ylabel("centre density x sphere volume")
    axes[0].legend(fontsize=8)
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main():
    global ALPHA
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="target/release/colloidsim")
    ap.add_argument("--runs", required=True)
    ap.add_argument("--data", default="docs/data")
    ap.add_argument("--img", default="docs/img")
    ap.add_argument("--methods", default="eq,ddft-fd,ddft-rpy,bd-fd")
    ap.add_argument("--peclet", default="0.3,1,3,10,30,100")
    ap.add_argument("--phi0", default="0.05,0.1,0.2")
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--particles", type=int, default=900)
    ap.add_argument("--alpha", type=float, default=2.0, help="size ratio d_l / d_s")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--analyse-only", action="store_true")
    ap.add_argument("--tag", default="", help="appended to the names of the data and figures")
    ap.add_argument("--panels", help="the methods the figures show (default: --methods)")
    ap.add_argument("--drawn", default=",".join(f"{f:g}" for f in DRAWN), metavar="F,...",
                    help="the fractions of the drying time whose diagrams are drawn (of 0.5, "
                         "0.75, 1)")
    ap.add_argument("--profiles-at", default="30:0.2", metavar="PE:PHI0,...",
                    help="the grid points whose profiles are drawn method by method")
    ap.add_argument("--compare-alpha", metavar="CSV,CSV,...",
                    help="only draw IMG/stratification-alpha<tag>.png from these data files")
    ap.add_argument("--from-csv", metavar="CSV,...",
                    help="take the rows of --methods from these data files (written by earlier "
                         "invocations) instead of the run folders: the combined data file, "
                         "thresholds and diagrams without the runs (no profile figures)")
    ap.add_argument("--compare-methods", metavar="METHOD,...",
                    help="with --compare-alpha: draw these methods only (default: all); with "
                         "--compare-stiffness: these of bd-fd, bd-rpy, mpcd-slip, mpcd-noslip "
                         "(default: the first two)")
    ap.add_argument("--compare-stiffness", metavar="CSV,CSV,...",
                    help="only draw IMG/stratification-stiffness<tag>.png from these data files: "
                         "S against the interface's stiffness at each --peclet")
    ap.add_argument("--base-stiffness", type=float, default=100.0,
                    help="with --compare-stiffness: the stiffness of methods without -k")
    args = ap.parse_args()
    ALPHA = args.alpha
    if args.compare_stiffness:
        os.makedirs(args.img, exist_ok=True)
        stiffness_figure(args.compare_stiffness.split(","),
                         os.path.join(args.img, f"stratification-stiffness{args.tag}.png"),
                         [float(x) for x in args.peclet.split(",")], args.base_stiffness,
                         methods=args.compare_methods and args.compare_methods.split(","))
        return
    if args.compare_alpha:
        alpha_figure(args.compare_alpha.split(","),
                     os.path.join(args.img, f"stratification-alpha{args.tag}.png"),
                     methods=args.compare_methods and args.compare_methods.split(","))
        return
    args.methods = args.methods.split(",")
    args.peclet = [float(x) for x in args.peclet.split(",")]
    args.phi0 = [float(x) for x in args.phi0.split(",")]
    if not args.analyse_only and not args.from_csv:
        os.makedirs(args.runs, exist_ok=True)
        with open(os.path.join(args.runs, "log.txt"), "a") as log:
            for method in args.methods:
                for pe, phi0 in points(args, method):
                    run_point(args, method, pe, phi0, log)
    rows = from_csv(args.from_csv.split(","), args.methods) if args.from_csv else analyse(args)[0]
    os.makedirs(args.data, exist_ok=True)
    os.makedirs(args.img, exist_ok=True)
    write_csv(os.path.join(args.data, f"stratification_study{args.tag}.csv"), rows)
    th = thresholds(rows, [m for m in args.methods if m != "eq"], args.phi0)
    write_csv(os.path.join(args.data, f"stratification_thresholds{args.tag}.csv"), th)
    shown = args.panels.split(",") if args.panels else args.methods
    for fraction in (float(f) for f in args.drawn.split(",")):
        figures(rows, shown, args.img, fraction, args.tag)
    for pe, phi0 in (map(float, x.split(":")) for x in args.profiles_at.split(",")
                     if not args.from_csv):
        profile_figure(args, shown, pe, phi0, 1.0, os.path.join(
            args.img, f"stratification-profiles-pe{pe:g}-phi{phi0:g}{args.tag}.png"))
    print("| method | t/t_end | phi0 | Pe_s | Pe_s phi_s | Delta | Delta_ideal | S | Delta_eq | "
          "S_eq | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        err = f" ± {r['delta_err']:.3f}" if r["delta_err"] is not None else ""
        fmt = lambda x: "n/a" if x is None else f"{x:.3f}"
        print(f"| {r['method']} | {r['fraction']:g} | {r['phi0']:g} | {r['pe_s']:g} | "
              f"{r['pe_phi_s']:.3g} | "
              f"{r['delta']:.3f}{err} | {r['delta_ideal']:.3f} | {r['S']:.3f} | "
              f"{fmt(r['delta_eq'])} | {fmt(r['S_eq'])} | "
              f"{fmt(r['wall_s'])} |")
    for t in th:
        v = t["threshold_pe_phi_s"]
        rng = lambda x: "?" if x is None else "%.3g" % x
        print(f"threshold {t['method']} t/t_end={t['fraction']:g} phi0={t['phi0']:g}: "
              f"{'%.3g' % v if v is not None else t['note']} "
              f"(S -/+ err: {rng(t['from'])} .. {rng(t['to'])})")


if __name__ == "__main__":
    sys.exit(main())
