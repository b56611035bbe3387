"""LuGre identification on arrays (SI units), as ``fistage identify`` does
on lab files. Each fit returns a :class:`Fit`: ``fit["f_c"]`` gives
``{"value", "ci95", "std_error", "unit"}``; ``fit.report`` the whole report
(residuals, what the data cannot determine, warnings)."""

import json

import numpy

from . import _fistage

__all__ = ["Fit", "stribeck", "frf", "record", "read_record", "simulate_record"]


class Fit:
    """A fit report, indexable by parameter name. It shows its page in
    Jupyter (the data against the fit, the parameters with their intervals,
    what the data cannot determine; a record fit's correlation matrix) and
    writes it with :meth:`write_page`."""

    def __init__(self, report, page=None):
        self.report = report
        self._page = page

    def _repr_html_(self):
        return None if self._page is None else _fistage._page_frame(self._page)

    def write_page(self, path):
        """Writes the fit's HTML page (as report.html of ``fistage identify``)."""
        _fistage._page_write(self._page, str(path))

    def _entries(self):
        listed = self.report.get("parameters")
        if isinstance(listed, list):
            # A stage fit: parameters by path and by short name.
            entries = {e["path"]: e for e in listed}
            entries.update({e["name"]: e for e in listed})
            return entries
        return {k: v for k, v in self.report.items() if isinstance(v, dict) and "value" in v}

    def __getitem__(self, name):
        entry = self._entries().get(name)
        if entry is None:
            raise KeyError("no parameter %r (fitted: %s)" % (name, ", ".join(self.parameters)))
        return entry

    def __contains__(self, name):
        return name in self._entries()

    @property
    def parameters(self):
        """The fitted parameters' names (paths for a stage fit)."""
        listed = self.report.get("parameters")
        if isinstance(listed, list):
            return [e["path"] for e in listed]
        return list(self._entries())

    @property
    def undetermined(self):
        """A stage fit's paths the records cannot determine (left at the scenario's values)."""
        return list(self.report.get("undetermined", []))

    @property
    def not_identifiable(self):
        """Parameters the data cannot determine, with the reason."""
        return {n["parameter"]: n["reason"] for n in self.report.get("not_identifiable", [])}

    def __repr__(self):
        values = ", ".join("%s=%.4g %s" % (k, self[k]["value"], self[k]["unit"]) for k in self.parameters)
        return "Fit(%s)" % values


def _floats(name, values):
    array = numpy.asarray(values, dtype=numpy.float64)
    if array.ndim != 1:
        raise _fistage.Error("%s must be one-dimensional, got shape %s" % (name, array.shape))
    return array.tolist()


def stribeck(velocity, force, loss="l2", asymmetric=False):
    """Fits f_c, f_s, v_s and sigma2 to a steady-state friction curve:
    velocity in m/s, force in N; loss "l2", "huber" or "l1"; asymmetric
    fits each direction and tests the difference."""
    text, page = _fistage._stribeck(_floats("velocity", velocity), _floats("force", force), loss,
                                    asymmetric)
    return Fit(json.loads(text), page)


def frf(freq, response=None, magnitude=None, phase=None, mass=None, sigma2=None):
    """Fits sigma0 and sigma1 + sigma2 (and the mass unless given, kg) to the
    pre-motion FRF: freq in Hz; response complex (m/N), or magnitude (m/N)
    with phase (rad) or alone; sigma2 (N s/m) from a Stribeck fit splits
    sigma1 off the damping."""
    freq = _floats("freq", freq)
    if response is not None:
        if magnitude is not None or phase is not None:
            raise _fistage.Error("give response, or magnitude (and phase), not both")
        response = numpy.asarray(response, dtype=numpy.complex128)
    elif magnitude is not None and phase is not None:
        response = numpy.asarray(magnitude, dtype=numpy.float64) * numpy.exp(
            1j * numpy.asarray(phase, dtype=numpy.float64))
    if response is not None:
        if response.ndim != 1:
            raise _fistage.Error("response must be one-dimensional, got shape %s" % (response.shape,))
        text, page = _fistage._frf(freq, real=response.real.tolist(), imaginary=response.imag.tolist(),
                                   mass=mass, sigma2=sigma2)
    elif magnitude is not None:
        text, page = _fistage._frf(freq, magnitude=_floats("magnitude", magnitude), mass=mass,
                                   sigma2=sigma2)
    else:
        raise _fistage.Error("give response (complex) or magnitude (with phase, or alone)")
    return Fit(json.loads(text), page)


