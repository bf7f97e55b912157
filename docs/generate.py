"""Pages of the site generated at build time (conf.py calls them; their folders are not in git).

`cli_pages(folder)`: one page per command of the `colloidsim` program, from its own parser
(`colloidsim CMD --help`), so that the reference cannot drift from the code.
"""

import os
import re
import shutil
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def cli_binary() -> Path:
    """The `colloidsim` binary: $COLLOIDSIM_BIN, else the newest of this checkout's
    target/release and target/debug (as python/tests/conftest.py), else the one on PATH."""
    env = os.environ.get("COLLOIDSIM_BIN")
    if env:
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    found = [p for p in (target / "release/colloidsim", target / "debug/colloidsim") if p.exists()]
    if found:
        return max(found, key=lambda p: p.stat().st_mtime)
    on_path = shutil.which("colloidsim")
    if on_path:
        return Path(on_path)
    raise RuntimeError(
        "docs: no colloidsim binary for the CLI reference: build it (`cargo build --release`) "
        "or set COLLOIDSIM_BIN"
    )


def _help(binary: Path, words):
    p = subprocess.run([str(binary), *words, "--help"], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"colloidsim {' '.join(words)} --help failed:\n{p.stderr}")
    return p.stdout


def _subcommands(text: str):
    """The names listed under `Commands:` in clap's help, without `help`."""
    names, inside = [], False
    for line in text.splitlines():
        if line.strip() == "Commands:":
            inside = True
            continue
        if inside:
            m = re.match(r"^  (\S+)\s", line + " ")
            if not m:
                break
            if m.group(1) != "help":
                names.append(m.group(1))
    return names


def _first_line(text: str) -> str:
    return text.strip().splitlines()[0] if text.strip() else ""


def _write(path: Path, text: str) -> None:
    """Write only when changed, so that Sphinx rereads only what changed."""
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def cli_pages(folder: Path) -> None:
    binary = cli_binary()
    folder.mkdir(parents=True, exist_ok=True)
    top = _help(binary, [])
    commands = _subcommands(top)
    pages = []
    for cmd in commands:
        text = _help(binary, [cmd])
        body = [f"# `colloidsim {cmd}`", "", _first_line(text), "", "```text", text.rstrip(), "```", ""]
        for sub in _subcommands(text):
            sub_text = _help(binary, [cmd, sub])
            body += [f"## `colloidsim {cmd} {sub}`", "", "```text", sub_text.rstrip(), "```", ""]
        _write(folder / f"{cmd}.md", "\n".join(body))
        pages.append(cmd)
    for old in folder.glob("*.md"):
        if old.stem not in pages and old.name != "index.md":
            old.unlink()
    index = [
        "# Command line (`colloidsim`)",
        "",
        "Generated at build time from the program's own parser (`colloidsim --help` and each "
        "command's `--help`), so it is the program's text word for word.",
        "",
        "```text",
        top.rstrip(),
        "```",
        "",
        "```{toctree}",
        ":maxdepth: 1",
        "",
        *pages,
        "```",
        "",
    ]
    _write(folder / "index.md", "\n".join(index))


# One tiny run of each method (and the theory where there is one), from its example with
# overrides that make it short: the files it writes and each CSV's header, as written.
OUTPUT_CASES = [
    ("bcd", "bcd.md#outputs-in-the---out-folder-default-the-scenarios-name", "bcd/hard-rods-cosine.toml",
     {"run.time": 1.0, "run.equilibrate": 0.1, "observe.trajectory": {"every": 1000}}, True),
    ("droplet-bd", "droplet.md#outputs", "droplet/drying-bd.toml",
     {"system.particles": 30, "replicas": 1, "observe.trajectory.every": 500}, True),
    ("droplet-bd with RPY", "droplet.md#outputs", "droplet/drying-rpy.toml",
     {"system.particles": 20, "replicas": 1}, False),
    ("bd", "bd.md#outputs", "bd/sedimentation.toml",
     {"system.particles": 20, "run.time": 2.0, "observe.trajectory.every": 500}, False),
    ("dpd", "dpd.md#outputs", "dpd/colloids-equilibrium.toml",
     {"system.box_length": 8.0, "run.steps": 200, "observe.structure_every": 100,
      "observe.trajectory_every": 100, "observe.viscosity_every": 10,
      "observe.viscosity_time": 0.1, "observe.msd_every": 20, "observe.thermo_every": 50}, False),
    ("dpd under shear", "dpd.md#shear-flow-leesedwards", "dpd/shear.toml",
     {"system.box_length": 5.0, "run.steps": 200, "observe.thermo_every": 20}, False),
    ("hs-mc", "mc.md#outputs", "mc/bulk.toml",
     {"system.particles": 64, "mc.sweeps": 400, "mc.warmup_sweeps": 50,
      "output.gr_max": 2.0}, False),
    ("mpcd", "mpcd.md#bulk-mpcd", "mpcd/viscosity.toml", {"system.box": 6, "run.collisions": 200}, False),
    ("droplet-mpcd", "mpcd.md#drying-droplet-droplet-mpcd", "droplet/drying-mpcd-solvent.toml",
     {"system.radius": 4, "drying.duration": 20, "observe.solvent.window": 100}, False),
]

