"""A weak mode high in the band beside a large low one, and a short, heavily damped decay at
kilohertz: records from outside the project that once crashed identify or read a frequency
with an interval of no width.

- A 1250 Hz mode at 2 um beside the wet 17 Hz mode (1 mm) at 10 kHz: the 17 Hz mode's band
  reaches far up towards the next, and the white noise there lifted its extrema near the
  noise floor by more than their size. The first-order correction took them below zero, and
  identify failed with fit_law's "extremum amplitudes must be finite and > 0". The same
  happened with a steady tone or an aliased mode near fs / 3 beside the decay.
- A 1667 Hz mode (6 samples per cycle) as large as the 17 Hz mode: the content above the
  split band, falling as that mode decays, was taken for a burst of broadband noise, and no
  decay was left ("found no free decay of at least 32 samples").
- A 2 kHz mode with 15 % viscous damping, 4.5 cycles at 50 kHz: in the crossing fit the
  frequency's column (s per rad/s) is 1e-8 of the time offsets', and the covariance's
  pseudo-inverse dropped it: the frequency came out 0.27 % off with an interval 1e-11 Hz
  wide.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsi_lab.dsp.identify import identify
from validation.cases import WET_C_F, WET_C_I, WET_F, WET_MASS, Case, Mode, trial


def _nearest(found, frequency: float):
    return min(found.modes, key=lambda m: abs(m.frequency_hz / frequency - 1.0))


def _coefficients(mode, mass: float) -> tuple[float, float]:
    a, beta = mode.quadratic.params
    return 2.0 * mass * a, mass * beta


@pytest.mark.parametrize("seed", [0, 1])
def test_a_weak_mode_near_an_eighth_of_the_rate_is_found_beside_a_large_low_one(seed):
    """Both modes are identified: the 17 Hz mode's frequency within 0.2 %, C_i within 5 % and
    C_f within 10 % of the truth; the 1250 Hz mode's frequency within 0.2 % and its C_i
    (viscous, 3 kg/(m s)) within its interval."""
    case = Case("high", (Mode(WET_F, c_f=WET_C_F, x0=1e-3),
                         Mode(1250.0, c_i=3.0, x0=2e-6)), fs=10000.0, duration=3.0)
    found = identify(trial(case, seed), case.fs)
    low, high = _nearest(found, WET_F), _nearest(found, 1250.0)
    assert low.frequency_hz == pytest.approx(WET_F, rel=0.002)
    c_i, c_f = _coefficients(low, WET_MASS)
    assert c_i == pytest.approx(WET_C_I, rel=0.05)
    assert c_f == pytest.approx(WET_C_F, rel=0.10)
    assert high.frequency_hz == pytest.approx(1250.0, rel=0.002)
    lo, hi = high.quadratic.interval("a")
    assert 2.0 * WET_MASS * lo <= 3.0 <= 2.0 * WET_MASS * hi


def test_a_high_mode_that_only_falls_is_no_burst_of_noise():
    """Beside the 1667 Hz mode sampled at 6 points per cycle, the 17 Hz mode is identified (its
    frequency within 0.2 %, C_i within 5 %), and no burst is named."""
    case = Case("sixth", (Mode(WET_F, c_f=WET_C_F, x0=1e-3),
                          Mode(10000.0 / 6.0, c_i=3.0, x0=1e-5)), fs=10000.0, duration=3.0)
    found = identify(trial(case, 0), case.fs)
    low = _nearest(found, WET_F)
    assert low.frequency_hz == pytest.approx(WET_F, rel=0.002)
    assert _coefficients(low, WET_MASS)[0] == pytest.approx(WET_C_I, rel=0.05)
    assert not any("burst" in note for note in found.notes), found.notes


def test_a_short_heavily_damped_kilohertz_decay_has_a_frequency_interval():
    """A 2 kHz mode (mass 0.0155 kg/m) with 15 % viscous damping released at 50 kHz, 0.3 s,
    0.5 % noise: the frequency's interval has a width (over 0.05 % of it) and covers 2 kHz."""
    mass, f0, zeta = 0.0155, 2000.0, 0.15
    c_i = 2.0 * mass * zeta * 2.0 * math.pi * f0
    case = Case("khz", (Mode(f0, c_i=c_i, x0=5e-6),), fs=50000.0, duration=0.3, mass=mass,
                noise=0.005, law="viscous")
    for seed in range(2):
        mode = identify(trial(case, seed), case.fs).modes[0]
        lo, hi = mode.frequency_ci
        assert hi - lo > 5e-4 * f0, (lo, hi)
        assert lo <= f0 <= hi, (mode.frequency_hz, lo, hi)
        assert np.isfinite(mode.frequency_hz)
