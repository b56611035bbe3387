"""LuGre identification on arrays (SI units), as ``fistage identify`` does
on lab files. Each fit returns a :class:`Fit`: ``fit["f_c"]`` gives
``{"value", "ci95", "std_error", "unit"}``; ``fit.report`` the whole report
(residuals, what the data cannot determine, warnings)."""

import json

import numpy

from . import _fistage

__all__ = ["Fit", "stribeck", "frf"]


class Fit:
    """A fit report, indexable by parameter name."""

    def __init__(self, report):
        self.report = report

    def __getitem__(self, name):
        entry = self.report.get(name)
        if not isinstance(entry, dict) or "value" not in entry:
            names = [k for k, v in self.report.items() if isinstance(v, dict) and "value" in v]
            raise KeyError("no parameter %r (fitted: %s)" % (name, ", ".join(names)))
        return entry

    def __contains__(self, name):
        entry = self.report.get(name)
        return isinstance(entry, dict) and "value" in entry

    @property
    def parameters(self):
        """The fitted parameters' names."""
        return [k for k, v in self.report.items() if isinstance(v, dict) and "value" in v]

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
    text = _fistage._stribeck(_floats("velocity", velocity), _floats("force", force), loss, asymmetric)
    return Fit(json.loads(text))


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
        text = _fistage._frf(freq, real=response.real.tolist(), imaginary=response.imag.tolist(),
                             mass=mass, sigma2=sigma2)
    elif magnitude is not None:
        text = _fistage._frf(freq, magnitude=_floats("magnitude", magnitude), mass=mass, sigma2=sigma2)
    else:
        raise _fistage.Error("give response (complex) or magnitude (with phase, or alone)")
    return Fit(json.loads(text))
