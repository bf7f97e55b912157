from os import PathLike
from pathlib import Path
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Union

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

class Engine:
    def __init__(
        self, scenario: ScenarioLike, overrides: Overrides = None, seed: Optional[int] = None
    ) -> None: ...
    def step(self, steps: int = 1, threads: Optional[int] = None) -> None: ...
    @property
    def method(self) -> str: ...
    @property
    def positions(self) -> np.ndarray: ...
    @property
    def velocities(self) -> Optional[np.ndarray]: ...
    @property
    def forces(self) -> np.ndarray: ...
    @property
    def steps(self) -> int: ...
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
