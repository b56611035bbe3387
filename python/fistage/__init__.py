"""fistage: precision motion stages with friction isolators, for Python.

The same library as the ``fistage`` program, with numpy arrays::

    import fistage
    scenario = fistage.load("scenarios/paper/fig05b_fi.toml")
    stiffer = scenario.with_overrides({"controller.c": 150.0})
    result = stiffer.run()
    x = result["encoder.position"]          # numpy float64, m
    print(result.summary["signals"]["encoder.position"]["peak_to_peak"])

Scenarios pickle, so ``multiprocessing`` or ``concurrent.futures`` can map
runs over parameters. ``scenario.sweep()`` and ``scenario.robust()`` run
the scenario's ``[sweep]`` and ``[robust]`` studies as the program does and
give :class:`Study` results (numpy columns of points.csv / samples.csv, and
summary.json); ``scenario.export_fmu(path)`` packages it as an FMU. Errors are subclasses of :class:`fistage.Error` with
the program's messages.
"""

import os

from ._fistage import (
    Error,
    IdentificationError,
    LoadError,
    Plant,
    Result,
    Scenario,
    SimulationError,
    _page_frame,
    _page_write,
    load,
)
from . import identify

__all__ = [
    "Error",
    "Modes",
    "Study",
    "IdentificationError",
    "LoadError",
    "Plant",
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


class Study:
    """The result of a sweep or a tolerance analysis: ``columns`` (name to
    numpy array: numbers as float64 with NaN where the program wrote
    nothing, verdicts as bool, or object arrays with None where a verdict is
    undetermined, text columns such as ``refused`` as objects with None
    where empty), ``points`` (one dict per row, as points.json holds
    them), ``summary`` (summary.json of a tolerance analysis, else None).
    ``study["stable_linear"]`` is a column; ``to_pandas()`` a DataFrame."""

    def __init__(self, table, summary=None, page=None):
        import numpy

        self._page = page
        lines = [line for line in table.splitlines() if line]
        names = lines[0].split(",")
        rows = [line.split(",") for line in lines[1:]]
        self.columns = {}
        self.points = [dict() for _ in rows]
        for j, name in enumerate(names):
            cells = [row[j] if j < len(row) else "" for row in rows]
            values = [_cell(c) for c in cells]
            for point, value in zip(self.points, values):
                point[name] = value
            if any(isinstance(v, str) for v in values):
                self.columns[name] = numpy.array(values, dtype=object)
            elif any(isinstance(v, bool) for v in values):
                dtype = bool if all(isinstance(v, bool) for v in values) else object
                self.columns[name] = numpy.array(values, dtype=dtype)
            else:
                self.columns[name] = numpy.array(
                    [numpy.nan if v is None else v for v in values], dtype=numpy.float64)
        self.summary = summary

    def __getitem__(self, name):
        try:
            return self.columns[name]
        except KeyError:
            raise KeyError("no column %r (columns: %s)" % (name, ", ".join(self.columns))) from None

    def __len__(self):
        return len(self.points)

    def _repr_html_(self):
        """The study's page in Jupyter (as report.html of the program's folder)."""
        return None if self._page is None else _page_frame(self._page)

    def report(self, path):
        """Writes the study's HTML page (as the program's report.html)."""
        _page_write(self._page, os.fspath(path))

    def __repr__(self):
        return "Study(%d rows, columns %s)" % (len(self.points), ", ".join(self.columns))

    def to_pandas(self):
        """The columns as a pandas DataFrame (needs pandas)."""
        import pandas

        return pandas.DataFrame(self.columns)


def _cell(text):
    """A cell as the program wrote it: empty is None, a verdict a bool, a
    number a float, anything else (why a sample was refused) its text."""
    if text == "":
        return None
    if text in ("true", "false"):
        return text == "true"
    try:
        return float(text)
    except ValueError:
        return text


def _study_flags(out, shard, merge, force, resume):
    """The program's study flags as the extension takes them: ``shard`` as
    "i/n" or (i, n), folders as strings."""
    if isinstance(shard, (tuple, list)):
        if len(shard) != 2:
            raise ValueError("shard must be \"i/n\" or (i, n), got %r" % (shard,))
        shard = "%d/%d" % (shard[0], shard[1])
    return dict(out=None if out is None else os.fspath(out), shard=shard,
                merge=None if merge is None else [os.fspath(m) for m in merge],
                force=force, resume=resume)


def _sweep(self, threads=None, progress=None, out=None, shard=None, merge=None, force=False, resume=True):
    """Runs the scenario's ``[sweep]`` grid as ``fistage sweep`` does (the
    interpreter released, ``threads`` threads, default all);
    ``progress(done, total)`` after each chunk of points; Ctrl-C stops it.
    Returns a :class:`Study` with the columns of points.csv (each axis, then
    stable_linear, stable_sim, amplitude, max_real_eig, bistable).

    As the program's flags: ``shard`` ("i/n" or (i, n)) computes every n-th
    point from i; ``out`` writes the result folder (points.csv, points.json,
    provenance.json) whole, journaled in ``.<out>.journal`` so a killed run
    resumes (``resume=False`` recomputes); ``merge`` joins shard folders (the
    program's too) into ``out``; ``force`` replaces other work there."""
    flags = _study_flags(out, shard, merge, force, resume)
    table, page = self._sweep(threads=threads, progress=progress, **flags)
    return Study(table, page=page)


def _robust(self, samples=None, seed=None, threads=None, progress=None, out=None, shard=None, merge=None,
            force=False, resume=True, from_fit=None, from_fit_draw=None):
    """Runs the scenario's ``[robust]`` tolerance analysis as ``fistage
    robust`` does: ``samples`` and ``seed`` replace the table's when given.
    Returns a :class:`Study` with the columns of samples.csv and
    ``summary`` as summary.json (probabilities with their intervals,
    quantiles, sensitivities). ``out``, ``shard``, ``merge``, ``force`` and
    ``resume`` as for :meth:`Scenario.sweep` (the folder holds samples.csv,
    summary.json and provenance.json).

    ``from_fit`` (a fit's ``fit.json``) draws the fitted parameters jointly
    from the fit's covariance (``from_fit_draw="normal"``, the default) or
    its jackknife replicates (``"replicates"``), alone or with the table's
    parameters: P(unstable) of the identified stage."""
    import json

    flags = _study_flags(out, shard, merge, force, resume)
    if from_fit is not None:
        flags["from_fit"] = str(from_fit)
    if from_fit_draw is not None:
        flags["from_fit_draw"] = from_fit_draw
    table, summary, page = self._robust(samples=samples, seed=seed, threads=threads, progress=progress,
                                        **flags)
    return Study(table, json.loads(summary), page=page)


class Modes(dict):
    """The result of :meth:`Scenario.modes`: the dict modes.json holds (with
    numpy arrays ``eigenvalues``, ``frequency_hz``, ``damping_ratio``), whose
    page (the stage in 3D with every mode animated) Jupyter shows."""

    def _repr_html_(self):
        return _page_frame(self._page)

    def report(self, path):
        """Writes the page (as report.html of ``fistage modes``)."""
        _page_write(self._page, os.fspath(path))


def _modes(self, equilibrium="slipping"):
    """modes(equilibrium="slipping") -> Modes: the linearisation at the
    sticking or slipping equilibrium, as modes.json holds it (verdict,
    max_real_part, state, coordinates, modes with frequency, damping ratio and
    energy shares), plus numpy arrays ``eigenvalues`` (complex),
    ``frequency_hz`` and ``damping_ratio``. A verdict the numerics cannot back
    is "undetermined". In Jupyter it shows its page."""
    data, page = self._modes(equilibrium)
    result = Modes(data)
    result._page = page
    return result


Scenario.sweep = _sweep
Scenario.robust = _robust
Scenario.modes = _modes
