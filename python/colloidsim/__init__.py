"""colloidsim from Python: the same run path as the ``colloidsim`` command.

Run a scenario and get its observables as numpy arrays::

    import colloidsim
    r = colloidsim.run("examples/bcd/hard-rods-cosine.toml", out="hard-rods")
    r.density.x, r.density.rho          # density.csv, column by column
    r.summary["steps"]                  # summary.json as a dict
    th = colloidsim.theory("examples/bcd/hard-rods-cosine.toml", out="hard-rods-theory")

or step an engine by hand::

    bcd = colloidsim.BCD({"method": "bcd", "system": {...}, "run": {...}})
    bcd.step(1000)
    bcd.positions                       # numpy array, read-only

A scenario is a path to a TOML file, a TOML string, or a dict with the file's structure.
``overrides`` sets keys by their dotted path (``{"run.dt": 1e-4}``), with the same validation as
in the file; so does the CLI's ``--set run.dt=1e-4``. Every key, with its unit, default and
allowed range: ``colloidsim.keys("bcd")``. Errors raise :class:`ColloidsimError` with the
message the CLI prints; Ctrl-C stops a run at the next point where it can write a checkpoint
and raises ``KeyboardInterrupt`` (continue it with :func:`resume`).
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
import warnings
from pathlib import Path
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _colloidsim
from ._colloidsim import ColloidsimError
from . import hydro  # noqa: E402 (colloidsim.hydro: libMobility-shaped mobility operators)
from . import analysis  # noqa: E402 (colloidsim.analysis: observables on arrays and gsd frames)
from . import _build

__all__ = [
    "BCD",
    "BrownianDynamics",
    "ColloidsimError",
    "DPD",
    "Engine",
    "MPCD",
    "MonteCarlo",
    "Periodic",
    "Result",
    "Table",
    "analyse",
    "check",
    "ensemble",
    "keys",
    "methods",
    "resume",
    "run",
    "theory",
]

__version__ = _colloidsim.version

ScenarioLike = Union[str, "os.PathLike[str]", Mapping[str, Any]]


def _jsonable(v: Any) -> Any:
    """numpy scalars and arrays to plain Python values."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    raise TypeError(f"scenario value {v!r} of type {type(v).__name__} is not a TOML value")


def _scenario(scenario: ScenarioLike) -> Tuple[str, str, str, Optional[str]]:
    """(TOML text, base folder, name, file) of a scenario given as path, TOML string or dict."""
    if isinstance(scenario, Mapping):
        text = _colloidsim.toml_from_json(json.dumps(dict(scenario), default=_jsonable))
        return text, os.getcwd(), "scenario", None
    if isinstance(scenario, os.PathLike) or (
        isinstance(scenario, str)
        and (os.path.isfile(scenario) or ("\n" not in scenario and "=" not in scenario))
    ):
        path = Path(scenario)
        if not path.is_file():
            raise ColloidsimError(f"cannot read scenario {path}: no such file")
        return "", str(path.parent), path.stem, str(path)
    if isinstance(scenario, str):
        return scenario, os.getcwd(), "scenario", None
    raise TypeError(
        "scenario must be a path, a TOML string or a dict, not " + type(scenario).__name__
    )


def _overrides(overrides: Optional[Union[Mapping[str, Any], Sequence[str]]]) -> str:
    """Overrides as the JSON list the extension reads: ``[key, value]`` pairs (from a dict) or
    ``"key.path=value"`` strings (read as the CLI's ``--set``)."""
    if overrides is None:
        return "[]"
    if isinstance(overrides, str):
        overrides = [overrides]
    if isinstance(overrides, Mapping):
        items: List[Any] = [[str(k), v] for k, v in overrides.items()]
    else:
        items = [str(o) for o in overrides]
    return json.dumps(items, default=_jsonable)


def _warn(report: Dict[str, Any]) -> None:
    for w in report.get("warnings", []):
        warnings.warn(w, stacklevel=3)


def _column(values: List[str]) -> np.ndarray:
    """A CSV column as floats (an empty field, a number that is not finite, as NaN), or as
    strings when it holds text (``observables.csv`` of an ensemble names its observables and
    may sweep text values)."""
    try:
        return np.array([float(x) if x.strip() else np.nan for x in values], dtype=float)
    except ValueError:
        return np.array([x.strip() for x in values], dtype=str)


