"""Engines from keywords and arrays: the scenario a set of keywords and particles stands for.

Keywords name a method's keys (``colloidsim.keys(method)``) by their dotted path with the dots
written as underscores (``run_dt``, ``system_species_diameters``), or by their last name where
no other key of the method ends so (``dt``, ``kT``, ``viscosity``); a section takes a dict
(``hydrodynamics={"model": "rpy", "tolerance": 1e-4}``).
"""

from __future__ import annotations

import difflib
import os
import tempfile
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from . import _colloidsim
from ._colloidsim import ColloidsimError

# The run's length: an engine stepped by hand does not read it, so it is filled in when left out.
_RUN_LENGTH = {"bd": "run.time", "bcd": "run.time", "bcd-chronological": "run.time", "mpcd": "run.collisions"}

# `hydrodynamics="..."`: the mobility by one word.
_HYDRO_WORDS = {
    "free-draining": {"model": "free-draining"},
    "rpy": {"model": "rpy"},
    "pse": {"model": "rpy", "method": "pse"},
    "direct": {"model": "rpy", "method": "direct"},
}


def _key_paths(method: str) -> List[str]:
    import json

    return [k["path"] for k in json.loads(_colloidsim.keys(method))]


def keyword_paths(method: str, keywords: Mapping[str, Any]) -> Dict[str, Any]:
    """The keys (dotted path -> value) that ``keywords`` name for ``method``."""
    paths = _key_paths(method)
    alias: Dict[str, str] = {p.replace(".", "_"): p for p in paths}
    by_last: Dict[str, List[str]] = {}
    for p in paths:
        by_last.setdefault(p.rsplit(".", 1)[-1], []).append(p)
    for name, ps in by_last.items():
        if len(ps) == 1:
            alias.setdefault(name, ps[0])
    out: Dict[str, Any] = {}
    for name, value in keywords.items():
        path = alias.get(name)
        if path is None:
            close = difflib.get_close_matches(name, list(alias), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ColloidsimError(
                f"{name}: not a key of {method} scenarios (colloidsim.keys({method!r}) lists them: "
                f"name one by its path with underscores, e.g. run_dt, or by its last name where "
                f"that is unique){hint}"
            )
        if path == "hydrodynamics" and isinstance(value, str):
            if value not in _HYDRO_WORDS:
                raise ColloidsimError(
                    f"hydrodynamics: one of {', '.join(map(repr, _HYDRO_WORDS))} or a dict of the "
                    f"section's keys, got {value!r}"
                )
            value = _HYDRO_WORDS[value]
        if isinstance(value, Mapping):
            for k, v in _flatten(value):
                out[f"{path}.{k}"] = v
        else:
            out[path] = value
    return out


def _flatten(d: Mapping[str, Any], prefix: str = "") -> List[Tuple[str, Any]]:
    items: List[Tuple[str, Any]] = []
    for k, v in d.items():
        if isinstance(v, Mapping):
            items.extend(_flatten(v, f"{prefix}{k}."))
        else:
            items.append((f"{prefix}{k}", v))
    return items


def nested(method: str, keys: Mapping[str, Any], seed: Optional[int]) -> Dict[str, Any]:
    """The scenario dict of ``keys`` (dotted paths), with the run's length filled in where an
    engine does not need it."""
    keys = dict(keys)
    length = _RUN_LENGTH.get(method)
    if length is not None and length not in keys:
        keys[length] = 1e4 * keys.get("run.dt", 1.0) if length == "run.time" else 1
    sc: Dict[str, Any] = {"method": method}
    if seed is not None:
        sc["seed"] = int(seed)
    for path, value in keys.items():
        if isinstance(value, np.ndarray):
            value = value.tolist()
        elif isinstance(value, np.generic):
            value = value.item()
        node = sc
        parts = path.split(".")
        for p in parts[:-1]:
            node = node.setdefault(p, {})
            if not isinstance(node, dict):
                raise ColloidsimError(f"{path}: {p} is a key, not a section")
        node[parts[-1]] = value
    return sc


def species(
    n: int,
    types: Optional[Sequence[Any]],
    type_names: Optional[Sequence[str]],
    diameters: Optional[Any],
) -> Tuple[np.ndarray, List[str], np.ndarray]:
    """Each particle's typeid, the type names and each particle's diameter from what was given:
    ``types`` as typeids (ints) or names, ``diameters`` as one number, one per type or one per
    particle (default 1)."""
    if types is None:
        typeid = np.zeros(n, dtype=np.uint32)
        names = list(type_names) if type_names is not None else ["A"]
    else:
        t = np.asarray(types)
        if t.shape != (n,):
            raise ColloidsimError(f"types: one per particle, {n}, got shape {t.shape}")
        if t.dtype.kind in "US" or t.dtype == object:
            names = list(type_names) if type_names is not None else list(dict.fromkeys(t.tolist()))
            index = {s: i for i, s in enumerate(names)}
            missing = [s for s in dict.fromkeys(t.tolist()) if s not in index]
            if missing:
                raise ColloidsimError(f"types: {missing[0]!r} is not in type_names {names}")
            typeid = np.array([index[s] for s in t.tolist()], dtype=np.uint32)
        elif t.dtype.kind in "iu":
            if n and t.min() < 0:
                raise ColloidsimError(f"types: typeids must be >= 0, got {t.min()}")
            typeid = t.astype(np.uint32)
            count = int(typeid.max()) + 1 if n else 1
            names = list(type_names) if type_names is not None else [chr(65 + i) for i in range(count)]
            if n and int(typeid.max()) >= len(names):
                raise ColloidsimError(f"types: typeid {int(typeid.max())} but {len(names)} type names")
        else:
            raise ColloidsimError(f"types: typeids (ints) or names (str), got dtype {t.dtype}")
    d = np.asarray(1.0 if diameters is None else diameters, dtype=float)
    if d.ndim == 0:
        per = np.full(n, float(d))
    elif d.shape == (n,):
        per = d.copy()
    elif d.shape == (len(names),):
        per = d[typeid]
    else:
        raise ColloidsimError(
            f"diameters: one number, one per type ({len(names)}) or one per particle ({n}), got shape {d.shape}"
        )
    return typeid, names, per


def type_diameters(typeid: np.ndarray, names: List[str], per: np.ndarray) -> Tuple[List[float], List[int]]:
    """Each type's diameter and count; every particle of a type must share its diameter."""
    ds, counts = [], []
    for t in range(len(names)):
        of = per[typeid == t]
        if len(of) and np.any(of != of[0]):
            raise ColloidsimError(
                f"diameters: the particles of type {names[t]!r} have diameters from {of.min()} to "
                f"{of.max()}; one diameter per type (species)"
            )
        ds.append(float(of[0]) if len(of) else 1.0)
        counts.append(int(len(of)))
    return ds, counts


class Start:
    """A temporary folder holding the start file of an engine built from arrays; the file's
    path in error messages is replaced by what it stands for."""

    def __init__(self) -> None:
        self._dir = tempfile.TemporaryDirectory(prefix="colloidsim-start-")
        self.path = os.path.join(self._dir.name, "start")

    def message(self, e: Exception) -> str:
        return str(e).replace(self.path + ".gsd", "(the positions given)")

    def close(self) -> None:
        self._dir.cleanup()