KINDS = {".png": "picture", ".svg": "picture (vector)", ".gif": "animation",
         ".gsd": "trajectory (HOOMD GSD schema)", ".json": "JSON", ".toml": "the scenario as run",
         ".bin": "checkpoint"}


def _describe(path: Path) -> str:
    if path.suffix == ".csv":
        with open(path) as f:
            header = f.readline().strip()
        return "columns `" + header.replace(",", ", ") + "`"
    return KINDS.get(path.suffix, "")


def _toml(v) -> str:
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml(x)}" for k, x in v.items()) + " }"
    if isinstance(v, str):
        return f'"{v}"'
    return str(v).lower() if isinstance(v, bool) else str(v)


def _set_flags(overrides) -> str:
    """Overrides as the CLI's `--set KEY=VALUE` flags."""
    return " ".join(f"--set {k}={_toml(v).replace(' ', '')}" for k, v in overrides.items())


def stale_keys_pages():
    """Methods whose docs/keys/METHOD.md differs from `colloidsim keys METHOD --format
    markdown` (crates/cli/tests/keys_pages.rs checks the same; this makes the site say so)."""
    binary = cli_binary()
    stale = []
    for page in sorted((REPO / "docs" / "keys").glob("*.md")):
        p = subprocess.run([str(binary), "keys", page.stem, "--format", "markdown"],
                           capture_output=True, text=True)
        if p.returncode != 0 or p.stdout != page.read_text():
            stale.append(page.stem)
    return stale


def output_page(path: Path) -> None:
    """reference/generated/outputs.md: the files of a tiny run of each example, with headers."""
    import tempfile
    import warnings

    import colloidsim

    lines = [
        "# Output files and their columns",
        "",
        "Generated at build time: one short run of an example of each method (and `colloidsim "
        "theory` where the method has one), with the files it wrote and each CSV file's header "
        "as written. What each column means, in which units, and the files other keys add: the "
        "*Outputs* section of each method's page, linked below. Every run also writes "
        "`summary.json` when it finishes (`completed`, the resolved parameters, the headline "
        "numbers, and for each null number the reason); `checkpoint.bin` lives in the folder "
        "while a run is under way ([run.md](../../run.md#what-every-run-shares-the-driver)).",
        "",
    ]
    for title, page, example, overrides, theory in OUTPUT_CASES:
        lines += [f"## {title}", "",
                  f"`colloidsim run examples/{example} {_set_flags(overrides)}` (the files are described in "
                  f"[{page.split('#')[0]}](../../{page})).", ""]
        results = []
        with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = colloidsim.run(REPO / "examples" / example, out=Path(tmp) / "run",
                               overrides=overrides)
            results.append(("`colloidsim run`", r))
            if theory:
                results.append(("`colloidsim theory`", colloidsim.theory(
                    REPO / "examples" / example, out=Path(tmp) / "theory", overrides=overrides)))
            for label, res in results:
                names = sorted(set(res.files) | {p.name for p in res.out.iterdir()})
                lines += [f"{label}:", "", "| file | holds |", "|---|---|"]
                lines += [f"| `{n}` | {_describe(res.out / n)} |" for n in names]
                lines.append("")
    _write(path, "\n".join(lines))
