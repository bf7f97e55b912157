"""Hydrodynamic mobility operators on numpy arrays, shaped as libMobility's Python interface.

A libMobility user moves to the CPU by changing the import::

    from colloidsim.hydro import NBody, PSE      # was: from libMobility import NBody, PSE

    solver = PSE(periodicityX="periodic", periodicityY="periodic", periodicityZ="periodic")
    solver.setParameters(psi=0.5, Lx=32.0, Ly=32.0, Lz=32.0)
    solver.initialize(viscosity=1.0, hydrodynamicRadius=1.0)
    solver.setPositions(positions)                 # shape (N, 3) or (3N,)
    mf, _ = solver.Mdot(forces)                    # M F, shaped as forces
    dw, _ = solver.sqrtMdotW(prefactor=1.0)        # prefactor M^(1/2) W, shaped as positions
    dx, _ = solver.LangevinVelocities(dt, kbt, forces)

- :class:`NBody`: the Rotne-Prager-Yamakawa mobility in an unbounded fluid by direct O(N^2)
  sums (both branches: overlapping spheres included); unequal radii (Zuk et al. 2014).
- :class:`PSE`: the RPY mobility in a periodic cube by positively split Ewald (Fiore et al.
  2017), O(N log N); unequal radii (one sinc filter per distinct radius, at most 8).
- :class:`SelfMobility`: free draining, ``M = I / (6 pi eta a)``.

They run colloidsim's engines' own operators (``crates/hydro``), in double precision, on all
cores; the noise is the engines' (keyed by seed and noise step), so a displacement equals a
colloidsim Brownian-dynamics step at the same positions, seed and step to round-off. Where this
module differs from libMobility: docs/python-hydro.md. Errors raise :class:`ColloidsimError`
(a ``RuntimeError``, as libMobility's errors are) naming the argument at fault.
"""

from __future__ import annotations

import math
import os
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _colloidsim
from ._colloidsim import ColloidsimError

__all__ = ["NBody", "PSE", "SelfMobility", "ColloidsimError"]

ArrayLike = Union[np.ndarray, Sequence[float], Sequence[Sequence[float]]]

_PERIODICITIES = ("open", "unspecified", "single_wall", "two_walls", "periodic")

# The Lanczos iteration limit of colloidsim's runs (`[hydrodynamics] max_iterations`).
_MAX_ITERATIONS = 200


