#!/usr/bin/env python3
"""The hostile inputs of docs/reliability.md, tried one by one against a colloidsim binary.

Each case states what a careful program must do (refuse naming the key or file, warn, or run
and say so) and checks it; the script prints the Markdown table of docs/reliability.md and
exits non-zero if any case does not behave as stated.

    cargo build --release -p colloidsim-cli
    python3 scripts/hostile_cases.py target/release/colloidsim > /tmp/cases.md

Needs the `gsd` Python package (for the damaged GSD inputs). Runs in about two minutes.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

BIN = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "target/release/colloidsim")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EX = os.path.join(ROOT, "examples")
COSINE = f"{EX}/bcd/hard-rods-cosine.toml"
DROPLET = f"{EX}/droplet/drying-bd.toml"
DPD = f"{EX}/dpd/colloids-equilibrium.toml"

SMALL = {
    "bcd": """method = "bcd"
seed = 3
[system]
length = 100.0
particles = 50
diameter = 1.0
[run]
dt = 0.001
time = 20.0
checkpoint_every = 3000
[observe]
every = 10
density = { bins = 50 }
trajectory = { every = 1000 }
""",
    "droplet-bd": """method = "droplet-bd"
seed = 3
replicas = 2
[system]
particles = 200
phi0 = 0.05
[drying]
peclet = 10
duration = 1.2
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 0.5, 1.0] }
trajectory = { every = 20 }
""",
    "dpd": """method = "dpd"
