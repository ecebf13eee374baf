"""The step the modal integrator needs, checked without loading it.

:mod:`fsi_lab.modal_integrator` compiles its loop with numba, which takes a while to import;
``fsi-lab profile check`` and the instruments' checks only need to know whether a sample rate
resolves every mode of a beam model, which is numpy arithmetic on the model.
"""

from __future__ import annotations

import math

import numpy as np

from fsi_lab.beam import BeamModel
from fsi_lab.errors import ParameterError

#: Largest accepted |lambda| dt, lambda the fastest linear eigenvalue of a kept mode. RK4 is
#: stable up to 2.83 on the imaginary axis; at 0.5 (12.6 steps per period) its frequency error is
#: 5e-4 relative and its numerical damping 2e-4 in damping ratio; at 0.25, 16 and 32 times less.
MAX_OMEGA_DT = 0.5


def _linear_rates(model: BeamModel) -> np.ndarray:
    """|lambda| of the fastest eigenvalue of each mode's linear part, rad/s."""
    omega = model.natural_frequencies_rad
    c = model.linear_damping_rates
    over = c > 2.0 * omega
    fast = omega.copy()
    fast[over] = 0.5 * (c[over] + np.sqrt(c[over] ** 2 - 4.0 * omega[over] ** 2))
    return fast


def check_step(model: BeamModel, sample_rate: float) -> None:
    """Raise ParameterError if the step 1/sample_rate cannot resolve the model's modes.

    Accepts ``|lambda_n| / sample_rate <= MAX_OMEGA_DT`` for every kept mode, where
    ``|lambda_n|`` is omega_n for an underdamped mode (faster if overdamped).

    Parameters
    ----------
    model
        The beam model.
    sample_rate
        Samples per second of the excitation and outputs, Hz (one RK4 step per sample).
    """
    if isinstance(sample_rate, bool) or not isinstance(sample_rate, (int, float, np.number)) \
            or not math.isfinite(sample_rate) or sample_rate <= 0:
        raise ParameterError(f"sample_rate: got {sample_rate!r}; expected a finite number > 0 Hz")
    rates = _linear_rates(model)
    limit = MAX_OMEGA_DT * sample_rate
    if np.all(rates <= limit):
        return
    worst = int(np.argmax(rates))
    needed = math.ceil(float(rates.max()) / MAX_OMEGA_DT)  # Hz, rounded up
    accepted = int(np.argmax(rates > limit))  # modes 1..accepted are resolved
    f_worst = model.natural_frequencies_hz[worst]
    fewer = (f"at {sample_rate:g} Hz at most {accepted} mode{'s' if accepted != 1 else ''} "
             f"{'are' if accepted != 1 else 'is'} accepted" if accepted else
             f"at {sample_rate:g} Hz not even mode 1 is resolved")
    raise ParameterError(
        f"sample_rate: {sample_rate:g} Hz cannot resolve mode {worst + 1} "
        f"({f_worst:.6g} Hz, |lambda| = {rates[worst]:.6g} rad/s) of the {model.modes}-mode "
        f"model: the fixed-step RK4 needs |lambda| / sample_rate <= {MAX_OMEGA_DT:g}; use a "
        f"sample rate >= {needed} Hz, or fewer modes ({fewer})")
