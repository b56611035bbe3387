"""Type stubs of fistage.identify."""

from typing import Any, Dict, List, Optional

import numpy.typing

class Fit:
    report: Dict[str, Any]
    """The whole report, as fit.json holds it."""
    parameters: List[str]
    not_identifiable: Dict[str, str]
    def __getitem__(self, name: str) -> Dict[str, Any]:
        """{"value", "ci95", "std_error", "unit"} of one parameter."""
    def __contains__(self, name: str) -> bool: ...

def stribeck(velocity: numpy.typing.ArrayLike, force: numpy.typing.ArrayLike, loss: str = "l2",
             asymmetric: bool = False) -> Fit:
    """Fits f_c, f_s, v_s and sigma2 to f_ss(v): m/s and N."""

def frf(freq: numpy.typing.ArrayLike, response: Optional[numpy.typing.ArrayLike] = None,
        magnitude: Optional[numpy.typing.ArrayLike] = None, phase: Optional[numpy.typing.ArrayLike] = None,
        mass: Optional[float] = None, sigma2: Optional[float] = None) -> Fit:
    """Fits sigma0, sigma1 + sigma2 (and the mass) to the pre-motion FRF: Hz, m/N, rad."""
