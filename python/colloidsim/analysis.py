"""Observables of particle configurations on numpy arrays or ``gsd.hoomd.Frame`` objects: the
functions behind ``colloidsim analyse`` (docs/analyse.md), one frame at a time.

A *system* is a ``gsd.hoomd.Frame`` (box, positions, diameters and types are read from it), or a
pair ``(box, positions)`` as freud takes it, the box an edge ``L``, three edges or HOOMD's six
numbers (tilts must be zero)::

    import colloidsim.analysis as ca
    r, g = ca.rdf((10.0, x), r_max=4.0, bins=80)        # g(r) of one frame
    r, g = ca.rdf(frame, r_max=4.0)                      # a gsd.hoomd.Frame
    msd = ca.msd(frames_positions, images, box=10.0)     # (F, N, 3) wrapped plus images
    bonds = ca.contacts(frame, gap=0.05)                 # (M, 2) pairs i < j
    labels = ca.cluster_labels(len(x), bonds)
    r, phi, n = ca.radial_profile(frame, centre="com", r_max=12.0, bins=40)
    q, s = ca.structure_factor(r, g, rho=0.4)

Lengths are in the positions' unit. Errors raise :class:`ColloidsimError` naming the argument.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np

from . import _colloidsim
from ._colloidsim import ColloidsimError

__all__ = [
    "ColloidsimError",
    "cluster_labels",
    "contacts",
    "coordination",
    "msd",
    "radial_profile",
    "rdf",
    "structure_factor",
]


def _box(box: Any) -> Tuple[float, float, float]:
    b = np.atleast_1d(np.asarray(box, dtype=float))
    if b.size == 1:
        b = np.repeat(b, 3)
    elif b.size == 6:
        if np.any(b[3:] != 0.0):
            raise ColloidsimError("box: tilted (triclinic) boxes are not supported")
        b = b[:3]
    elif b.size != 3:
        raise ColloidsimError(f"box: an edge, three edges or HOOMD's six numbers, got {b.size}")
    if not np.all(np.isfinite(b)) or np.any(b <= 0.0):
        raise ColloidsimError(f"box: edges must be positive and finite, got {list(b)}")
    return float(b[0]), float(b[1]), float(b[2])


def _positions(x: Any, name: str = "positions") -> np.ndarray:
    a = np.ascontiguousarray(np.asarray(x, dtype="<f8"))
    if a.ndim != 2 or a.shape[1] != 3:
        raise ColloidsimError(f"{name}: shape (N, 3) expected, got {a.shape}")
    return a


def _system(system: Any) -> Tuple[Tuple[float, float, float], np.ndarray, np.ndarray]:
    """(box edges, positions (N, 3), diameters (N,)) of a gsd Frame or a (box, positions) pair."""
    if hasattr(system, "configuration") and hasattr(system, "particles"):
        box = _box(system.configuration.box)
        x = _positions(system.particles.position)
        d = system.particles.diameter
        d = np.ones(len(x)) if d is None else np.asarray(d, dtype=float)
        return box, x, d
    try:
        box, x = system
    except (TypeError, ValueError):
        raise ColloidsimError(
            "system: a gsd.hoomd.Frame or a pair (box, positions)"
        ) from None
    x = _positions(x)
    return _box(box), x, np.ones(len(x))


def _diameters(d: Optional[Any], default: np.ndarray) -> list:
    if d is None:
        return [float(v) for v in default]
    a = np.asarray(d, dtype=float)
    if a.ndim == 0:
        a = np.full(len(default), float(a))
    return [float(v) for v in a]


def rdf(system: Any, r_max: Optional[float] = None, bins: int = 200) -> Tuple[np.ndarray, np.ndarray]:
    """g(r) of one frame: bin centres ``r`` and ``g``, normalised by ``N^2 / V`` times the shell
    volume (freud's default ``exact`` mode); ``r_max`` defaults to 0.49 of the shortest edge."""
    box, x, _ = _system(system)
    if r_max is None:
        r_max = 0.49 * min(box)
    r, g = _colloidsim.analysis_rdf(x.tobytes(), list(box), float(r_max), int(bins))
    return np.array(r), np.array(g)


def msd(positions: Any, images: Optional[Any] = None, box: Optional[Any] = None) -> np.ndarray:
    """Mean-squared displacement at lags 1 .. F-1 (in frames), over every time origin and
    particle, from positions of shape (F, N, 3): unwrapped ones, or wrapped ones with their
    image flags ``images`` (F, N, 3) and the ``box``."""
    p = np.asarray(positions, dtype=float)
    if p.ndim != 3 or p.shape[2] != 3 or p.shape[0] < 2:
        raise ColloidsimError(f"positions: shape (F, N, 3) with F >= 2 expected, got {p.shape}")
    if images is not None:
        if box is None:
            raise ColloidsimError("box: needed with images")
        i = np.asarray(images)
        if i.shape != p.shape:
            raise ColloidsimError(f"images: shape {p.shape} expected, got {i.shape}")
        p = p + i * np.array(_box(box))
    n = p.shape[1]
    out = _colloidsim.analysis_msd(np.ascontiguousarray(p, dtype="<f8").tobytes(), n)
    return np.array(out)


def contacts(system: Any, gap: Optional[float] = None, diameters: Optional[Any] = None) -> np.ndarray:
    """Pairs (i, j), i < j, of spheres whose surface gap ``r - (d_i + d_j) / 2`` under the
    minimum image is below ``gap`` (default 0.1 mean diameters), as an (M, 2) array."""
    box, x, d0 = _system(system)
    d = _diameters(diameters, d0)
    if gap is None:
        gap = 0.1 * (sum(d) / len(d) if d else 1.0)
    if not math.isfinite(float(gap)):
        raise ColloidsimError(f"gap: must be finite, got {gap}")
    flat = _colloidsim.analysis_contacts(x.tobytes(), [0.5 * v for v in d], list(box), float(gap))
    return np.array(flat, dtype=np.int64).reshape(-1, 2)


def cluster_labels(n: int, bonds: Any) -> np.ndarray:
    """Cluster label of each of ``n`` particles joined by ``bonds`` ((M, 2) pairs): clusters
    numbered 0, 1, ... in the order of their lowest-indexed particle."""
    b = np.asarray(bonds, dtype=np.int64).reshape(-1)
    if np.any(b < 0):
        raise ColloidsimError("bonds: indices must be non-negative")
    return np.array(_colloidsim.analysis_cluster_labels(int(n), [int(v) for v in b]))


def coordination(n: int, bonds: Any) -> np.ndarray:
    """Number of bonds of each of ``n`` particles."""
    b = np.asarray(bonds, dtype=np.int64).reshape(-1)
    if np.any(b < 0) or np.any(b >= n):
        raise ColloidsimError(f"bonds: indices must lie in [0, {n})")
    return np.bincount(b, minlength=int(n))


def radial_profile(
    system: Any,
    centre: Union[str, Sequence[float]] = "origin",
    r_max: Optional[float] = None,
    bins: int = 50,
    diameters: Optional[Any] = None,
    images: Optional[Any] = None,
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Radial profiles about ``centre`` (``"origin"``, ``"com"`` or a point): shell mid-points,
    the volume fraction by sphere-shell overlap and the number density by centre binning.
    ``"com"`` takes the centre of mass of the unwrapped positions (``images`` of a gsd Frame
    are read from it)."""
    box, x, d0 = _system(system)
    d = _diameters(diameters, d0)
    if images is None and hasattr(system, "particles") and system.particles.image is not None:
        images = system.particles.image
    if isinstance(centre, str):
        if centre == "origin":
            c = [0.0, 0.0, 0.0]
        elif centre == "com":
            if images is not None:
                x = x + np.asarray(images) * np.array(box)
            c = [float(v) for v in x.mean(axis=0)]
        else:
            raise ColloidsimError(f"centre: 'origin', 'com' or a point, got {centre!r}")
    else:
        c = [float(v) for v in np.asarray(centre, dtype=float).reshape(-1)]
        if len(c) != 3:
            raise ColloidsimError(f"centre: three coordinates expected, got {len(c)}")
    if r_max is None:
        r_max = 0.5 * min(box)
    r, phi, n = _colloidsim.analysis_radial_profile(
        np.ascontiguousarray(x, dtype="<f8").tobytes(), d, c, float(r_max), int(bins)
    )
    return np.array(r), np.array(phi), np.array(n)


def structure_factor(
    r: Any, g: Any, rho: float, q: Optional[Any] = None
) -> Tuple[np.ndarray, np.ndarray]:
    """S(q) from g(r) on evenly spaced bins (Lorch window, as runs write ``sq.csv``); ``q``
    defaults to ``k pi / r_max``, k = 2 .. bins."""
    r = np.asarray(r, dtype=float)
    if q is None:
        if r.size < 2:
            raise ColloidsimError("r: at least two bins")
        edge = r[-1] + 0.5 * (r[1] - r[0])
        q = np.arange(2, r.size + 1) * np.pi / edge
    q = np.asarray(q, dtype=float)
    s = _colloidsim.analysis_structure_factor(
        [float(v) for v in r], [float(v) for v in np.asarray(g, dtype=float)], float(rho), [float(v) for v in q]
    )
    return q, np.array(s)