class Table(Mapping[str, np.ndarray]):
    """A CSV table of a run: its columns as numpy arrays, by header name (``t["rho"]`` or
    ``t.rho``); numbers as floats, a column holding text as strings."""

    def __init__(self, path: Union[str, "os.PathLike[str]"]):
        self.path = Path(path)
        with open(self.path, newline="") as f:
            rows = list(csv.reader(f))
        self.columns: List[str] = [c.strip() for c in rows[0]] if rows else []
        self._data = {c: _column([r[k] for r in rows[1:]]) for k, c in enumerate(self.columns)}

    def __getitem__(self, key: str) -> np.ndarray:
        return self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.columns)

    def __len__(self) -> int:
        return len(self.columns)

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["_data"][name]
        except KeyError:
            raise AttributeError(
                f"{self.path.name} has no column {name!r} (columns: {', '.join(self.columns)})"
            ) from None

    def __repr__(self) -> str:
        n = len(next(iter(self._data.values()))) if self._data else 0
        return f"Table({self.path.name}: {', '.join(self.columns)}; {n} rows)"


class Result:
    """What a run or a theory solve wrote: ``out`` (the folder), ``summary`` (summary.json as a
    dict), ``files``, ``message``, ``warnings``, and every CSV table as a :class:`Table`, by
    file stem (``result.density``, ``result["profile_0.50"]``, ``result.tables``)."""

    def __init__(self, report: Dict[str, Any]):
        self.out = Path(report["out"])
        self.summary: Dict[str, Any] = report["summary"]
        self.files: List[str] = list(report["files"])
        self.message: str = report["message"]
        self.warnings: List[str] = list(report.get("warnings", []))
        self.tables: Dict[str, Table] = {}
        for name in sorted(os.listdir(self.out)):
            if name.endswith(".csv"):
                self.tables[name[:-4]] = Table(self.out / name)

    def __getitem__(self, name: str) -> Table:
        return self.tables[name]

    def __getattr__(self, name: str) -> Table:
        tables = self.__dict__.get("tables", {})
        if name in tables:
            return tables[name]
        raise AttributeError(
            f"{name!r}: no table {name}.csv in {self.__dict__.get('out')} "
            f"(tables: {', '.join(tables)})"
        )

    def __repr__(self) -> str:
        return f"Result({self.out}: {', '.join(self.tables)})"


def _out(out: Optional[Union[str, "os.PathLike[str]"]]) -> Optional[str]:
    return None if out is None else os.fspath(out)


def run(
    scenario: ScenarioLike,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    overrides: Optional[Union[Mapping[str, Any], Sequence[str]]] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    force: bool = False,
) -> Result:
    """Run a scenario and write its outputs (as ``colloidsim run``).

    ``out`` defaults to a new temporary folder (its path is ``result.out``); an existing
    non-empty folder is refused unless ``force``. ``seed`` replaces the scenario's; ``threads``
    sets the worker threads of this call (default: all cores). The run releases the GIL;
    Ctrl-C writes a checkpoint and raises ``KeyboardInterrupt``.
    """
    text, base, name, origin = _scenario(scenario)
    if out is None:
        out = tempfile.mkdtemp(prefix=f"colloidsim-{name}-")
    report = json.loads(
        _colloidsim.run(
            text, base, name, origin, _overrides(overrides), _out(out), seed, threads, force
        )
    )
    _warn(report)
    return Result(report)


def ensemble(
    scenario: ScenarioLike,
    replicas: int = 4,
    vary: Optional[Mapping[str, Sequence[Any]]] = None,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    overrides: Optional[Union[Mapping[str, Any], Sequence[str]]] = None,
    threads: Optional[int] = None,
    force: bool = False,
) -> Result:
    """Replicas of a scenario (seeds ``seed, seed + 1, ...``) at every point of a sweep (as
    ``colloidsim ensemble``): ``vary={"system.particles": [4, 6]}`` runs every combination of the
    listed values. Each member is a plain run in ``out/replica-R`` (``out/point-P/replica-R`` with
    a sweep); the tables the replicas share are written beside them with each column's mean and
    standard error (``COLUMN_err``), and the summaries' numbers into ``observables.csv``.
    ``result.headline`` (``headline.csv``) holds the method's headline observables as numpy
    arrays, one element per sweep point: the swept keys' values
    (``result.headline["system.particles"]``), ``replicas``, and each observable ``NAME`` (mean
    over the replicas) with its standard error ``NAME_err`` (NaN where a replica gave no value:
    ``result.summary["nulls"]`` says why); ``result.summary["headline"]`` gives each one's unit,
    meaning and columns, and ``headline_NAME.png`` pictures it against the first swept key.
    ``out`` defaults to a new temporary folder. Spreading members over MPI ranks is the CLI's
    (``mpirun -n 4 colloidsim ensemble ...``, docs/parallel.md)."""
    text, base, name, origin = _scenario(scenario)
    if out is None:
        out = tempfile.mkdtemp(prefix=f"colloidsim-{name}-ensemble-")
    pairs = [[k, list(v)] for k, v in (vary or {}).items()]
    report = json.loads(
        _colloidsim.ensemble(
            text,
            base,
            name,
            origin,
            _overrides(overrides),
            json.dumps(pairs),
            replicas,
            _out(out),
            threads,
            force,
        )
    )
    _warn(report)
    return Result(report)


