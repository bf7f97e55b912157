#!/usr/bin/env python3
"""The drying droplet with hydrodynamics, with error bars from independent droplets (issue 13):

1. free draining (FD) against RPY in an unbounded fluid (direct sums): the paper's Fig. 3a;
2. RPY by positively split Ewald in the paper's periodic box (box_factor 2, optionally 3 or 4)
   against the direct free-space sums on the same droplet;
3. the centres beyond R at the end of drying: the same droplets in a stiffer interface;
4. free draining against RPY at the paper's other initial volume fractions, phi0 = 0.1 and 0.2
   (fd-phi0.1, rpy-phi0.1, fd-phi0.2, rpy-phi0.2; the same N in a smaller droplet, dried to the
   same phi = 0.5): the paper's Fig. S2.

Each (variant, seed) is one droplet, `colloidsim run SCENARIO --out RUNS/N<n>/<variant>/seed<s>
--seed s --threads T --quiet`; the droplet is examples/droplet/drying-rpy.toml scaled to N
particles (phi0 = 0.05, Pe = 10, dried to phi = 0.5, WCA, k = 50 kT/d^2, range d/2, offset -d/2,
dt = 2.5e-4 d^2/D0, Euler-Maruyama for every mobility, 30 radial bins, profiles at 0, 25, 50, 75
and 100 % of the drying time) and one GSD frame at the start and at the end. A folder whose
summary.json says completed is skipped; one with a checkpoint is continued with --restart; any
other is run again with --force. So the script can be stopped and started again.

Seed s gives the same initial configuration for every mobility (replica 0 of seed s), so the
profiles at t = 0 agree between variants exactly; the noise differs.

Outputs (the folders are created):
  DATA/summary.csv       centre (r/R < 0.5), outer (0.8 <= r/R < 1.05, i.e. the bins over
                         [0.8 R, R]) and skin (0.9 <= r/R < 1.05) mean volume fractions per
                         variant and profile time: mean and standard error over the droplets
  DATA/differences.csv   RPY - FD, PSE - direct, stiff - soft, ... per time and region, with
                         the combined standard error and the difference in units of it
  DATA/profiles.csv      the mean profile and its standard error per variant, time and bin
  DATA/interface.csv     the last frame per variant: centres beyond R, the largest excursion
                         (summary.json), centres in the interface's well, the pressure the
                         interface exerts (sum of its radial forces / 4 pi (R - d/2)^2), and the
                         outer shell's volume fraction counting the centres beyond R
  DATA/timing.csv        steps, wall and CPU seconds per droplet
  IMG/droplet-hydro-fd-vs-rpy.png, IMG/droplet-hydro-direct-vs-pse.png,
  IMG/droplet-hydro-interface.png
and a markdown table on stdout.

Usage (from the repository root; run it at low priority on a shared machine):
  nice -n 19 python3 scripts/droplet_hydrodynamics.py --bin target/release/colloidsim \\
      --particles 400 --seeds 6 --runs /work/droplet-runs [--variants fd,rpy,pse2,...] \\
      [--threads 1] [--analyse-only]

Variants: fd, rpy (direct), pse2, pse3, pse4 (PSE at box_factor 2, 3, 4), fd-k200, rpy-k200,
fd-k500, rpy-k500 (stiffer interfaces), and fd-k500-dt2, rpy-k500-dt2 (k = 500 at half the
time step, to check that step). --seeds-of VARIANT=S sets another number of seeds for one
variant (e.g. --seeds-of fd=12).
"""
import argparse
import csv
import json
import math
import os
import re
import resource
import subprocess
import sys
import time

import numpy as np

