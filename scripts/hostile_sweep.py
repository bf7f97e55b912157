"""Hostile-input sweep: every key of four examples set, one at a time, to each of 14 hostile
values; `check`, and `run` where check accepts, under a 4 GB address-space limit and an 8 s
timeout. Reports panics, aborts and kills (exit status other than 0 and 1) and tallies the
outcomes; a timeout is a valid run that is still going. A run that completes has its outputs
checked: every CSV field a finite number or empty, every JSON file valid, every null of
summary.json listed in its `nulls` and every `non_finite` column with its reason ("silent").

    cargo build --release -p colloidsim-cli
    python3 scripts/hostile_sweep.py target/release/colloidsim /tmp/hostile [EXAMPLES.json]

EXAMPLES.json (optional) lists [example, [--set values that shorten it]] pairs instead of the
four default examples. About 20 minutes on 2 cores. The tally of the last sweep is in
docs/reliability.md."""
import json, os, subprocess, sys, tomllib, itertools, shutil, resource

BIN, OUT = sys.argv[1], sys.argv[2]
EX = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "examples")
examples = [[e, []] for e in ["bcd/hard-rods-cosine.toml", "bcd/channel-trap.toml", "droplet/drying-bd.toml", "dpd/colloids-equilibrium.toml"]]
if len(sys.argv) > 3:
    examples = json.load(open(sys.argv[3]))
VALUES = [0, -1, 1e300, -1e300, 1e18, 3.5, "nan", "inf", "x", True, [], [1e300], {"a": 1}, 2**62]

def toml_value(v):
    if isinstance(v, bool): return "true" if v else "false"
    if isinstance(v, str):
        return v if v in ("nan", "inf") else json.dumps(v)
    if isinstance(v, list): return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict): return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    return repr(v) if isinstance(v, float) else str(v)

def silent(d):
    """What a completed run's folder `d` holds that is not a number, or null without a reason."""
    found = []
    for name in sorted(os.listdir(d)):
        path = os.path.join(d, name)
        if name.endswith(".csv"):
            for line in open(path, errors="replace").read().splitlines()[1:]:
                for f in line.split(","):
                    try:
                        x = float(f)
                    except ValueError:
                        continue
                    if x != x or x in (float("inf"), float("-inf")):
                        found.append(f"{name}: {f}")
        elif name.endswith(".json"):
            try:
                v = json.load(open(path))
            except ValueError:
                found.append(f"{name}: not valid JSON")
                continue
            if name == "summary.json" and isinstance(v, dict):
                nulls = v.get("nulls", {})
                def walk(x, at):
                    if x is None:
                        if at not in nulls: found.append(f"summary.json: {at} null without a reason")
                    elif isinstance(x, dict):
                        for k, y in x.items():
                            if y is None and (k in ("why_null", "note") or k.endswith("_note")): continue
                            walk(y, f"{at}.{k}" if at else k)
                    elif isinstance(x, list):
                        for i, y in enumerate(x): walk(y, f"{at}[{i}]")
                for k, x in v.items():
                    if k not in ("parameters", "error", "nulls", "non_finite"): walk(x, k)
                for n in v.get("non_finite", []):
                    if not n.get("reason"): found.append(f"summary.json: non_finite without a reason: {n}")
    return found

def limit():
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))

results = []
tally = {}
os.makedirs(OUT, exist_ok=True)
for ex, shorten in examples:
    method = tomllib.load(open(f"{EX}/{ex}", "rb"))["method"]
    keys = json.loads(subprocess.run([BIN, "keys", method, "--format", "json"], capture_output=True, text=True).stdout)
    for k in keys:
        if k["path"] == "method": continue
        for v in VALUES:
            tag = f"{os.path.basename(ex)}:{k['path']}={toml_value(v)}"
            d = os.path.join(OUT, "case")
            shutil.rmtree(d, ignore_errors=True)
            for cmd in (["check", f"{EX}/{ex}"], ["run", f"{EX}/{ex}", "--out", d, "--quiet"]):
                args = [BIN, *cmd, *[a for x in shorten for a in ("--set", x)], "--set", f"{k['path']}={toml_value(v)}"]
                try:
                    p = subprocess.run(args, capture_output=True, text=True, timeout=8, preexec_fn=limit)
                    rc = p.returncode
                    err = p.stderr.strip().splitlines()[-1:] if p.stderr.strip() else [""]
                except subprocess.TimeoutExpired:
                    rc, err = "timeout", [""]
                tally[(cmd[0], str(rc))] = tally.get((cmd[0], str(rc)), 0) + 1
                bad = rc not in (0, 1)
                warn = rc == 0 and "warning" in (p.stderr if rc != "timeout" else "")
                if bad or cmd[0] == "run":
                    results.append((tag, cmd[0], rc, err[0][:200]))
                    print(tag, cmd[0], rc, err[0][:160], flush=True)
                if cmd[0] == "run" and rc == 0 and os.path.isdir(d):
                    for f in silent(d)[:3]:
                        tally[("run", "silent")] = tally.get(("run", "silent"), 0) + 1
                        results.append((tag, "silent", 0, f[:200]))
                        print(tag, "SILENT", f[:160], flush=True)
                if rc != 0: break  # check refused: do not run
json.dump(results, open(os.path.join(OUT, "results.json"), "w"), indent=1)
for r in results:
    if r[2] not in (0, 1): print("CRASH", r)
    if r[1] == "silent": print("SILENT", r)
print("tally (command, exit status): count")
for (c, r), n in sorted(tally.items()): print(f"  {c:6s} {r:8s} {n}")
json.dump({f"{c} {r}": n for (c, r), n in tally.items()}, open(os.path.join(OUT, "tally.json"), "w"), indent=1)
print(len(results), "noted;", sum(r[2] not in (0,1) for r in results), "crashes/timeouts")