def resume(
    folder: Union[str, "os.PathLike[str]"],
    seed: Optional[int] = None,
    threads: Optional[int] = None,
) -> Result:
    """Continue the interrupted run in ``folder`` from its checkpoint (as
    ``colloidsim run --restart folder``); the result is bitwise that of an uninterrupted run.
    An ensemble's folder (it holds ``ensemble.json``) is continued as ``colloidsim ensemble
    --restart folder``: completed members kept, interrupted ones resumed, the rest run."""
    if os.path.exists(os.path.join(os.fspath(folder), "ensemble.json")):
        if seed is not None:
            raise ColloidsimError("resume: an ensemble's seeds are its replicas; give no seed")
        report = json.loads(_colloidsim.resume_ensemble(os.fspath(folder), threads))
        _warn(report)
        return Result(report)
    report = json.loads(_colloidsim.resume(os.fspath(folder), seed, threads))
    _warn(report)
    return Result(report)


def theory(
    scenario: ScenarioLike,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    overrides: Optional[Union[Mapping[str, Any], Sequence[str]]] = None,
    dx: Optional[float] = None,
    force: bool = False,
    hydrodynamics: Optional[str] = None,
    pair: Optional[str] = None,
    threads: Optional[int] = None,
) -> Result:
    """The continuum counterpart of a scenario on the run's grid and file names (as
    ``colloidsim theory``); ``out`` defaults to a new temporary folder. ``hydrodynamics``:
    ``"free-draining"`` or ``"rpy"``; ``pair`` (RPY only): ``"dilute"`` or ``"trokhymchuk"``."""
    text, base, name, origin = _scenario(scenario)
    if out is None:
        out = tempfile.mkdtemp(prefix=f"colloidsim-{name}-theory-")
    report = json.loads(
        _colloidsim.theory(
            text,
            base,
            name,
            origin,
            _overrides(overrides),
            _out(out),
            dx,
            force,
            hydrodynamics,
            pair,
            threads,
        )
    )
    _warn(report)
    return Result(report)


def analyse(
    trajectory: Union[str, "os.PathLike[str]"],
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    force: bool = False,
    types: Optional[Sequence[str]] = None,
    frames: Optional[Union[str, slice]] = None,
    r_max: Optional[float] = None,
    bins: Optional[int] = None,
    contact_gap: Optional[float] = None,
    centre: Optional[Union[str, Sequence[float]]] = None,
    profile_bins: Optional[int] = None,
    dt: Optional[float] = None,
    percus_yevick: bool = False,
    threads: Optional[int] = None,
) -> Result:
    """Analyse a GSD trajectory (HOOMD schema; any program's) as ``colloidsim analyse``: g(r)
    with its standard error over frames (``gr``), S(q) (``sq``), the MSD (``msd``),
    coordination numbers and clusters, radial profiles about ``centre`` (``"origin"``,
    ``"com"`` or a point); ``frames`` a slice or ``"first:last:stride"`` (``last`` included);
    ``out`` defaults to a new temporary folder. docs/analyse.md lists the files."""
    if out is None:
        out = tempfile.mkdtemp(prefix=f"colloidsim-{Path(trajectory).stem}-analysis-")
    if isinstance(frames, slice):
        if frames.step is not None and frames.step < 1 or any(
            v is not None and v < 0 for v in (frames.start, frames.stop)
        ):
            raise ColloidsimError(f"frames: a slice without negative values, got {frames}")
        # A Python slice leaves its stop out; the CLI's range keeps its last frame.
        last = "" if frames.stop is None else str(frames.stop - 1)
        frames = f"{frames.start or 0}:{last}:{frames.step or 1}"
        if last == "-1":
            raise ColloidsimError("frames: an empty slice selects no frame")
    if centre is not None and not isinstance(centre, str):
        centre = ",".join(repr(float(c)) for c in centre)
    report = json.loads(
        _colloidsim.analyse(
            os.fspath(trajectory),
            _out(out),
            force,
            None if types is None else [str(t) for t in types],
            frames,
            r_max,
            bins,
            contact_gap,
            centre,
            profile_bins,
            dt,
            percus_yevick,
            threads,
        )
    )
    _warn(report)
    return Result(report)