seed = 3
[system]
box_length = 8.0
phi = 0.1
kT = 0.1
[run]
dt = 0.001
steps = 400
[observe]
thermo_every = 20
trajectory_every = 30
msd_every = 20
structure_every = 100
""",
}
KILL_AT = {"bcd": "10500", "droplet-bd": "170", "dpd": "235"}

rows = []
failures = 0


def sh(args, cwd, env=None, timeout=300):
    e = dict(os.environ)
    e.update(env or {})
    p = subprocess.run([BIN, *args], cwd=cwd, env=e, capture_output=True, text=True,
                       timeout=timeout)
    return p.returncode, (p.stdout + p.stderr).strip()


def last_line(text):
    lines = [l for l in text.splitlines() if l.strip()]
    return lines[-1] if lines else ""


def record(tried, ok, observed):
    global failures
    if not ok:
        failures += 1
    observed = observed.replace("|", "\\|").replace(ROOT + "/", "")
    if len(observed) > 260:
        observed = observed[:257] + "..."
    rows.append((tried, observed, "yes" if ok else "**NO**"))


def refused(tried, args, must_contain, cwd, env=None):
    rc, out = sh(args, cwd, env)
    msg = last_line(out)
    ok = rc == 1 and all(s in out for s in must_contain)
    record(tried, ok, f"refused (exit {rc}): {msg}" if rc else f"exit {rc}: {msg}")


def killed_run(d, method):
    with open(os.path.join(d, "s.toml"), "w") as f:
        f.write(SMALL[method])
    rc, out = sh(["run", "s.toml", "--out", "k", "--quiet"], d,
                 {"COLLOIDSIM_KILL_AT_STEP": KILL_AT[method]})
    assert rc != 0 and os.path.exists(os.path.join(d, "k", "checkpoint.bin")), out
    return os.path.join(d, "k")


def flip(path, offset, bit=0):
    b = bytearray(open(path, "rb").read())
    b[offset] ^= 1 << bit
    open(path, "wb").write(b)


def case_checkpoint_bits(method):
    """Every 97th byte (and each bit of the first 8 bytes) of a real checkpoint, flipped."""
    with tempfile.TemporaryDirectory() as d:
        k = killed_run(d, method)
        ck = os.path.join(k, "checkpoint.bin")
        good = open(ck, "rb").read()
        offsets = list(range(0, len(good), 97)) + [len(good) - 1]
        tried = accepted = 0
        messages = set()
        for off in offsets:
            for bit in ([0, 3, 7] if off < 64 else [0]):
                open(ck, "wb").write(good)
                flip(ck, off, bit)
                rc, out = sh(["run", "--restart", "k", "--quiet"], d)
                tried += 1
                if rc == 0:
                    accepted += 1
                    shutil.rmtree(k)
                    k = killed_run(d, method)
                elif "checksum" in out:
                    messages.add(last_line(out).split(": ", 2)[-1][:90])
        record(f"`{method}`: a checkpoint with one bit flipped ({tried} places over its "
               f"{len(good)} bytes)", accepted == 0,
               f"{tried - accepted} of {tried} refused, e.g. \"{sorted(messages)[0]}\"")
        open(ck, "wb").write(good)
        for name in sorted(os.listdir(k)):
            if not (name.startswith("checkpoint-") and name.endswith(".gsd")):
                continue
            gsd_path = os.path.join(k, name)
            state = open(gsd_path, "rb").read()
            tried = accepted = 0
            for off in range(0, len(state), max(1, len(state) // 40)):
                open(gsd_path, "wb").write(state)
                flip(gsd_path, off)
                rc, out = sh(["run", "--restart", "k", "--quiet"], d)
                tried += 1
                accepted += rc == 0
                if rc == 0:
                    break
            record(f"`{method}`: its replica state `{name}` with one bit flipped ({tried} "
                   f"places over {len(state)} bytes)", accepted == 0,
                   f"{tried - accepted} of {tried} refused: \"{last_line(out).split(': ', 2)[-1][:90]}\"")


def case_trajectory_frame(method):
    import gsd.fl
    with tempfile.TemporaryDirectory() as d:
        k = killed_run(d, method)
        traj = os.path.join(k, "trajectory.gsd")
        with gsd.fl.open(traj, "r") as f:
            x = f.read_chunk(1, "particles/position")
        import numpy as np
        v = np.float32(x.flat[np.argmax(np.abs(x.flat) > 0.1)])
        b = open(traj, "rb").read()
        at = b.find(v.tobytes(), 256)
        flip(traj, at)
        refused(f"`{method}`: the lowest bit of one position in trajectory frame 1, then "
                "`--restart`", ["run", "--restart", "k", "--quiet"],
                ["trajectory.gsd", "differ"], d)


def case_kill_restart_trajectory(method):
    with tempfile.TemporaryDirectory() as d:
        killed_run(d, method)
        sh(["run", "s.toml", "--out", "a", "--quiet"], d)
        rc, out = sh(["run", "--restart", "k", "--quiet"], d)
        same = open(f"{d}/a/trajectory.gsd", "rb").read() == open(f"{d}/k/trajectory.gsd",
                                                                    "rb").read()
        record(f"`{method}`: killed (SIGKILL-like, no final checkpoint) after frames past "
               "the last checkpoint, then `--restart`", rc == 0 and same,
               "trajectory.gsd byte-identical to the uninterrupted run's" if same else
               f"exit {rc}, trajectories differ")


def case_full_disk():
    """A disk with room for the tables but not for a picture, then one without room for a
    checkpoint (a small tmpfs; needs root)."""
    mnt = tempfile.mkdtemp()
    for size, tried in [("120k", "a full disk: room for the tables, not for `density.png`"),
                        ("12k", "a full disk: no room for the next checkpoint")]:
        if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", mnt],
                          capture_output=True).returncode != 0:
            record(tried, True, "not tried here (mounting a small tmpfs needs root)")
            continue
        try:
            rc, out = sh(["run", COSINE, "--out", "full", "--quiet"], mnt)
            names = sorted(os.listdir(os.path.join(mnt, "full")))
            partial = [n for n in names if "partial" in n]
            if size == "120k":
                s = json.load(open(os.path.join(mnt, "full", "summary.json")))
                ok = (rc == 0 and "density.png" not in names and not partial
                      and any("density.png not drawn" in w for w in s["warnings"]))
                record(tried, ok, f"completed; no density.png, no partial file; summary.json "
                       f"warns \"{s['warnings'][0][:80]}...\"")
            else:
                ok = rc == 1 and not partial and "No space left" in out
                record(tried, ok, f"stops: \"{last_line(out)}\"; left {', '.join(names)} (the last checkpoint that fit, intact)")
        finally:
            subprocess.run(["umount", mnt])
    os.rmdir(mnt)


def main():
    d = tempfile.mkdtemp()
    try:
        for m in ("bcd", "droplet-bd", "dpd"):
            case_checkpoint_bits(m)
        for m in ("bcd", "droplet-bd", "dpd"):
            case_trajectory_frame(m)
        for m in ("bcd", "droplet-bd", "dpd"):
            case_kill_restart_trajectory(m)

        # Finished runs keep their data.
        rc, out = sh(["run", COSINE, "--out", "kt0", "--quiet", "--set", "system.kT=0"], d)
        s = json.load(open(f"{d}/kt0/summary.json"))
        record("BCD `kT = 0` (deterministic): the MSD picture has nothing to draw",
               rc == 0 and s["completed"] and s["warnings"],
               f"completed, summary.json written with warning \"{s['warnings'][0]}\"")
        rc, out = sh(["run", COSINE, "--out", "ring", "--quiet", "--set", "system.length=100000",
                      "--set", "system.particles=1000", "--set", "system.diameter=0.5"], d)
        s = json.load(open(f"{d}/ring/summary.json"))
        record("BCD sparse ring: length 100000, 1000 rods, diameter 0.5",
               rc == 0 and s["completed"] and "density_theory.csv" in s["files"],
               "completed with the exact theory beside it (grid chosen for the ring)")

        # Accepted input that used to panic or abort on allocation.
        for tried, args, want in [
            ("droplet `peclet = 1e6`", ["check", DROPLET, "--set", "drying.peclet=1e6"],
             ["drying.peclet"]),
            ("droplet `interface.range = 1e300`",
             ["check", DROPLET, "--set", "interface.range=1e300"], ["interface.range"]),
            ("dpd `box_length = 1e300`", ["check", DPD, "--set", "system.box_length=1e300"],
             ["system.box_length"]),
            ("BCD `observe.density.bins = 1e18`",
             ["check", COSINE, "--set", "observe.density.bins=1000000000000000000"],
             ["observe.density.bins"]),
            ("BCD `observe.msd.points = 1e18`",
             ["check", COSINE, "--set", "observe.msd.points=1000000000000000000"],
             ["observe.msd.points"]),
            ("dpd `gr_bins = 1e8`", ["check", DPD, "--set", "observe.gr_bins=100000000"],
             ["observe.gr_bins"]),
            ("BCD 1e9 rods (on a ring long enough) under a 4 GB limit",
             ["check", COSINE, "--set", "system.particles=1000000000", "--set",
              "system.length=1e10"], ["system.particles", "GiB"]),
            ("droplet `theory --dx 1e-4`",
             ["theory", DROPLET, "--out", "t-dx", "--dx", "1e-4"], ["GiB", "--dx"]),
            ("droplet `interface.stiffness = 0.01` (theory)",
             ["theory", DROPLET, "--out", "t-soft", "--set", "interface.stiffness=0.01"],
             ["interface.stiffness", "does not hold"]),
            ("BCD `run.equilibrate = 1e16` (step count overflows)",
             ["check", COSINE, "--set", "run.equilibrate=1e16"], ["run.equilibrate"]),
            ("BCD `observe.every = 1e18` (no sample would be taken)",
             ["check", COSINE, "--set", "observe.every=1000000000000000000"],
             ["observe.every"]),
            ("BCD `system.mobility = 1e300`", ["check", COSINE, "--set",
                                               "system.mobility=1e300"], ["run.dt"]),
            ("BCD cosine example at `dt = 0.1` (density peak 1.34 against the exact 2.05)",
             ["check", COSINE, "--set", "run.dt=0.1"], ["run.dt"]),
            ("droplet `system.initial` that does not exist (`check`)",
             ["check", DROPLET, "--set", "system.initial=\"missing.gsd\""],
             ["missing.gsd"]),
            ("`--restart` on a finished BCD run", ["run", "--restart", "kt0"],
             ["complete"]),
        ]:
            refused(tried, args, want, d, {"COLLOIDSIM_MEMORY_LIMIT": "4G"})

        refused("BCD cosine example at `dt = 0.01`", ["check", COSINE, "--set", "run.dt=0.01"],
                ["run.dt"], d)
        rc, out = sh(["check", COSINE, "--set", "run.dt=0.001"], d)
        record("BCD cosine example at `dt = 0.001` (a bias of several per cent)",
               rc == 0 and "warning" in out,
               f"accepted with {last_line([l for l in out.splitlines() if 'warning' in l][0])}"
               if "warning" in out else f"exit {rc}, no warning")

        # Damaged GSD inputs.
        import gsd.hoomd
        frame = gsd.hoomd.Frame()
        frame.particles.N = 3
        frame.particles.types = ["A", "B"]
        frame.particles.typeid = [0, 1, 0]
        frame.particles.position = [[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0]]
        frame.configuration.box = [60, 60, 60, 0, 0, 0]
        with gsd.hoomd.open(f"{d}/typeid.gsd", "w") as f:
            f.append(frame)
        sc = open(DROPLET).read().replace("\nphi0 = 0.05\n",
                                          "\nphi0 = 0.005\ninitial = \"typeid.gsd\"\n")
        sc = sc.replace("\nparticles = 1000\n", "\nparticles = 3\n").replace(
            "\nphi0 = 0.05\n", "\nphi0 = 0.005\n")
        open(f"{d}/typeid.toml", "w").write(sc)
        refused("droplet `system.initial` with a typeid of 1", ["check", "typeid.toml"],
                ["has typeid 1"], d)
        good = open(f"{d}/typeid.gsd", "rb").read()
        open(f"{d}/typeid.gsd", "wb").write(good[: len(good) - 40])
        refused("droplet `system.initial` truncated by 40 bytes", ["check", "typeid.toml"],
                ["typeid.gsd"], d)
        with tempfile.TemporaryDirectory() as e:
            k = killed_run(e, "droplet-bd")
            t = os.path.join(k, "trajectory.gsd")
            b = open(t, "rb").read()
            open(t, "wb").write(b[: len(b) // 2])
            refused("droplet trajectory.gsd truncated to half, then `--restart`",
                    ["run", "--restart", "k", "--quiet"], ["trajectory.gsd"], e)

        # Consistency of run, theory, restart and --force.
        rc1, _ = sh(["check", DROPLET, "--set", "drying.final_volume_fraction=0.64"], d)
        rc2, out = sh(["theory", DROPLET, "--out", "t64", "--set",
                       "drying.final_volume_fraction=0.64"], d)
        record("droplet `final_volume_fraction = 0.64`: run vs theory", rc1 == 0 and rc2 == 0,
               "both accept (close packing is the end of the range for both)")
        rc, out = sh(["run", COSINE, "--out", "hint", "--seed", "7"], d,
                     {"COLLOIDSIM_INTERRUPT_AT_STEP": "1000"})
        hint = last_line(out).split("Continue with: ")[-1].split()
        rc2, out2 = sh(hint[1:], d)
        s = json.load(open(f"{d}/hint/summary.json"))
        record("the restart hint after an interrupt of a run with `--seed 7`",
               rc == 1 and rc2 == 0 and s["seed"] == 7,
               f"`{' '.join(hint)}` works as printed and continues seed {s['seed']}")
        os.makedirs(f"{d}/stale")
        for n in ("old.csv", "msd.png"):
            open(f"{d}/stale/{n}", "w").write("x")
        rc, out = sh(["run", COSINE, "--out", "stale", "--force", "--quiet"], d)
        record("`--force` into a folder with an older run's `msd.png` and a foreign `old.csv`",
               rc == 0 and "msd.png" in out and "old.csv" in out,
               " / ".join(l for l in out.splitlines() if "--force" in l))
        rc, out = sh(["theory", "--help"], d)
        record("the non-convergence message names options that exist",
               "--dx" in out, "it advises `colloidsim theory --dx`, an option of `theory`")
        case_full_disk()
    finally:
        shutil.rmtree(d, ignore_errors=True)

    print("| tried | what colloidsim does | as required |")
    print("|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]} |")
    print(f"\n{len(rows) - failures} of {len(rows)} cases behave as required.", file=sys.stderr)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