def _number(name: str, value: Any, positive: bool = True) -> float:
    """A finite float (> 0 if ``positive``), else ColloidsimError naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ColloidsimError(f"{name}: must be a number, got {value!r}") from None
    if not math.isfinite(v) or (positive and v <= 0.0):
        raise ColloidsimError(
            f"{name}: must be a finite number{' > 0' if positive else ''}, got {value!r}"
        )
    return v


def _vectors(name: str, a: Any, n: Optional[int] = None) -> Tuple[np.ndarray, Tuple[int, ...]]:
    """``a`` as a C-contiguous float64 array of 3N numbers, with its shape ((N, 3) or (3N,));
    errors name ``name``."""
    try:
        x = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ColloidsimError(f"{name}: not an array of numbers ({e})") from None
    shape = x.shape
    if not (x.ndim == 1 and x.size % 3 == 0) and not (x.ndim == 2 and shape[1] == 3):
        raise ColloidsimError(f"{name}: must have shape (N, 3) or (3N,), got {shape}")
    if n is not None and x.size != 3 * n:
        raise ColloidsimError(f"{name}: {x.size // 3} particles, the positions have {n}")
    if not np.all(np.isfinite(x)):
        bad = int(np.flatnonzero(~np.isfinite(x.reshape(-1)))[0]) // 3
        raise ColloidsimError(f"{name}: particle {bad} has a non-finite component")
    return np.ascontiguousarray(x.reshape(-1), dtype="<f8"), shape


class _Solver:
    """The interface every solver shares (libMobility's ``libmobility::Mobility``)."""

    #: Precision of the arithmetic (libMobility: "float" or "double" per build); always double.
    precision = "double"
    _method = ""
    _accepts: Tuple[Tuple[str, ...], Tuple[str, ...], Tuple[str, ...]] = ((), (), ())

    def __init__(self, periodicityX: str, periodicityY: str, periodicityZ: str):
        for name, value, ok in zip(
            ("periodicityX", "periodicityY", "periodicityZ"),
            (periodicityX, periodicityY, periodicityZ),
            self._accepts,
        ):
            if value not in _PERIODICITIES:
                raise ColloidsimError(
                    f"{name}: one of {', '.join(map(repr, _PERIODICITIES))}, got {value!r}"
                )
            if value not in ok:
                raise ColloidsimError(
                    f"{name}: {type(self).__name__} takes {' or '.join(map(repr, ok))}, got "
                    f"{value!r} (colloidsim has no {value} geometry; docs/python-hydro.md)"
                )
        self.periodicity = (periodicityX, periodicityY, periodicityZ)
        self._init: Optional[dict] = None
        self._op: Any = None
        self._op_key: Any = None
        self._positions: Optional[np.ndarray] = None
        self._shape: Optional[Tuple[int, ...]] = None
        self._seed = 0
        self._rng = np.random.default_rng()
        #: Noise step of the next random call (sqrtMdotW, LangevinVelocities, thermalDrift):
        #: the noise is a function of (seed, noise step, particle); each call advances it.
        self.noiseStep = 0

    # --- the common interface -------------------------------------------------------------

    def initialize(
        self,
        viscosity: float,
        hydrodynamicRadius: Union[float, ArrayLike],
        includeAngular: bool = False,
        tolerance: float = 1e-4,
        seed: Optional[int] = None,
        lanczos_callback: Optional[Callable[[int, float], Any]] = None,
        maxIterations: int = _MAX_ITERATIONS,
    ) -> None:
        """Set the fluid and the spheres; call :meth:`setParameters` first where the solver
        has one. ``hydrodynamicRadius``: one radius, or one per particle (colloidsim's
        extension: unequal radii). ``tolerance``: of the Lanczos square root (and of the PSE
        product), in (0, 1e-2]. ``seed``: of the noise, in [1, 2^32 - 1] (None: a random one).
        ``lanczos_callback(iterations, residual)`` is called once after each square root
        (libMobility calls it every iteration). ``maxIterations`` (colloidsim's): the Lanczos
        limit. ``includeAngular=True`` is refused: colloidsim has no rotational mobility."""
        if includeAngular:
            raise ColloidsimError(
                "includeAngular: colloidsim's mobilities are translational only; must be False"
            )
        eta = _number("viscosity", viscosity)
        radius = None
        if not np.isscalar(hydrodynamicRadius):
            radius = np.asarray(hydrodynamicRadius, dtype=np.float64)
            if radius.ndim == 0:
                radius = None
        if radius is None:
            a: Union[float, np.ndarray] = _number("hydrodynamicRadius", hydrodynamicRadius)
        else:
            if radius.ndim != 1 or radius.size == 0:
                raise ColloidsimError(
                    f"hydrodynamicRadius: one number or one per particle, got shape {radius.shape}"
                )
            if not np.all(np.isfinite(radius) & (radius > 0)):
                i = int(np.flatnonzero(~(np.isfinite(radius) & (radius > 0)))[0])
                raise ColloidsimError(
                    f"hydrodynamicRadius: must be finite and > 0, got {radius[i]} (particle {i})"
                )
            a = radius.copy()
        tol = _number("tolerance", tolerance)
        if tol > 1e-2:
            raise ColloidsimError(f"tolerance: must lie in (0, 0.01], got {tolerance!r}")
        if (
            isinstance(maxIterations, bool)
            or not isinstance(maxIterations, (int, np.integer))
            or not 1 <= maxIterations <= 1000
        ):
            raise ColloidsimError(f"maxIterations: an integer in [1, 1000], got {maxIterations!r}")
        if seed is None or seed == 0:
            # libMobility: None or 0 draws a random seed.
            s = int.from_bytes(os.urandom(4), "little") or 1
        else:
            if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
                0 < seed < 2**32
            ):
                raise ColloidsimError(f"seed: an integer in [1, 4294967295], got {seed!r}")
            s = int(seed)
        if lanczos_callback is not None and not callable(lanczos_callback):
            raise ColloidsimError("lanczos_callback: must be callable or None")
        self._check_parameters()
        self._init = dict(
            viscosity=eta, radius=a, tolerance=tol, max_iterations=int(maxIterations)
        )
        self._seed = s
        self._rng = np.random.default_rng(s)
        self._callback = lanczos_callback
        self.noiseStep = 0
        self._op = None
        # As libMobility, positions given before stay in force (when the radii fit them).
        if self._positions is not None:
            n = self._positions.size // 3
            if not isinstance(a, np.ndarray) or a.size == n:
                self.setPositions(self._positions.reshape(self._shape))
            else:
                self._positions = None

    def setPositions(self, positions: ArrayLike) -> None:
        """The positions the mobility is computed at, shape (N, 3) or (3N,); results of
        :meth:`sqrtMdotW` and :meth:`divM` take this shape."""
        if self._init is None:
            raise ColloidsimError("initialize: call initialize before setPositions")
        x, shape = _vectors("positions", positions)
        n = x.size // 3
        if n == 0:
            raise ColloidsimError("positions: no particles")
        radius = self._init["radius"]
        if isinstance(radius, np.ndarray) and radius.size != n:
            raise ColloidsimError(
                f"hydrodynamicRadius: {radius.size} radii for {n} particles in positions"
            )
        key = n
        if self._op is None or self._op_key != key:
            radii = list(radius) if isinstance(radius, np.ndarray) else [radius] * n
            self._op = _colloidsim.HydroOperator(
                self._method,
                radii,
                self._init["viscosity"],
                self._init["tolerance"],
                self._init["max_iterations"],
                self._seed,
                **self._extra(),
            )
            self._op_key = key
        self._op.set_positions(x.tobytes())
        self._positions = x
        self._shape = shape

    def Mdot(
        self, forces: Optional[ArrayLike] = None, torques: Optional[ArrayLike] = None
    ) -> Tuple[np.ndarray, None]:
        """``(M F, None)``; ``M F`` has the shape of ``forces``."""
        op = self._ready()
        self._no_torques(torques)
        if forces is None:
            raise ColloidsimError("forces: give the forces (colloidsim has no torques)")
        f, shape = _vectors("forces", forces, op.particles)
        u = np.frombuffer(op.mdot(f.tobytes()), dtype="<f8").reshape(shape)
        return u.copy(), None

    def sqrtMdotW(self, prefactor: float = 1.0) -> Tuple[np.ndarray, None]:
        """``(prefactor M^(1/2) W, None)``, W standard normal (no ``sqrt(2 kT)``: as
        libMobility), shaped as the positions; Lanczos square root to ``tolerance`` (PSE: the
        wave-space part drawn exactly). Each call draws new noise (advances ``noiseStep``)."""
        op = self._ready()
        p = _number("prefactor", prefactor, positive=False)
        if p == 0.0:
            return np.zeros(self._shape), None
        w = op.sqrt_mdot_w(self._next_step(), p)
        self._report()
        return np.frombuffer(w, dtype="<f8").reshape(self._shape).copy(), None

    def divM(self, prefactor: float = 1.0) -> Tuple[np.ndarray, None]:
        """``(prefactor div M, None)``: zero exactly, as in libMobility's open and periodic
        solvers (the RPY tensor is divergence-free, equal or unequal radii). A random finite
        difference estimate of it: :meth:`thermalDrift`."""
        self._ready()
        _number("prefactor", prefactor, positive=False)
        return np.zeros(self._shape), None

    def thermalDrift(
        self, prefactor: float = 1.0, delta: Optional[float] = None
    ) -> Tuple[np.ndarray, None]:
        """One random-finite-difference sample of ``prefactor div M`` (colloidsim's;
        libMobility's ``random_finite_differences``): ``(M(x + d W/2) W - M(x - d W/2) W) / d``
        with W standard normal, ``d = delta`` times the (smallest) radius (default: the
        ``delta`` of setParameters, 1e-3). Its mean over W is ``div M`` to O(d^2); for a
        position-dependent mobility it is the Ito drift ``kT div M`` with ``prefactor = kT``.
        The positions are restored afterwards."""
        op = self._ready()
        p = _number("prefactor", prefactor, positive=False)
        d = _number("delta", self._delta if delta is None else delta)
        radius = self._init["radius"]
        step = d * float(np.min(radius))
        x0 = self._positions
        rng = np.random.Generator(np.random.PCG64([self._seed, self._next_step()]))
        w = rng.standard_normal(x0.size)
        try:
            op.set_positions((x0 + 0.5 * step * w).tobytes())
            plus = np.frombuffer(op.mdot(w.tobytes()), dtype="<f8")
            op.set_positions((x0 - 0.5 * step * w).tobytes())
            minus = np.frombuffer(op.mdot(w.tobytes()), dtype="<f8")
        finally:
            op.set_positions(x0.tobytes())
        return ((p / step) * (plus - minus)).reshape(self._shape), None

    def LangevinVelocities(
        self,
        dt: float,
        kbt: float,
        forces: Optional[ArrayLike] = None,
        torques: Optional[ArrayLike] = None,
    ) -> Tuple[np.ndarray, None]:
        """``(M F + sqrt(2 kbt / dt) M^(1/2) W + kbt div M, None)`` (div M = 0): the
        velocities of an Euler-Maruyama step; ``dt`` times them is colloidsim's Brownian
        dynamics displacement at the same seed and noise step, to round-off."""
        op = self._ready()
        self._no_torques(torques)
        h = _number("dt", dt)
        kt = _number("kbt", kbt, positive=False)
        if kt < 0:
            raise ColloidsimError(f"kbt: must be >= 0, got {kbt!r}")
        if forces is None:
            f, shape = np.zeros(3 * op.particles), self._shape
        else:
            f, shape = _vectors("forces", forces, op.particles)
        if kt == 0.0:
            u = np.frombuffer(op.mdot(f.tobytes()), dtype="<f8")
            return u.reshape(shape).copy(), None
        dx = np.frombuffer(op.displacement(f.tobytes(), h, kt, self._next_step()), dtype="<f8")
        self._report()
        return (dx / h).reshape(shape), None

    def clean(self) -> None:
        """Free the operator (its grids and lists); setPositions builds it again."""
        self._op = None
        self._op_key = None

    # --- colloidsim's additions -------------------------------------------------------------

    @property
    def seed(self) -> int:
        """The noise seed (given to initialize, or drawn there)."""
        return self._seed

    @property
    def numberParticles(self) -> int:
        """Particles of the last setPositions (0 before)."""
        return 0 if self._op is None else self._op.particles

    @property
    def lastLanczos(self) -> Tuple[int, float]:
        """(iterations, relative change) of the last square root."""
        return self._ready().last_lanczos

    # --- internals ------------------------------------------------------------------------

    _delta = 1e-3

    def _check_parameters(self) -> None:
        pass

    def _extra(self) -> dict:
        return {}

    def _ready(self) -> Any:
        if self._op is None or self._positions is None:
            raise ColloidsimError(
                "positions: not set; call initialize and setPositions first"
            )
        return self._op

    def _no_torques(self, torques: Any) -> None:
        if torques is not None and np.size(torques) > 0:
            raise ColloidsimError(
                "torques: colloidsim's mobilities are translational only (includeAngular=False)"
            )

    def _next_step(self) -> int:
        s = int(self.noiseStep)
        if not 0 <= s < 2**64:
            raise ColloidsimError(f"noiseStep: must lie in [0, 2^64), got {self.noiseStep!r}")
        self.noiseStep = s + 1
        return s

    def _report(self) -> None:
        cb = getattr(self, "_callback", None)
        if cb is not None:
            cb(*self._op.last_lanczos)

    def __repr__(self) -> str:
        n = self.numberParticles
        return f"{type(self).__name__}({', '.join(self.periodicity)}; {n} particles)"