# Units: d = kT = eta = 1, D0 = kT / (3 pi eta d), d^2 / D0 = 9.4248.
D0 = 1.0 / (3.0 * math.pi)
DT = 2.36e-3  # 2.5e-4 d^2 / D0, the time step of examples/droplet/drying-rpy.toml
FRACTIONS = [0.0, 0.25, 0.5, 0.75, 1.0]
BINS = 30
RANGE, OFFSET = 0.5, -0.5
REGIONS = {"centre": (0.0, 0.5), "outer": (0.8, 1.05), "skin": (0.9, 1.05)}
# PSE splitting. The paper's xi = 0.5 / a = 1 / d needs a grid spacing of 0.54 a, i.e. a 148^3
# grid for the N = 400 droplet's box of 4 R0 = 40 d; xi = 0.5 / d halves the grid per axis and
# doubles the real-space cut-off. The operator is the same RPY to the tolerance for any xi
# (docs/hydrodynamics.md, PSE against Beenakker at xi = 0.7, 1 and 1.5 / d), so xi is a cost
# choice only. --splitting overrides it.
SPLITTING = 1.0

SCENARIO = """# written by scripts/droplet_hydrodynamics.py (variant {variant}): the droplet of
# examples/droplet/drying-rpy.toml with N = {n}, one droplet per run (--seed gives the droplet).
method = "droplet-bd"
seed = 1
replicas = 1

[system]
particles = {n}
diameter = 1.0
kT = 1.0
viscosity = 1.0
phi0 = {phi0}

[drying]
peclet = 10
final_volume_fraction = 0.5

[interface]
stiffness = {k}
range = {range}
offset = {offset}

[run]
dt = {dt}

[observe]
profile = {{ bins = {bins}, fractions = [0, 0.25, 0.5, 0.75, 1.0] }}
trajectory = {{ every = {every} }}

[hydrodynamics]
{hydro}
"""


def variants(splitting):
    fd = 'model = "free-draining"'
    rpy = 'model = "rpy"\nmethod = "direct"\ntolerance = 1e-3'

    def pse(bf):
        return (f'model = "rpy"\nmethod = "pse"\ntolerance = 1e-3\nbox_factor = {bf}\n'
                f"splitting = {splitting}")

    v = {
        "fd": dict(label="free draining", hydro=fd, k=50.0, dt=DT),
        "rpy": dict(label="RPY direct (free space)", hydro=rpy, k=50.0, dt=DT),
    }
    for bf in (2, 3, 4):
        v[f"pse{bf}"] = dict(label=f"RPY PSE, box {bf} droplet diameters", hydro=pse(bf),
                             k=50.0, dt=DT)
    # The paper's Fig. S2: Fig. 3 (free draining against RPY) at its other initial volume
    # fractions, the same N (a smaller droplet dried to the same phi = 0.5).
    for phi0 in (0.1, 0.2):
        v[f"fd-phi{phi0}"] = dict(label=f"free draining, phi0 = {phi0}", hydro=fd, k=50.0,
                                  dt=DT, phi0=phi0)
        v[f"rpy-phi{phi0}"] = dict(label=f"RPY direct, phi0 = {phi0}", hydro=rpy, k=50.0,
                                   dt=DT, phi0=phi0)
    for k in (200, 500):
        v[f"fd-k{k}"] = dict(label=f"free draining, k = {k}", hydro=fd, k=float(k), dt=DT)
        v[f"rpy-k{k}"] = dict(label=f"RPY direct, k = {k}", hydro=rpy, k=float(k), dt=DT)
        v[f"fd-k{k}-dt2"] = dict(label=f"free draining, k = {k}, dt / 2", hydro=fd,
                                 k=float(k), dt=DT / 2)
        v[f"rpy-k{k}-dt2"] = dict(label=f"RPY direct, k = {k}, dt / 2", hydro=rpy,
                                  k=float(k), dt=DT / 2)
    return v