def check(
    scenario: ScenarioLike,
    overrides: Optional[Union[Mapping[str, Any], Sequence[str]]] = None,
) -> Dict[str, Any]:
    """Validate a scenario (as ``colloidsim check``): the resolved parameters as a dict;
    warnings are issued as Python warnings."""
    text, base, name, origin = _scenario(scenario)
    c = json.loads(_colloidsim.check(text, base, name, origin, _overrides(overrides)))
    _warn(c)
    return c["resolved"]


def keys(method: str) -> List[Dict[str, str]]:
    """Every scenario key of ``method`` with its unit, default and allowed range."""
    return json.loads(_colloidsim.keys(method))


def methods() -> List[Dict[str, Any]]:
    """The registered methods: their ``method`` names, one line each, and their docs."""
    return json.loads(_colloidsim.methods())


class Periodic:
    """A trigger as HOOMD-blue's ``hoomd.trigger.Periodic``: true at the steps ``phase + k
    period`` (k = 0, 1, ...)."""

    def __init__(self, period: int, phase: int = 0):
        if int(period) < 1 or int(phase) < 0:
            raise ColloidsimError(
                f"period: must be >= 1 and phase >= 0, got period {period}, phase {phase}"
            )
        self.period, self.phase = int(period), int(phase)

    def __call__(self, step: int) -> bool:
        return step >= self.phase and (step - self.phase) % self.period == 0

    def next_after(self, step: int) -> int:
        """The first step after ``step`` at which the trigger is true."""
        if step < self.phase:
            return self.phase
        return step + self.period - (step - self.phase) % self.period

    def __repr__(self) -> str:
        return f"Periodic({self.period}, phase={self.phase})"


