"""fistage: precision motion stages with friction isolators, for Python.

The same library as the ``fistage`` program, with numpy arrays::

    import fistage
    scenario = fistage.load("scenarios/paper/fig05b_fi.toml")
    stiffer = scenario.with_overrides({"controller.c": 150.0})
    result = stiffer.run()
    x = result["encoder.position"]          # numpy float64, m
    print(result.summary["signals"]["encoder.position"]["peak_to_peak"])

Scenarios pickle, so ``multiprocessing`` or ``concurrent.futures`` can map
runs over parameters. Errors are subclasses of :class:`fistage.Error` with
the program's messages.
"""

from ._fistage import (
    Error,
    IdentificationError,
    LoadError,
    Result,
    Scenario,
    SimulationError,
    load,
)
from . import identify

__all__ = [
    "Error",
    "IdentificationError",
    "LoadError",
    "Result",
    "Scenario",
    "SimulationError",
    "identify",
    "load",
    "to_pandas",
]


def to_pandas(result):
    """The signals of a :class:`Result` as a pandas DataFrame indexed by time
    (needs pandas; column names are signal names, units in ``df.attrs``)."""
    import pandas

    frame = pandas.DataFrame(dict(result.signals), index=pandas.Index(result.time, name="time"))
    frame.attrs["units"] = dict(result.units)
    return frame


Result.to_pandas = to_pandas