class NBody(_Solver):
    """The Rotne-Prager-Yamakawa mobility in an unbounded fluid, by direct O(N^2) sums on all
    cores (libMobility's ``NBody`` with ``periodicityZ="open"``): both branches (overlapping
    spheres included), unequal radii by Zuk et al. (2014); the noise by a Lanczos square root.
    Periodicity: ``"open"`` in x, y and z (``single_wall``, Rotne-Prager-Blake, is not here)."""

    _method = "direct"
    _accepts = (("open",), ("open",), ("open",))

    def setParameters(
        self,
        algorithm: str = "advise",
        Nbatch: int = -1,
        NperBatch: int = -1,
        wallHeight: Optional[float] = None,
        delta: float = 1e-3,
    ) -> None:
        """libMobility's NBody parameters: ``algorithm`` is accepted and ignored (one CPU
        algorithm); batches are not supported (``Nbatch``, ``NperBatch`` must stay -1 or
        describe one batch); ``wallHeight`` needs a wall, which colloidsim has not;
        ``delta``: the random finite difference step of :meth:`thermalDrift`, in radii."""
        if algorithm not in ("naive", "fast", "block", "advise"):
            raise ColloidsimError(
                f"algorithm: one of 'naive', 'fast', 'block', 'advise', got {algorithm!r}"
            )
        if Nbatch not in (-1, 1):
            raise ColloidsimError(
                f"Nbatch: colloidsim computes one batch (-1 or 1), got {Nbatch!r}"
            )
        if NperBatch != -1 and (isinstance(NperBatch, bool) or not isinstance(NperBatch, int)):
            raise ColloidsimError(f"NperBatch: -1 or the number of particles, got {NperBatch!r}")
        self._nper = NperBatch
        if wallHeight is not None:
            raise ColloidsimError(
                "wallHeight: only valid with a wall (periodicityZ='single_wall'), which "
                "colloidsim does not have"
            )
        self._delta = _number("delta", delta)

    def setPositions(self, positions: ArrayLike) -> None:
        super().setPositions(positions)
        nper = getattr(self, "_nper", -1)
        if nper != -1 and nper != self.numberParticles:
            raise ColloidsimError(
                f"NperBatch: {nper} is not the {self.numberParticles} particles (one batch)"
            )