# Comparisons written to differences.csv: (name, a, b) means a - b.
COMPARISONS = [
    ("RPY - FD", "rpy", "fd"),
    ("PSE(2) - direct", "pse2", "rpy"),
    ("PSE(3) - direct", "pse3", "rpy"),
    ("PSE(4) - direct", "pse4", "rpy"),
    ("RPY - FD, k = 200", "rpy-k200", "fd-k200"),
    ("RPY - FD, k = 500", "rpy-k500", "fd-k500"),
    ("FD k = 200 - FD k = 50", "fd-k200", "fd"),
    ("RPY k = 200 - RPY k = 50", "rpy-k200", "rpy"),
    ("FD k = 500 - FD k = 50", "fd-k500", "fd"),
    ("RPY k = 500 - RPY k = 50", "rpy-k500", "rpy"),
    ("FD k = 500: dt/2 - dt", "fd-k500-dt2", "fd-k500"),
    ("RPY k = 500: dt/2 - dt", "rpy-k500-dt2", "rpy-k500"),
    ("RPY - FD, phi0 = 0.1", "rpy-phi0.1", "fd-phi0.1"),
    ("RPY - FD, phi0 = 0.2", "rpy-phi0.2", "fd-phi0.2"),
]


def radii(n):
    r0 = (n / (8 * 0.05)) ** (1 / 3)
    r_end = (n / (8 * 0.5)) ** (1 / 3)
    return r0, r_end


def scenario_text(name, v, n, steps):
    return SCENARIO.format(variant=name, n=n, phi0=v.get("phi0", 0.05), k=v["k"],
                           range=RANGE, offset=OFFSET,
                           dt=repr(v["dt"]), bins=BINS, every=steps, hydro=v["hydro"])


def check_steps(binary, path):
    """Steps of the scenario from `colloidsim check` (the trajectory writes the first and the
    last frame when its interval is the number of steps)."""
    out = subprocess.run([binary, "check", "--json", path], check=True, capture_output=True,
                         text=True).stdout
    m = re.search(r"\"steps\":\s*(\d+)", out)
    if not m:
        sys.exit(f"cannot find the steps in `colloidsim check {path}`:\n{out}")
    return int(m.group(1)), out


def complete(folder):
    try:
        with open(os.path.join(folder, "summary.json")) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return False
    return s.get("completed", False) and all(
        os.path.exists(os.path.join(folder, f"profile_{fr:.2f}.csv")) for fr in FRACTIONS)


def prepare(binary, root, name, v, n):
    """Write the variant's scenario (steps from `check`; the trajectory interval is the number
    of steps) and return its path."""
    vdir = os.path.join(root, f"N{n}", name)
    os.makedirs(vdir, exist_ok=True)
    path = os.path.join(vdir, "scenario.toml")
    # Steps do not depend on the trajectory interval: check a copy with every = 0 first.
    probe = os.path.join(vdir, "probe.toml")
    with open(probe, "w") as f:
        f.write(scenario_text(name, v, n, 0))
    steps, _ = check_steps(binary, probe)
    os.remove(probe)
    text = scenario_text(name, v, n, steps)
    old = open(path).read() if os.path.exists(path) else None
    if old != text:
        if old is not None and any(
                d.startswith("seed") and os.path.isdir(os.path.join(vdir, d))
                for d in os.listdir(vdir)):
            sys.exit(f"{path} changed but {vdir} holds runs of the old one: move them away")
        with open(path, "w") as f:
            f.write(text)
    return path, steps


