"""Type stubs of the fistage package."""

from os import PathLike
from typing import Callable, Any, Dict, List, Optional, Tuple, Union

import numpy
import numpy.typing

from . import identify as identify

class Error(Exception):
    """Every error fistage raises."""

class LoadError(Error):
    """A scenario, robot or parameter the loader refuses."""

class SimulationError(Error):
    """A run the engine could not complete."""

class IdentificationError(Error):
    """A fit the data or the options do not allow."""

class Result:
    """A finished run."""

    time: numpy.typing.NDArray[numpy.float64]
    """Sample times, s."""
    signals: Dict[str, numpy.typing.NDArray[numpy.float64]]
    """Every signal by name, SI units."""
    units: Dict[str, str]
    """The unit of every signal."""
    summary: Dict[str, Any]
    """As summary.json: scenario, window, solver statistics, tracking, per-signal statistics."""
    def __getitem__(self, name: str) -> numpy.typing.NDArray[numpy.float64]: ...
    def to_pandas(self) -> Any:
        """The signals as a pandas DataFrame indexed by time (needs pandas)."""
    def report(self, path: Union[str, PathLike]) -> None:
        """Writes the run's HTML page (as `fistage run` writes report.html)."""
    def _repr_html_(self) -> str:
        """The page in Jupyter: the same interactive plots, in a frame."""

class Plant:
    """The stage as an ODE x' = f(t, x) for Python's own integrators (e.g. scipy's solve_ivp)."""

    n_states: int
    state_names: List[str]
    x0: numpy.typing.NDArray[numpy.float64]
    """The scenario's start state."""
    nominal: numpy.typing.NDArray[numpy.float64]
    """Typical state sizes: fistage's absolute tolerance is rtol * atol_scale * nominal."""
    atol_scale: float
    duration: float
    sample_times: numpy.typing.NDArray[numpy.float64]
    breakpoints: List[float]
    """Times where the inputs jump: restart an integrator there."""
    def rhs(self, t: float, x: numpy.typing.NDArray[numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """The state derivative, the evaluation fistage integrates."""
    def jacobian(self, t: float, x: numpy.typing.NDArray[numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """d rhs / dx, exact (dual numbers)."""

class Scenario:
    """A scenario: its TOML text, the file its paths resolve against, and overrides."""

    title: str
    overrides: Dict[str, float]
    @staticmethod
    def from_toml(text: str, base_dir: Union[str, PathLike, None] = None) -> "Scenario":
        """A scenario from TOML text; relative paths resolve against base_dir."""
    def with_overrides(self, values: Dict[str, float]) -> "Scenario":
        """A new scenario with these parameter-table values, each checked by its rule."""
    def parameters(self) -> List[Dict[str, Any]]:
        """Every parameter-table entry: path, value, unit, rule, description."""
    def run(self, rtol: Optional[float] = None, engine: Optional[str] = None,
            progress: Optional[Callable[[float], None]] = None) -> Result:
        """Simulates the scenario (interpreter released) and returns its signals; progress(fraction)
        now and then; Ctrl-C or an exception in the callback stops the run."""
    def plant(self) -> Plant:
        """The stage as an ODE for Python's own integrators."""
    def modes(self, equilibrium: str = "slipping") -> Modes:
        """The linearisation at an equilibrium, as modes.json, with numpy eigenvalues."""
    def sweep(self, threads: Optional[int] = None,
              progress: Optional[Callable[[int, int], None]] = None,
              out: Union[str, PathLike, None] = None, shard: Union[str, Tuple[int, int], None] = None,
              merge: Optional[List[Union[str, PathLike]]] = None, force: bool = False,
              resume: bool = True) -> "Study":
        """The scenario's [sweep] grid as `fistage sweep` computes it (journal, resume, shards, merge)."""
    def robust(self, samples: Optional[int] = None, seed: Optional[int] = None, threads: Optional[int] = None,
               progress: Optional[Callable[[int, int], None]] = None,
               out: Union[str, PathLike, None] = None, shard: Union[str, Tuple[int, int], None] = None,
               merge: Optional[List[Union[str, PathLike]]] = None, force: bool = False,
               resume: bool = True) -> "Study":
        """The scenario's [robust] tolerance analysis as `fistage robust` computes it."""
    def export_fmu(self, path: Union[str, PathLike], library: Union[str, PathLike, None] = None) -> PathLike:
        """The scenario as an FMI 2.0 Co-Simulation FMU, as `fistage fmu` packages it."""

class Study:
    """Columns of points.csv / samples.csv as numpy arrays, rows as dicts, summary.json."""

    columns: Dict[str, Any]
    points: List[Dict[str, Any]]
    summary: Optional[Dict[str, Any]]
    def __getitem__(self, name: str) -> Any: ...
    def __len__(self) -> int: ...
    def to_pandas(self) -> Any: ...
    def report(self, path: Union[str, PathLike]) -> None:
        """Writes the study's HTML page (as the program's report.html)."""
    def _repr_html_(self) -> Optional[str]: ...

class Modes(Dict[str, Any]):
    """The dict modes.json holds; Jupyter shows its page (the stage in 3D, every mode animated)."""
    def report(self, path: Union[str, PathLike]) -> None:
        """Writes the page (as report.html of `fistage modes`)."""
    def _repr_html_(self) -> str: ...

def load(path: Union[str, PathLike]) -> Scenario:
    """Reads and checks a scenario file and its robot."""

def to_pandas(result: Result) -> Any: ...
