from os import PathLike
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import analysis as analysis
from . import hydro as hydro

__version__: str

ScenarioLike = Union[str, PathLike[str], Mapping[str, Any]]
Overrides = Optional[Union[Mapping[str, Any], Sequence[str]]]

class ColloidsimError(RuntimeError): ...

class Table(Mapping[str, np.ndarray]):
    path: Path
    columns: List[str]
    def __init__(self, path: Union[str, PathLike[str]]) -> None: ...
    def __getitem__(self, key: str) -> np.ndarray: ...
    def __iter__(self) -> Iterator[str]: ...
    def __len__(self) -> int: ...
    def __getattr__(self, name: str) -> np.ndarray: ...

class Result:
    out: Path
    summary: Dict[str, Any]
    files: List[str]
    message: str
    warnings: List[str]
    tables: Dict[str, Table]
    def __init__(self, report: Dict[str, Any]) -> None: ...
    def __getitem__(self, name: str) -> Table: ...
    def __getattr__(self, name: str) -> Table: ...

def run(
    scenario: ScenarioLike,
    out: Optional[Union[str, PathLike[str]]] = None,
    overrides: Overrides = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    force: bool = False,
) -> Result: ...
def ensemble(
    scenario: ScenarioLike,
    replicas: int = 4,
    vary: Optional[Mapping[str, Sequence[Any]]] = None,
    out: Optional[Union[str, PathLike[str]]] = None,
    overrides: Overrides = None,
    threads: Optional[int] = None,
    force: bool = False,
) -> Result: ...
def resume(
    folder: Union[str, PathLike[str]],
    seed: Optional[int] = None,
    threads: Optional[int] = None,
) -> Result: ...
def theory(
    scenario: ScenarioLike,
    out: Optional[Union[str, PathLike[str]]] = None,
    overrides: Overrides = None,
    dx: Optional[float] = None,
    force: bool = False,
    hydrodynamics: Optional[str] = None,
    threads: Optional[int] = None,
) -> Result: ...
def analyse(
    trajectory: Union[str, PathLike[str]],
    out: Optional[Union[str, PathLike[str]]] = None,
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
) -> Result: ...
def check(scenario: ScenarioLike, overrides: Overrides = None) -> Dict[str, Any]: ...
def keys(method: str) -> List[Dict[str, str]]: ...
def methods() -> List[Dict[str, Any]]: ...

class Periodic:
    period: int
    phase: int
    def __init__(self, period: int, phase: int = 0) -> None: ...
    def __call__(self, step: int) -> bool: ...
    def next_after(self, step: int) -> int: ...

class Engine:
    analyzers: List[Tuple[Any, Any]]
    custom_forces: List[Any]
    def __init__(
        self,
        scenario: Optional[ScenarioLike] = None,
        overrides: Overrides = None,
        seed: Optional[int] = None,
        method: Optional[str] = None,
        **keys: Any,
    ) -> None: ...
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
    ) -> "Engine": ...
    @classmethod
    def from_frame(
        cls, frame: Any, seed: Optional[int] = None, method: Optional[str] = None, **keys: Any
    ) -> "Engine": ...
    def add_analyzer(self, analyzer: Callable[["Engine"], Any], trigger: Union[Periodic, int, Callable[[int], bool]]) -> None: ...
    def add_force(self, force: Callable[["Engine"], Any]) -> None: ...
    def remove_force(self, force: Callable[["Engine"], Any]) -> None: ...
    def step(self, steps: int = 1, threads: Optional[int] = None) -> None: ...
    def run(self, steps: int, threads: Optional[int] = None) -> None: ...
    def set_state(
        self,
        positions: Optional[Any] = None,
        velocities: Optional[Any] = None,
        steps: Optional[int] = None,
        seed: Optional[int] = None,
    ) -> None: ...
    def snapshot(self) -> Any: ...
    @property
    def method(self) -> str: ...
    @property
    def positions(self) -> np.ndarray: ...
    @positions.setter
    def positions(self, value: Any) -> None: ...
    @property
    def velocities(self) -> Optional[np.ndarray]: ...
    @velocities.setter
    def velocities(self, value: Any) -> None: ...
    @property
    def forces(self) -> np.ndarray: ...
    @property
    def steps(self) -> int: ...
    @steps.setter
    def steps(self, value: int) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, value: int) -> None: ...
    @property
    def time(self) -> float: ...
    @property
    def dt(self) -> float: ...
    @property
    def particles(self) -> int: ...
    @property
    def box(self) -> np.ndarray: ...

class BCD(Engine): ...
class BrownianDynamics(Engine): ...
class DPD(Engine): ...
class MonteCarlo(Engine): ...
class MPCD(Engine): ...