def run_one(binary, scen, folder, seed, threads, log):
    if complete(folder):
        return "done"
    args = [binary, "run"]
    if os.path.exists(os.path.join(folder, "checkpoint.bin")):
        args += [scen, "--restart", folder]
        how = "restart"
    else:
        args += [scen, "--out", folder, "--seed", str(seed), "--force"]
        how = "new"
    args += ["--threads", str(threads), "--quiet"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    print(f"  {how}: {' '.join(args)}", file=log, flush=True)
    res = subprocess.run(args, capture_output=True, text=True)
    wall = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if res.returncode != 0 or not complete(folder):
        print(f"  FAILED ({res.returncode}): {res.stderr.strip()[-2000:]}", file=log, flush=True)
        return "failed"
    # CPU time of this session (a restarted run adds to the earlier sessions' file).
    tfile = folder.rstrip("/") + ".time.json"
    prev = {"wall": 0.0, "cpu": 0.0, "sessions": 0}
    if os.path.exists(tfile):
        with open(tfile) as f:
            prev = json.load(f)
    with open(tfile, "w") as f:
        json.dump({"wall": prev["wall"] + wall, "cpu": prev["cpu"] + cpu,
                   "sessions": prev["sessions"] + 1}, f)
    print(f"  ok: {wall:.0f} s wall, {cpu:.0f} s CPU", file=log, flush=True)
    return "ran"


# ---------------------------------------------------------------- analysis


def load_run(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        s = json.load(f)
    p = s["parameters"]
    prof = []
    for frac, step in zip(p["fractions"], p["profile_steps"]):
        t = step * p["dt"]
        radius = math.sqrt(p["r0"] ** 2 - p["alpha"] * t / (4 * math.pi))
        data = np.loadtxt(os.path.join(folder, f"profile_{frac:.2f}.csv"), delimiter=",",
                          skiprows=1)
        prof.append(dict(frac=frac, t=t, R=radius, r=data[:, 0], phi=data[:, 1]))
    return s, prof


def shell_mean(r, phi, radius, lo, hi):
    """Volume-weighted mean phi of the bins whose mid-point lies in lo <= r / R < hi."""
    dr = r[1] - r[0]
    sel = (r / radius >= lo) & (r / radius < hi)
    vol = (r[sel] + dr / 2) ** 3 - (r[sel] - dr / 2) ** 3
    return float(np.sum(phi[sel] * vol) / np.sum(vol))


def last_frame(folder):
    """Positions (with images unwrapped) of the last GSD frame, or None without gsd."""
    try:
        import gsd.hoomd
    except ImportError:
        return None
    with gsd.hoomd.open(os.path.join(folder, "trajectory.gsd"), "r") as t:
        fr = t[-1]
        pos = np.asarray(fr.particles.position, dtype=float)
        img = np.asarray(fr.particles.image, dtype=float)
        box = np.asarray(fr.configuration.box[:3], dtype=float)
        radius = float(np.asarray(fr.log["droplet/radius"]).ravel()[0])
        step = int(fr.configuration.step)
    return pos + img * box, radius, step


def interface_stats(folder, summary):
    p = summary["parameters"]
    out = dict(beyond_R=summary.get("centres_beyond_R_at_end", float("nan")),
               max_excursion=summary.get("max_excursion_beyond_wall", float("nan")))
    got = last_frame(folder)
    if got is None:
        return out
    pos, radius, step = got
    if step != p["steps"]:
        sys.exit(f"{folder}: last frame at step {step}, not the last step {p['steps']}")
    k, rng, off = p["stiffness"], p["range"], p["offset"]
    r = np.linalg.norm(pos, axis=1)
    s = r - (radius + off)
    force = np.where(s <= 0, 0.0, np.where(s < rng, k * s, k * rng))
    wall = radius + off
    dr = radius / BINS
    lo = 0.8 * radius
    # the outer shell [0.8 R, R] in the profile's bins, and the same counting the centres
    # beyond R (all of them are within the interface's range of a few d)
    v_shell = 4 * math.pi / 3 * (radius**3 - lo**3)
    vp = math.pi / 6
    out.update(
        frame_beyond_R=int(np.sum(r > radius)),
        in_well=int(np.sum(s > 0)),
        mean_s_in_well=float(np.mean(s[s > 0])) if np.any(s > 0) else 0.0,
        max_s_end=float(np.max(s)),
        pressure=float(np.sum(force) / (4 * math.pi * wall**2)),
        force_per_well_particle=float(np.mean(force[s > 0])) if np.any(s > 0) else 0.0,
        cap=k * rng,
        outer_in_R=vp * int(np.sum((r >= lo) & (r < radius))) / v_shell,
        outer_all=vp * int(np.sum(r >= lo)) / v_shell,
        bin_width=dr,
    )
    return out


def mean_se(x):
    x = np.asarray(x, dtype=float)
    n = len(x)
    if n == 0:
        return float("nan"), float("nan")
    return float(np.mean(x)), (float(np.std(x, ddof=1) / math.sqrt(n)) if n > 1 else float("nan"))


def analyse(root, n, names, vdefs, data_dir, img_dir):
    os.makedirs(data_dir, exist_ok=True)
    os.makedirs(img_dir, exist_ok=True)
    res = {}
    for name in names:
        vdir = os.path.join(root, f"N{n}", name)
        if not os.path.isdir(vdir):
            continue
        runs = sorted((d for d in os.listdir(vdir)
                       if re.fullmatch(r"seed\d+", d) and complete(os.path.join(vdir, d))),
                      key=lambda d: int(d[4:]))
        if not runs:
            continue
        per = []
        for d in runs:
            folder = os.path.join(vdir, d)
            s, prof = load_run(folder)
            regions = [{reg: shell_mean(pr["r"], pr["phi"], pr["R"], lo, hi)
                        for reg, (lo, hi) in REGIONS.items()} for pr in prof]
            tfile = folder + ".time.json"
            tm = json.load(open(tfile)) if os.path.exists(tfile) else {}
            per.append(dict(seed=int(d[4:]), summary=s, prof=prof, regions=regions,
                            iface=interface_stats(folder, s), wall=s.get("wall_seconds"),
                            cpu=tm.get("cpu")))
        res[name] = per
    if not res:
        sys.exit("no complete runs to analyse")

    # summary.csv and the mean profiles
    rows, prow = [], []
    for name, per in res.items():
        p0 = per[0]["prof"]
        for j, pr in enumerate(p0):
            row = dict(variant=name, droplets=len(per), fraction=pr["frac"], t=round(pr["t"], 3),
                       R=round(pr["R"], 4))
            for reg in REGIONS:
                m, e = mean_se([q["regions"][j][reg] for q in per])
                row[f"{reg}"] = m
                row[f"{reg}_se"] = e
            rows.append(row)
            phis = np.array([q["prof"][j]["phi"] for q in per])
            m = phis.mean(axis=0)
            e = phis.std(axis=0, ddof=1) / math.sqrt(len(per)) if len(per) > 1 else m * np.nan
            for i, r in enumerate(pr["r"]):
                prow.append(dict(variant=name, fraction=pr["frac"], r=round(float(r), 6),
                                 r_over_R=round(float(r / pr["R"]), 6), phi=m[i], se=e[i]))
    write_csv(os.path.join(data_dir, "summary.csv"), rows, fmt=5)
    write_csv(os.path.join(data_dir, "profiles.csv"), prow, fmt=5)

    summ = {(r["variant"], r["fraction"]): r for r in rows}
    drows = []
    for label, a, b in COMPARISONS:
        if a not in res or b not in res:
            continue
        for fr in FRACTIONS:
            ra, rb = summ[(a, fr)], summ[(b, fr)]
            row = dict(comparison=label, a=a, b=b, fraction=fr, t=ra["t"])
            for reg in REGIONS:
                diff = ra[reg] - rb[reg]
                se = math.hypot(ra[f"{reg}_se"], rb[f"{reg}_se"])
                row[reg] = diff
                row[f"{reg}_se"] = se
                row[f"{reg}_z"] = diff / se if se > 0 else float("nan")
            # paired by seed (seed s starts both from the same configuration)
            common = sorted(set(q["seed"] for q in res[a]) & set(q["seed"] for q in res[b]))
            j = FRACTIONS.index(fr)
            for reg in REGIONS:
                qa = {q["seed"]: q["regions"][j][reg] for q in res[a]}
                qb = {q["seed"]: q["regions"][j][reg] for q in res[b]}
                m, e = mean_se([qa[s] - qb[s] for s in common])
                if len(common) < 4 or not e > 1e-9:
                    e = float("nan")  # too few pairs (or identical differences of counts)
                row[f"{reg}_paired"] = m
                row[f"{reg}_paired_se"] = e
            row["pairs"] = len(common)
            drows.append(row)
    write_csv(os.path.join(data_dir, "differences.csv"), drows, fmt=5)

    irows, trows = [], []
    for name, per in res.items():
        keys = [k for k in per[0]["iface"] if isinstance(per[0]["iface"][k], (int, float))]
        row = dict(variant=name, droplets=len(per), stiffness=per[0]["summary"]["parameters"]["stiffness"],
                   dt=per[0]["summary"]["parameters"]["dt"])
        for k in keys:
            if k in ("cap", "bin_width"):
                row[k] = per[0]["iface"][k]
                continue
            m, e = mean_se([q["iface"][k] for q in per])
            row[k] = m
            row[f"{k}_se"] = e
        row["max_excursion_max"] = max(q["iface"]["max_excursion"] for q in per)
        irows.append(row)
        walls = [q["wall"] for q in per if q["wall"] is not None]
        cpus = [q["cpu"] for q in per if q["cpu"] is not None]
        trows.append(dict(variant=name, droplets=len(per),
                          steps=per[0]["summary"]["parameters"]["steps"],
                          threads=per[0]["summary"].get("threads"),
                          wall_mean=np.mean(walls) if walls else float("nan"),
                          wall_total=np.sum(walls) if walls else float("nan"),
                          cpu_mean=np.mean(cpus) if cpus else float("nan"),
                          cpu_total=np.sum(cpus) if cpus else float("nan")))
    write_csv(os.path.join(data_dir, "interface.csv"), irows, fmt=5)
    write_csv(os.path.join(data_dir, "timing.csv"), trows, fmt=4)

    print_markdown(res, summ, drows, irows, trows, vdefs, n)
    figures(res, prow, vdefs, img_dir, n)


def write_csv(path, rows, fmt):
    if not rows:
        return
    keys = list(rows[0].keys())
    for r in rows[1:]:
        for k in r:
            if k not in keys:
                keys.append(k)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.{fmt}g}" if isinstance(v, float) else v)
                        for k, v in r.items()})