class Engine:
    """A method's engine, stepped by hand: built from a scenario, from keywords (the method's
    keys by name) or from arrays (:meth:`from_arrays`, :meth:`from_frame`).

    ``positions``, ``velocities`` and ``forces`` are numpy arrays (copies of the engine's state
    at the time of reading), shaped ``(N,)`` for rods and ``(N, 3)`` for spheres, in the
    particles' input order. ``positions``, ``velocities``, ``steps`` and ``seed`` can be set
    between runs (:meth:`set_state` sets several at once): the engine is then set up afresh from
    the new state, as if it had been built from it at that step.

    Analyzers and writers (``add_analyzer``) are Python callables run during ``step`` at the
    steps their trigger selects (a :class:`Periodic`, or any callable ``step -> bool``, which is
    asked after every step and so makes ``step`` advance one step at a time). Forces of one's
    own (``add_force``) are Python callables evaluated before every step (Brownian dynamics).
    """

    _method: Optional[Tuple[str, ...]] = None

    def __init__(
        self,
        scenario: Optional[ScenarioLike] = None,
        overrides: Optional[Union[Mapping[str, Any], Sequence[str]]] = None,
        seed: Optional[int] = None,
        method: Optional[str] = None,
        **keys: Any,
    ):
        """``Engine(scenario, overrides=None, seed=None)``, or ``Engine(method=..., **keys)``
        with the method's keys as keywords: by their path with underscores for dots
        (``run_dt``) or by their last name where it is unique (``dt``, ``kT``); a section as a
        dict; ``hydrodynamics="pse"`` (or ``"direct"``, ``"rpy"``, ``"free-draining"``)."""
        self.analyzers: List[Tuple[Any, Any]] = []
        self.custom_forces: List[Any] = []
        if scenario is None:
            m = self._method_for(method)
            scenario = _build.nested(m, _build.keyword_paths(m, keys), None)
        elif keys or method is not None:
            raise ColloidsimError(
                "keywords: give a scenario (and overrides) or the method's keys as keywords, not both"
            )
        text, base, name, origin = _scenario(scenario)
        self._engine = _colloidsim.Engine(text, base, name, origin, _overrides(overrides), seed)
        if self._method is not None and self._engine.method not in self._method:
            raise ColloidsimError(
                f"{type(self).__name__} takes a scenario with method = "
                f"{' or '.join(repr(m) for m in self._method)}, got {self._engine.method!r}"
            )

    @classmethod
    def _method_for(cls, method: Optional[str]) -> str:
        if method is None:
            if cls._method is not None and cls._method[0] == "bcd":
                return "bcd"
            if cls._method is None or len(cls._method) > 1:
                choices = " or ".join(repr(m) for m in cls._method) if cls._method else "a method"
                raise ColloidsimError(f"method: {cls.__name__} needs method = {choices}")
            return cls._method[0]
        if cls._method is not None and method not in cls._method:
            raise ColloidsimError(
                f"method: {cls.__name__} builds {' or '.join(repr(m) for m in cls._method)}, got {method!r}"
            )
        return method

    @classmethod
    def from_arrays(
        cls,
        positions: Any,
        box: Optional[Any] = None,
        types: Optional[Sequence[Any]] = None,
        diameters: Optional[Any] = None,
        type_names: Optional[Sequence[str]] = None,
        velocities: Optional[Any] = None,
        timestep: Optional[int] = None,
        seed: Optional[int] = None,
        method: Optional[str] = None,
        **keys: Any,
    ) -> "Engine":
        """An engine whose particles start at ``positions`` (``(N, 3)``; rods: ``(N,)``, sorted,
        unwrapped on the ring), with the method's other keys as keywords (see the constructor).

        - ``box``: the periodic box's edge (``bd``, ``hs-mc`` in bulk; a cube) or the ring's
          length (``bcd``); a droplet's size is its ``radius`` (or ``phi0``) keyword.
        - ``types``: each particle's typeid (int) or type name; ``type_names`` orders the names;
          ``diameters``: one number, one per type or one per particle (default 1). Types
          become the scenario's species ``A``, ``B``, ... in typeid order, each with its
          diameter and count.
        - ``velocities`` (DPD, MPCD), ``timestep`` (the steps done, as HOOMD names it) and
          ``seed`` as :meth:`set_state` takes them.

        Spheres (BD, Monte Carlo) are written exactly to a temporary GSD file that the
        scenario's ``system.initial`` reads, so the engine is bitwise the one built from that
        scenario. Rods (BCD) start on a lattice and are then given ``positions`` in the order
        given (a file would be read sorted into ``[0, L)``); DPD and MPCD, which start from
        their own solvent, are built from the keywords and then given ``positions`` (and
        velocities) of as many particles as the keywords make."""
        m = cls._method_for(method)
        kw = _build.keyword_paths(m, keys)
        rods = m.startswith("bcd")
        x = np.asarray(positions, dtype=float)
        n = len(x)
        shape = (n,) if rods else (n, 3)
        if x.shape != shape:
            raise ColloidsimError(f"positions: shape {shape} for {m}, got {x.shape}")
        start = _build.Start()
        try:
            if m in ("dpd", "mpcd", "droplet-mpcd"):
                if box is not None:
                    kw.setdefault("system.box_length" if m == "dpd" else "system.box", box)
                engine = cls(_build.nested(m, kw, seed))
                engine.set_state(positions=x, velocities=velocities, steps=timestep)
                return engine
            typeid, names, per = _build.species(n, types, type_names, diameters)
            ds, counts = _build.type_diameters(typeid, names, per)
            kw["system.particles"] = n
            if len(names) == 1:
                kw.setdefault("system.diameter", ds[0])
            else:
                kw["system.species.diameters"] = ds
                kw["system.species.counts"] = counts
            if rods:
                if box is None:
                    raise ColloidsimError("box: the ring's (or walls') length, required for rods")
                kw["system.length"] = float(np.asarray(box, dtype=float).ravel()[0])
                if len(names) != 1:
                    raise ColloidsimError("types: rods are one species")
                # On a lattice first, then at the positions in the order given (a file would
                # be read sorted into [0, L), turning the ring).
                kw["initial.placement"] = "lattice"
                engine = cls(_build.nested(m, kw, seed))
                engine.set_state(positions=x, steps=timestep)
                return engine
            else:
                if box is not None:
                    b = np.asarray(box, dtype=float).ravel()
                    if len(b) not in (1, 3) or np.any(b != b[0]):
                        raise ColloidsimError(f"box: a cube's edge (one number or three equal), got {b.tolist()}")
                    edge = float(b[0])
                    kw["system.box_length" if m == "bd" else "system.box"] = edge
                    box3 = [edge] * 3
                else:
                    if m == "bd" or (m == "hs-mc" and kw.get("system.geometry") == "bulk"):
                        raise ColloidsimError(f"box: the periodic cube's edge, required for {m} in bulk")
                    reach = float(np.abs(x).max()) if n else 1.0
                    box3 = [4.0 * reach + 4.0 * float(per.max())] * 3
                _colloidsim.write_initial_gsd(
                    start.path + ".gsd", box3, np.ascontiguousarray(x, dtype="<f8").tobytes(),
                    typeid.tolist(), names, per.tolist(),
                )
                kw["system.initial"] = start.path + ".gsd"
            engine = cls(_build.nested(m, kw, seed))
            if velocities is not None or timestep is not None:
                engine.set_state(velocities=velocities, steps=timestep)
            return engine
        except ColloidsimError as e:
            raise ColloidsimError(start.message(e)) from None
        finally:
            start.close()

    @classmethod
    def from_frame(
        cls,
        frame: Any,
        seed: Optional[int] = None,
        method: Optional[str] = None,
        **keys: Any,
    ) -> "Engine":
        """An engine started from a ``gsd.hoomd.Frame`` (or the last frame of a GSD file named
        by a path): its positions (exact where the frame logs ``particles/position_f64``, as
        :meth:`snapshot` and colloidsim's checkpoints write), box, types, diameters, velocities
        and step; the method's other keys as keywords (:meth:`from_arrays`)."""
        if isinstance(frame, (str, os.PathLike)):
            import gsd.hoomd

            with gsd.hoomd.open(os.fspath(frame), "r") as t:
                if len(t) == 0:
                    raise ColloidsimError(f"frame: {os.fspath(frame)} holds no frame")
                frame = t[len(t) - 1]
        m = cls._method_for(method)
        p, c = frame.particles, frame.configuration
        box = [float(v) for v in c.box[:3]]
        log = getattr(frame, "log", {}) or {}
        image = np.zeros((p.N, 3)) if p.image is None else np.asarray(p.image, dtype=float)
        if m.startswith("bcd"):
            if "rods/position_f64" in log:
                x = np.asarray(log["rods/position_f64"], dtype=float).ravel()
            else:
                x = np.asarray(p.position, dtype=float)[:, 0] + 0.5 * box[0] + image[:, 0] * box[0]
            args: Dict[str, Any] = {"box": box[0]}
        else:
            pos = log.get("particles/position_f64")
            x = np.asarray(p.position if pos is None else pos, dtype=float).reshape(-1, 3)
            args = {"box": box[0]} if m in ("bd",) or keys.get("geometry") == "bulk" else {}
            if m in ("dpd", "mpcd", "droplet-mpcd"):
                x = x + image * np.asarray(box)
        if m not in ("dpd", "mpcd", "droplet-mpcd"):
            args["types"] = None if p.typeid is None else np.asarray(p.typeid, dtype=np.int64)
            args["type_names"] = None if p.types is None else list(p.types)
            args["diameters"] = None if p.diameter is None else np.asarray(p.diameter, dtype=float)
        vel = log.get("particles/velocity_f64", p.velocity)
        if m in ("dpd", "mpcd", "droplet-mpcd") and vel is not None:
            args["velocities"] = np.asarray(vel, dtype=float).reshape(-1, 3)
        return cls.from_arrays(x, timestep=int(c.step or 0), seed=seed, method=m, **args, **keys)

    def add_analyzer(self, analyzer: Any, trigger: Any) -> None:
        """Call ``analyzer(engine)`` during ``step`` after every step ``trigger(step)`` selects
        (``trigger``: a :class:`Periodic`, an int period, or a callable ``step -> bool``). The
        analyzers are called in the order they were added; they see the engine at that step
        and leave its trajectory as it would be without them."""
        if isinstance(trigger, int):
            trigger = Periodic(trigger)
        if not callable(trigger):
            raise ColloidsimError(f"trigger: a Periodic, an int or a callable, got {trigger!r}")
        if not callable(analyzer):
            raise ColloidsimError(f"analyzer: must be callable, got {analyzer!r}")
        self.analyzers.append((trigger, analyzer))

    def add_force(self, force: Any) -> None:
        """Add ``force(engine)`` (a callable returning an ``(N, 3)`` array, input order) to the
        systematic forces: it is evaluated at the positions before every step, which ``step``
        then takes one at a time, as a built-in external or pair force would be (Brownian
        dynamics, ``bd`` and ``droplet-bd``; the sum of every added force). Slower than the
        built-in forces: docs/python.md measures it."""
        if not callable(force):
            raise ColloidsimError(f"force: must be callable, got {force!r}")
        self._engine.set_extra_forces(b"")  # refused by an engine that takes none
        self.custom_forces.append(force)

    def remove_force(self, force: Any) -> None:
        """Remove a force :meth:`add_force` added."""
        self.custom_forces.remove(force)
        if not self.custom_forces:
            self._engine.set_extra_forces(b"")

    def _apply_forces(self) -> None:
        n = self.particles
        total = np.zeros((n, 3))
        for f in self.custom_forces:
            a = np.asarray(f(self), dtype=float)
            if a.shape != (n, 3):
                raise ColloidsimError(f"force: {f!r} returned shape {a.shape}, expected ({n}, 3)")
            total += a
        self._engine.set_extra_forces(np.ascontiguousarray(total, dtype="<f8").tobytes())

    def step(self, steps: int = 1, threads: Optional[int] = None) -> None:
        """Advance ``steps`` steps (releases the GIL; Ctrl-C stops at a whole step), calling
        the analyzers at their trigger steps and the forces before every step on the way."""
        if steps < 0:
            raise ValueError(f"steps: must be >= 0, got {steps}")
        if not self.analyzers and not self.custom_forces:
            self._engine.step(steps, threads)
            return
        target = self.steps + steps
        while self.steps < target:
            now = self.steps
            nxt = min(
                [t.next_after(now) if hasattr(t, "next_after") else now + 1 for t, _ in self.analyzers]
                + [now + 1 if self.custom_forces else target]
            )
            if self.custom_forces:
                self._apply_forces()
            self._engine.step(min(nxt, target) - now, threads)
            for t, a in self.analyzers:
                if t(self.steps):
                    a(self)

    def run(self, steps: int, threads: Optional[int] = None) -> None:
        """:meth:`step` by the name HOOMD-blue's ``Simulation.run(steps)`` has."""
        self.step(steps, threads)

    def set_state(
        self,
        positions: Optional[Any] = None,
        velocities: Optional[Any] = None,
        steps: Optional[int] = None,
        seed: Optional[int] = None,
    ) -> None:
        """Replace what is given of the state at once; the engine is set up afresh from it, as
        if it had been built from it at that step (lists built, particles sorted), and is left
        as it was on an error (which names the argument). Positions are laid out as
        :attr:`positions` gives them (any periodic image: they are the unwrapped positions from
        then on)."""

        def raw(name: str, a: Optional[Any]) -> Optional[bytes]:
            if a is None:
                return None
            try:
                v = np.asarray(a, dtype=float)
            except (TypeError, ValueError) as e:
                raise ColloidsimError(f"{name}: not an array of numbers ({e})") from None
            return np.ascontiguousarray(v, dtype="<f8").tobytes()

        if steps is not None and (isinstance(steps, bool) or int(steps) != steps or steps < 0):
            raise ColloidsimError(f"steps: a whole number >= 0, got {steps!r}")
        if seed is not None and (isinstance(seed, bool) or int(seed) != seed or seed < 0):
            raise ColloidsimError(f"seed: a whole number in [0, 4294967295], got {seed!r}")
        self._engine.set_state(
            raw("positions", positions),
            raw("velocities", velocities),
            None if steps is None else int(steps),
            None if seed is None else int(seed),
        )

    def snapshot(self) -> Any:
        """The engine's state as a ``gsd.hoomd.Frame`` (needs the ``gsd`` package): step, box,
        positions in HOOMD's convention (a box centred on the origin, wrapped, with image
        flags), types and diameters, velocities where the engine has them, and the exact
        double-precision positions (and velocities) in the frame's log
        (``particles/position_f64``, as colloidsim's checkpoints), which :meth:`from_frame`
        reads. Rods: the line ``[0, L)`` as the x axis of a 2D box ``[L, L, 0]``, shifted by
        ``-L/2``, with image flags counting the turns of a ring; their exact unwrapped centres
        are logged as ``rods/position_f64``. ``gsd.hoomd.open(path, "w").append(engine.snapshot())``
        writes it."""
        import gsd.hoomd

        f = gsd.hoomd.Frame()
        f.configuration.step = int(self.steps)
        x = self.positions
        if self._engine.dimensions == 1:
            length = float(self.box[0])
            f.configuration.box = [length, length, 0.0, 0.0, 0.0, 0.0]
            f.configuration.dimensions = 2
            turns = np.floor(x / length)
            pos = np.zeros((len(x), 3))
            pos[:, 0] = x - turns * length - 0.5 * length
            image = np.zeros((len(x), 3), dtype=np.int32)
            image[:, 0] = turns.astype(np.int32)
            f.log["rods/position_f64"] = np.asarray(x, dtype=np.float64)
        else:
            b = np.asarray(self.box, dtype=float)
            f.configuration.box = [float(b[0]), float(b[1]), float(b[2]), 0.0, 0.0, 0.0]
            turns = np.floor(x / b + 0.5)
            pos = x - turns * b
            image = turns.astype(np.int32)
            f.log["particles/position_f64"] = np.ascontiguousarray(pos, dtype=np.float64)
            v = self.velocities
            if v is not None:
                f.particles.velocity = v.astype(np.float32)
                f.log["particles/velocity_f64"] = np.ascontiguousarray(v, dtype=np.float64)
        f.particles.N = len(pos)
        f.particles.position = pos.astype(np.float32)
        f.particles.image = image
        t = self._engine.types()
        if t is not None:
            names, typeid, diameter = t
            f.particles.types = list(names)
            f.particles.typeid = np.asarray(typeid, dtype=np.uint32)
            f.particles.diameter = np.asarray(diameter, dtype=np.float32)
        return f

    def _array(self, b: Optional[bytes]) -> Optional[np.ndarray]:
        if b is None:
            return None
        a = np.frombuffer(b, dtype="<f8")
        d = self._engine.dimensions
        return a if d == 1 else a.reshape(-1, d)

    @property
    def method(self) -> str:
        """The scenario's method."""
        return self._engine.method

    @property
    def positions(self) -> np.ndarray:
        """Positions (unwrapped where the engine keeps them so); settable (:meth:`set_state`)."""
        return self._array(self._engine.positions_bytes())

    @positions.setter
    def positions(self, value: Any) -> None:
        self.set_state(positions=value)

    @property
    def velocities(self) -> Optional[np.ndarray]:
        """Velocities (DPD, MPCD); None for Brownian engines, which have none; settable."""
        return self._array(self._engine.velocities_bytes())

    @velocities.setter
    def velocities(self, value: Any) -> None:
        self.set_state(velocities=value)

    @property
    def forces(self) -> np.ndarray:
        """Forces: for Brownian engines the systematic force at the current positions (with
        the forces of :meth:`add_force` as last evaluated); for DPD the total force of the
        last step (conservative, dissipative and random)."""
        return self._array(self._engine.forces_bytes())

    @property
    def steps(self) -> int:
        """Steps done; settable (the time is ``steps * dt``, the random streams are keyed by
        it)."""
        return self._engine.steps

    @steps.setter
    def steps(self, value: int) -> None:
        self.set_state(steps=value)

    @property
    def seed(self) -> int:
        """Seed of the counter-based random streams; settable."""
        return self._engine.seed

    @seed.setter
    def seed(self, value: int) -> None:
        self.set_state(seed=value)

    @property
    def time(self) -> float:
        """Simulated time."""
        return self._engine.time

    @property
    def dt(self) -> float:
        """Time step."""
        return self._engine.dt

    @property
    def particles(self) -> int:
        """Number of particles."""
        return self._engine.particles

    @property
    def box(self) -> np.ndarray:
        """System length (rods) or box edges (spheres)."""
        return np.array(self._engine.box_lengths)

    def __repr__(self) -> str:
        if "_engine" not in self.__dict__:
            return f"{type(self).__name__}(not built)"
        return (
            f"{type(self).__name__}({self.method}: {self.particles} particles, "
            f"step {self.steps}, t = {self.time:g})"
        )


