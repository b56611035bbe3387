"""Type stubs of fistage.identify."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy.typing

class Fit:
    simulated: numpy.typing.NDArray[numpy.float64]
    """The simulated position of a record fit, m."""
    report: Dict[str, Any]
    """The whole report, as fit.json holds it."""
    parameters: List[str]
    not_identifiable: Dict[str, str]
    def __getitem__(self, name: str) -> Dict[str, Any]:
        """{"value", "ci95", "std_error", "unit"} of one parameter."""
    def __contains__(self, name: str) -> bool: ...
    def write_page(self, path: Union[str, PathLike]) -> None:
        """Writes a record fit's HTML page (as report.html of `fistage identify record`)."""
    def _repr_html_(self) -> Optional[str]: ...

def stribeck(velocity: numpy.typing.ArrayLike, force: numpy.typing.ArrayLike, loss: str = "l2",
             asymmetric: bool = False) -> Fit:
    """Fits f_c, f_s, v_s and sigma2 to f_ss(v): m/s and N."""

def frf(freq: numpy.typing.ArrayLike, response: Optional[numpy.typing.ArrayLike] = None,
        magnitude: Optional[numpy.typing.ArrayLike] = None, phase: Optional[numpy.typing.ArrayLike] = None,
        mass: Optional[float] = None, sigma2: Optional[float] = None) -> Fit:
    """Fits sigma0, sigma1 + sigma2 (and the mass) to the pre-motion FRF: Hz, m/N, rad."""

def record(t: numpy.typing.ArrayLike, force: numpy.typing.ArrayLike, position: numpy.typing.ArrayLike,
           mass: Optional[float] = None, loss: str = "l2", horizon: Optional[float] = 0.01,
           progress: Optional[Callable[[int, float], None]] = None) -> Fit:
    """Fits the six LuGre parameters (and the mass) to a record: s, N (held over each interval), m."""

def read_record(path: str) -> Tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64],
                                    numpy.typing.NDArray[numpy.float64]]:
    """(t, force, position) of a CSV or MAT-file record, in s, N and m."""

def simulate_record(stage: str, seed: int = 1, quantum: float = 1e-9, noise: float = 0.0,
                    disturbance: float = 0.0, rate: float = 10000.0) -> Tuple[Any, Any, Any, Dict[str, float]]:
    """A lab-style record of the open-loop stage: (t, force, position, truth)."""