def pm(m, e, digits=4):
    if math.isnan(e):
        return f"{m:.{digits}f}"
    return f"{m:.{digits}f} ± {e:.{digits}f}"


def print_markdown(res, summ, drows, irows, trows, vdefs, n):
    names = list(res)
    print(f"\n### N = {n}: mean volume fraction, mean ± standard error over droplets\n")
    print("| variant | droplets | fraction | t | R | centre r/R < 0.5 | outer 0.8 <= r/R < 1.05 |")
    print("|---|---|---|---|---|---|---|")
    for nm in names:
        for fr in FRACTIONS:
            r = summ[(nm, fr)]
            print(f"| {nm} | {r['droplets']} | {fr:g} | {r['t']:.1f} | {r['R']:.2f} | "
                  f"{pm(r['centre'], r['centre_se'])} | {pm(r['outer'], r['outer_se'])} |")
    print("\n### Differences (a - b ± combined standard error, and in units of it)\n")
    print("| comparison | fraction | centre a - b | z | paired: mean ± se | z | "
          "outer a - b | z | paired: mean ± se | z |")
    print("|---|---|---|---|---|---|---|---|---|---|")

    def z(m, e):
        return f"{m / e:+.1f}" if e > 0 else "–"  # nan > 0 is False

    for d in drows:
        cells = [d["comparison"], f"{d['fraction']:g}"]
        for reg in ("centre", "outer"):
            cells += [f"{d[reg]:+.4f} ± {d[reg + '_se']:.4f}", z(d[reg], d[reg + "_se"]),
                      f"{d[reg + '_paired']:+.4f} ± {d[reg + '_paired_se']:.4f}",
                      z(d[reg + "_paired"], d[reg + "_paired_se"])]
        print("| " + " | ".join(cells) + " |")
    print("\n### The interface at the end of drying (mean ± standard error over droplets)\n")
    print("| variant | k | dt | beyond R | max excursion (largest) | in the well | "
          "pressure (kT/d^3) | force per particle in the well (cap) | outer phi in [0.8R, R] | "
          "outer counting beyond R |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in irows:
        def g(k, digits=2):
            if k not in r:
                return "–"
            return pm(r[k], r.get(f"{k}_se", float("nan")), digits)
        print(f"| {r['variant']} | {r['stiffness']:g} | {r['dt']:.4g} | {g('beyond_R', 1)} | "
              f"{g('max_excursion', 3)} ({r['max_excursion_max']:.3f}) | {g('in_well', 1)} | "
              f"{g('pressure', 2)} | {g('force_per_well_particle', 1)} ({r.get('cap', float('nan')):g}) | "
              f"{g('outer_in_R', 4)} | {g('outer_all', 4)} |")
    print("\n### Cost per droplet\n")
    print("| variant | droplets | steps | threads | wall s (mean) | CPU s (mean) | wall s (all) |")
    print("|---|---|---|---|---|---|---|")
    for r in trows:
        print(f"| {r['variant']} | {r['droplets']} | {r['steps']} | {r['threads']} | "
              f"{r['wall_mean']:.0f} | {r['cpu_mean']:.0f} | {r['wall_total']:.0f} |")


MERGE = 2  # the figures merge this many neighbouring bins (volume-weighted) against the noise


def figures(res, prow, vdefs, img_dir, n):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def merged(name, frac):
        """Mean and standard error over the droplets of the profile with MERGE bins merged."""
        j = FRACTIONS.index(frac)
        ys = []
        for q in res[name]:
            pr = q["prof"][j]
            r, phi, dr = pr["r"], pr["phi"], pr["r"][1] - pr["r"][0]
            vol = (r + dr / 2) ** 3 - (r - dr / 2) ** 3
            m = len(r) // MERGE * MERGE
            ys.append((phi[:m] * vol[:m]).reshape(-1, MERGE).sum(1)
                      / vol[:m].reshape(-1, MERGE).sum(1))
            x = r[:m].reshape(-1, MERGE).mean(1) / pr["R"]
        ys = np.array(ys)
        se = (ys.std(axis=0, ddof=1) / math.sqrt(len(ys)) if len(ys) > 1
              else np.full(ys.shape[1], np.nan))
        return x, ys.mean(axis=0), se

    def draw(ax, name, frac, style, color, lw, label=None):
        x, y, e = merged(name, frac)
        ax.plot(x, y, style, color=color, lw=lw, label=label)
        if np.all(np.isfinite(e)):
            ax.fill_between(x, y - e, y + e, color=color, alpha=0.22, lw=0)
        return np.max((y + np.nan_to_num(e))[x > 0.15])

    def panel(fname, pairs, title):
        present = [(nm, st) for nm, st in pairs if nm in res]
        if len(present) < 2:
            return
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.3), gridspec_kw={"width_ratios": [3, 2]})
        for ax, fracs in zip(axes, (FRACTIONS[:-1], FRACTIONS[-1:])):
            top = 0
            for j, (nm, st) in enumerate(present):
                for i, fr in enumerate(fracs):
                    c = f"C{FRACTIONS.index(fr)}"
                    top = max(top, draw(ax, nm, fr, st, c, 1.7 if st == "-" else 1.3,
                                        f"{fr:.0%} of drying" if j == 0 else None))
                ax.plot([], [], st, color="k",
                        label=f"{vdefs[nm]['label']} ({len(res[nm])})")
            ax.set_xlim(0, 1.0)
            ax.set_ylim(0, 1.08 * top)
            ax.set_xlabel("r / R(t)")
            ax.set_ylabel("volume fraction phi(r)")
            ax.legend(fontsize=7.5, loc="upper left")
        fig.suptitle(title, fontsize=10)
        fig.tight_layout()
        fig.savefig(os.path.join(img_dir, fname), dpi=90)
        plt.close(fig)

    sub = (f"N = {n}, Pe = 10, dried to phi = 0.5; mean over droplets (their number in "
           f"brackets), bands ± 1 standard error; {BINS // MERGE} shells")
    panel("droplet-hydro-fd-vs-rpy.png", [("fd", "--"), ("rpy", "-")],
          "Free draining vs RPY in free space\n" + sub)
    for phi0 in (0.1, 0.2):
        panel(f"droplet-hydro-fd-vs-rpy-phi{phi0}.png",
              [(f"fd-phi{phi0}", "--"), (f"rpy-phi{phi0}", "-")],
              f"Free draining vs RPY in free space, phi0 = {phi0} (Fig. S2)\n" + sub)
    panel("droplet-hydro-direct-vs-pse.png", [("rpy", "-"), ("pse2", "--"), ("pse3", "-."),
                                              ("pse4", ":")],
          "RPY: direct (free space) vs PSE (periodic box)\n" + sub)

    # the interface: profiles at the two stiffnesses, FD and RPY
    pairs = [("fd", "--"), ("rpy", "-"), ("fd-k500", "--"), ("rpy-k500", "-")]
    if all(nm in res for nm, _ in pairs):
        fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
        for ax, frac in zip(axes, (0.75, 1.0)):
            top = 0
            for nm, st in pairs:
                stiff = "k500" in nm
                lab = ("RPY" if nm.startswith("rpy") else "FD") + (
                    ", k = 500" if stiff else ", k = 50") + f" ({len(res[nm])})"
                top = max(top, draw(ax, nm, frac, st, "C3" if nm.startswith("rpy") else "C0",
                                    2.2 if stiff else 1.0, lab))
            ax.set_xlabel("r / R(t)")
            ax.set_ylabel("phi(r)")
            ax.set_xlim(0, 1)
            ax.set_ylim(0, 1.08 * top)
            ax.set_title(f"{frac:.0%} of the drying time", fontsize=10)
            ax.legend(fontsize=8, loc="upper left")
        fig.suptitle(f"N = {n}: interface k = 50 (thin) and 500 kT/d² (thick), "
                     "mean ± standard error over droplets", fontsize=10)
        fig.tight_layout()
        fig.savefig(os.path.join(img_dir, "droplet-hydro-interface.png"), dpi=90)
        plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True, help="the colloidsim binary")
    ap.add_argument("--particles", type=int, default=400)
    ap.add_argument("--seeds", type=int, default=6, help="droplets per variant (seeds 1..S)")
    ap.add_argument("--seeds-of", action="append", default=[], metavar="VARIANT=S")
    ap.add_argument("--variants", default="fd,rpy,pse2")
    ap.add_argument("--runs", default="/work/droplet-runs", help="run folders (not in git)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--splitting", type=float, default=SPLITTING)
    ap.add_argument("--data", default="docs/data/droplet-hydro")
    ap.add_argument("--img", default="docs/img")
    ap.add_argument("--analyse-only", action="store_true")
    ap.add_argument("--interleave", action="store_true",
                    help="run seed by seed across the variants (partial results stay balanced)")
    a = ap.parse_args()
    vdefs = variants(a.splitting)
    names = [x for x in a.variants.split(",") if x]
    for nm in names:
        if nm not in vdefs:
            sys.exit(f"unknown variant {nm}; known: {', '.join(vdefs)}")
    seeds = {nm: a.seeds for nm in names}
    for s in a.seeds_of:
        nm, k = s.split("=")
        seeds[nm] = int(k)
    r0, r_end = radii(a.particles)
    print(f"N = {a.particles}: R0 = {r0:.3f} d, R_end = {r_end:.3f} d", flush=True)
    if not a.analyse_only:
        binary = os.path.abspath(a.bin)
        scen = {nm: prepare(binary, a.runs, nm, vdefs[nm], a.particles) for nm in names}
        jobs = [(nm, s) for nm in names for s in range(1, seeds[nm] + 1)]
        if a.interleave:
            jobs.sort(key=lambda j: (j[1], names.index(j[0])))
        log = open(os.path.join(a.runs, f"N{a.particles}", "log.txt"), "a")
        for nm, s in jobs:
            folder = os.path.join(a.runs, f"N{a.particles}", nm, f"seed{s}")
            print(f"{time.strftime('%H:%M:%S')} {nm} seed {s} ({scen[nm][1]} steps)",
                  file=log, flush=True)
            st = run_one(binary, scen[nm][0], folder, s, a.threads, log)
            print(f"{time.strftime('%H:%M:%S')} {nm} seed {s}: {st}", flush=True)
    analyse(a.runs, a.particles, names, vdefs, a.data, a.img)


if __name__ == "__main__":
    main()
