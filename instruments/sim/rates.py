"""The rate the simulated world runs at: the digitiser's, or the smallest integer multiple of
it at which the beam integrator resolves every mode of the bench's beam.

Numpy arithmetic on the beam model only, so that ``fsi-lab profile check`` can refuse a record
the bench could not simulate without loading the world's filters (scipy) or its integrator
(numba).
"""

from __future__ import annotations

from fsi_lab.errors import ParameterError
from fsi_lab.modal_step import check_step

#: Largest factor between the world's rate and the digitiser's.
MAX_OVERSAMPLING = 64


def oversampling(model, sample_rate: float) -> int:
    """Smallest integer factor that lets the integrator resolve every mode of ``model``."""
    for factor in range(1, MAX_OVERSAMPLING + 1):
        try:
            check_step(model, sample_rate * factor)
            return factor
        except ParameterError:
            continue
    raise ParameterError(
        f"the simulated bench cannot resolve the highest mode at {sample_rate:g} Hz even "
        f"oversampled {MAX_OVERSAMPLING} times; lower model.modes or raise run.sample_rate")
