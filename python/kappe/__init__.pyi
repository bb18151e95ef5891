from typing import Any, Callable, Dict, Iterator, List, Mapping, MutableMapping, Optional, Union

import numpy as np

from . import cem as cem
from . import fe as fe
from . import robot as robot
from ._buildability import buildability_monte_carlo as buildability_monte_carlo
from ._ceiling import CeilingResult as CeilingResult
from ._ceiling import ceiling as ceiling
from ._design_mc import design_monte_carlo as design_monte_carlo
from ._optimize import OptimizeResult as OptimizeResult
from ._optimize import optimize as optimize
from ._study import study as study

__version__: str

class DesignError(ValueError):
    """A design outside what Kappe accepts; names the field and what is allowed."""
    @property
    def field(self) -> str: ...
    @property
    def value(self) -> str: ...
    @property
    def allowed(self) -> str: ...

class Design(MutableMapping[str, Any]):
    dtype: str
    def __init__(self, data: Optional[Mapping[str, Any]] = ..., **fields: Any) -> None: ...
    @classmethod
    def from_toml(cls, text: str) -> Design: ...
    @classmethod
    def from_file(cls, path: str) -> Design: ...
    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Design: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def to_toml(self) -> str: ...
    def validate(self) -> Design: ...
    @property
    def __data__(self) -> Dict[str, Any]: ...
    @classmethod
    def __from_data__(cls, data: Mapping[str, Any]) -> Design: ...
    def copy(self) -> Design: ...
    def __getitem__(self, key: str) -> Any: ...
    def __setitem__(self, key: str, value: Any) -> None: ...
    def __delitem__(self, key: str) -> None: ...
    def __iter__(self) -> Iterator[str]: ...
    def __len__(self) -> int: ...

class Layer:
    id: int
    nodes: np.ndarray
    segment_forces: np.ndarray
    segment_stress: np.ndarray
    overhang: Optional[float]

class PrintPath:
    points: np.ndarray
    axis: np.ndarray
    layer: np.ndarray
    length: float
    time: float

class Result:
    dtype: str
    summary: Dict[str, Any]
    ok: bool
    print_time: float
    states: List[Dict[str, Any]]
    constraints: List[Dict[str, Any]]
    layers: List[Layer]
    path: PrintPath
    network: Dict[str, Any]
    report_html: Optional[str]
    trajectory_csv: Optional[str]
    trajectory_header: List[str]
    trajectory: Optional[np.ndarray]
    @property
    def node_xyz(self) -> np.ndarray: ...
    @property
    def blf(self) -> np.ndarray: ...
    @property
    def __data__(self) -> Dict[str, Any]: ...
    @classmethod
    def __from_data__(cls, data: Mapping[str, Any]) -> Result: ...
    def write(self, directory: str, force: bool = ...) -> Optional[str]: ...

def design(
    design: Union[Design, Mapping[str, Any], str, None] = ...,
    analysis: Union[str, None, Mapping[str, Any]] = ...,
    robot: bool = ...,
    progress: Optional[Callable[[str, int, int], Any]] = ...,
    allow_fail: bool = ...,
    report: bool = ...,
) -> Result: ...