def record(t=None, force=None, position=None, mass=None, loss="l2", horizon=0.01, progress=None,
           closed_loop=None, scenario=None, paths=None, records=None):
    """Fits all six LuGre parameters (and the mass unless given, kg) to a
    recorded run by output error on the position (paper Eq. 31): t in s,
    force in N held over each sample interval (force[k] acts on
    [t[k], t[k+1])), position in m sampled at t[k] before force[k] acts; the
    stage starts at rest with relaxed bristles. No start is asked: the first
    estimates come from the record. loss "l2" or "huber"; horizon (s) is how
    often the simulated position is re-anchored to the encoder (None: pure
    output error). progress(iteration, rms) is called after every
    iteration; Ctrl-C stops the fit. closed_loop names the scenario (.toml)
    whose servo drove the run: the plant is then driven by that servo law
    on the simulated encoder, the logged force giving only the first
    estimates. The result also holds the simulated position as
    ``fit.simulated``.

    With ``scenario`` (a ``fistage.Scenario``) the fit is of that stage
    (any robot file): ``paths`` are parameter-table paths (``"*"`` within
    names) fitted to ``records`` jointly, each a dict with ``t``, ``force``,
    ``position`` (the stage's main sensor) and optionally ``sensors``
    ({sensor name: readings in m}); t, force, position given as well are
    one more record. closed_loop is then True when the scenario's own servo
    drove the records. The result holds ``fit.report["covariance"]`` (what
    ``Scenario.robust(from_fit=...)`` reads from its file), the
    ``undetermined`` paths (left at the scenario's values) and
    ``fit.simulated`` per record and sensor."""
    if scenario is not None:
        return _stage(scenario, paths, records, t, force, position, loss, progress, closed_loop)
    if t is None or force is None or position is None:
        raise _fistage.Error("give t, force and position, or a scenario with records")
    text, page, simulated = _fistage._record(
        _floats("t", t), _floats("force", force), _floats("position", position),
        mass=mass, loss=loss, horizon=horizon, progress=progress,
        closed_loop=None if closed_loop is None else str(closed_loop))
    fit = Fit(json.loads(text), page)
    fit.simulated = numpy.asarray(simulated, dtype=numpy.float64)
    return fit


def _stage(scenario, paths, records, t, force, position, loss, progress, closed_loop):
    if not paths:
        raise _fistage.Error("a stage fit needs paths: the parameter-table entries to fit")
    given = list(records or [])
    if t is not None:
        given.append({"t": t, "force": force, "position": position})
    if not given:
        raise _fistage.Error("a stage fit needs records")
    arrays = []
    for i, entry in enumerate(given):
        sensors = [(str(name), _floats(f"records[{i}].sensors[{name}]", values))
                   for name, values in dict(entry.get("sensors", {})).items()]
        arrays.append((_floats(f"records[{i}].t", entry["t"]),
                       _floats(f"records[{i}].force", entry["force"]),
                       _floats(f"records[{i}].position", entry["position"]), sensors))
    text, page, simulated = _fistage._stage(
        scenario, [str(p) for p in paths], arrays, closed_loop=bool(closed_loop), loss=loss,
        progress=progress)
    fit = Fit(json.loads(text), page)
    fit.simulated = [[numpy.asarray(s, dtype=numpy.float64) for s in per] for per in simulated]
    return fit


def read_record(path):
    """Reads a record file (CSV, or a MAT-file as MATLAB's save writes it):
    columns or variables by unit suffix (t_s, f_servo_N, x_nm, ...).
    Returns (t, force, position) as numpy arrays in s, N and m."""
    t, force, position = _fistage._read_record(str(path))
    return tuple(numpy.asarray(a, dtype=numpy.float64) for a in (t, force, position))


def simulate_record(stage, seed=1, quantum=1e-9, noise=0.0, disturbance=0.0, rate=10000.0,
                    closed_loop=False, duration=None):
    """A lab-style record of the open-loop stage of a robot (.urdf) or
    scenario (.toml) file, as ``fistage identify simulate-record`` makes it:
    small and large chirps, breakaway ramps, holds, steps and rests, 7 s;
    encoder step quantum (m), white position noise (m), an unmeasured force
    disturbance (RMS, N). With closed_loop, a run of the scenario's own
    servo along its reference over duration s (the scenario's by default),
    the disturbance unlogged. Returns (t, force, position, truth), truth the
    stage's parameters by name."""
    t, force, position, truth = _fistage._simulate_record(
        str(stage), seed=seed, quantum=quantum, noise=noise, disturbance=disturbance, rate=rate,
        closed_loop=closed_loop, duration=duration)
    arrays = tuple(numpy.asarray(a, dtype=numpy.float64) for a in (t, force, position))
    return arrays + (json.loads(truth),)