class PSE(_Solver):
    """The Rotne-Prager-Yamakawa mobility in a periodic cube by positively split Ewald
    (Fiore, Balboa Usabiaga, Donev & Swan 2017), O(N log N) on all cores; unequal radii by one
    sinc filter per distinct radius (at most 8, within a factor 16). The product's relative
    error is below ``tolerance``; the wave-space noise is exact, the real-space noise a
    Lanczos square root. Periodicity: ``"periodic"`` in x, y and z; the box must be a cube."""

    _method = "pse"
    _accepts = (("periodic",), ("periodic",), ("periodic",))

    def setParameters(
        self,
        psi: float,
        Lx: float,
        Ly: float,
        Lz: float,
        shearStrain: Optional[float] = None,
    ) -> None:
        """``psi``: the Ewald splitting (1 / length; 0.5 / a is a good choice); ``Lx``, ``Ly``,
        ``Lz``: the box, a cube (all three equal); ``shearStrain``: None or 0 (no sheared
        boxes)."""
        xi = _number("psi", psi)
        lx, ly, lz = _number("Lx", Lx), _number("Ly", Ly), _number("Lz", Lz)
        if ly != lx:
            raise ColloidsimError(
                f"Ly: colloidsim's PSE box is a cube: must equal Lx = {lx}, got {ly}"
            )
        if lz != lx:
            raise ColloidsimError(
                f"Lz: colloidsim's PSE box is a cube: must equal Lx = {lx}, got {lz}"
            )
        if shearStrain is not None and _number("shearStrain", shearStrain, positive=False) != 0:
            raise ColloidsimError(
                "shearStrain: colloidsim's PSE box is not sheared: must be None or 0, got "
                f"{shearStrain!r}"
            )
        # As in libMobility, they take effect at the next initialize.
        self._pse = dict(splitting=xi, box_length=lx)

    def _check_parameters(self) -> None:
        if getattr(self, "_pse", None) is None:
            raise ColloidsimError(
                "setParameters: call setParameters(psi, Lx, Ly, Lz) before initialize"
            )
        self._pse_init = dict(self._pse)

    def _extra(self) -> dict:
        return dict(self._pse_init)

    @property
    def geometry(self) -> dict:
        """The PSE grid, spreading window (exponential of semicircle: support points per axis,
        shape ``beta``, ``half_width``) and cut-offs chosen for psi and tolerance."""
        g = self._ready().pse_geometry()
        keys = ("grid", "spacing", "k_cut", "support", "beta", "half_width", "r_cut")
        return dict(zip(keys, g))


class SelfMobility(_Solver):
    """Free draining: ``M = I / (6 pi eta a_i)`` (libMobility's ``SelfMobility``); periodicity
    ``"open"`` in x, y and z."""

    _method = "self"
    _accepts = (("open",), ("open",), ("open",))

    def setParameters(self, parameter: float = 0.0) -> None:
        """libMobility's example parameter: accepted and ignored."""
        _number("parameter", parameter, positive=False)