class BCD(Engine):
    """1D Brownian cluster dynamics (``method = "bcd"`` or ``"bcd-chronological"``)."""

    _method = ("bcd", "bcd-chronological")


class BrownianDynamics(Engine):
    """Brownian dynamics of WCA spheres, replica 0: a drying or static droplet
    (``method = "droplet-bd"``) or a periodic cube (``method = "bd"``), free draining or with
    RPY hydrodynamics as the scenario's ``[hydrodynamics]`` says. ``positions`` are wrapped
    into the box (input order); ``forces`` are the systematic forces (WCA, the droplet's
    interface or the body force); ``box`` the periodic box's edges."""

    _method = ("droplet-bd", "bd")


class DPD(Engine):
    """DPD colloids in explicit solvent (``method = "dpd"``)."""

    _method = ("dpd",)


class MonteCarlo(Engine):
    """Hard-sphere Monte Carlo (``method = "hs-mc"``); one step is one sweep of N trial moves
    (the move size is the scenario's starting one: the run path's warm-up tuning is not done)."""

    _method = ("hs-mc",)


class MPCD(Engine):
    """MPCD (``method = "mpcd"`` or ``"droplet-mpcd"``): one step is one streaming step, the
    colloids' velocity-Verlet steps over it, and one collision. The arrays hold the solvent (in
    storage order), then the colloids' centres (unwrapped), then their vertices (42 per colloid,
    colloid by colloid); ``forces`` are zero on the solvent and, on the colloids, the bonds, the
    WCA between centres and the droplet's interface."""

    _method = ("mpcd", "droplet-mpcd")
