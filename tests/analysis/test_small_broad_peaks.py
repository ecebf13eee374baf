"""A heavily damped mode beside a lightly damped one: its spectral peak is low for its
amplitude (its height goes as amplitude over damping), under the share of the largest peak a
component needs. It is left out with a note naming it and the way to identify it (band_hz),
and that way identifies it, against the sum of two exact decays with linear + quadratic
damping."""

from __future__ import annotations

import math

import numpy as np

from fsi_lab.dsp.identify import identify
from fsi_lab.dsp.laws import simulate_decay

FS, DURATION = 10000.0, 4.5
#: (frequency Hz, damping ratio, velocity at the release m/s): the 316 Hz mode is released
#: with 1.4 times the 17 Hz mode's velocity, its peak under 1 % of that mode's.
LIGHT, HEAVY = (17.0, 0.0055, 0.208), (315.9, 0.02, 0.29)


def _decay(f: float, zeta: float, v0: float, t: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Velocity (m/s) of a release with as much quadratic as linear damping at its start, and
    the law's a (1/s) and beta (1/m)."""
    w = 2.0 * math.pi * f
    a = zeta * w
    beta = 2.0 * a * 3.0 * math.pi / (8.0 * v0)
    v = simulate_decay("quadratic", [a, beta], w, v0 / w, 0.0, t, quantity="displacement",
                       output="velocity")
    return v, a, beta


def _record() -> tuple[np.ndarray, float, float]:
    t = np.arange(int(DURATION * FS)) / FS
    light, _, _ = _decay(*LIGHT, t)
    heavy, a, beta = _decay(*HEAVY, t)
    v = light + heavy
    return v + 0.0018 * float(np.max(np.abs(v))) * np.random.default_rng(3).standard_normal(
        t.size), a, beta


def test_a_heavily_damped_mode_under_the_threshold_is_noted_and_band_hz_identifies_it():
    v, a, beta = _record()
    found = identify(v, FS)
    assert [round(m.frequency_hz) for m in found.modes] == [17]
    (note,) = [n for n in found.notes if "a heavily damped mode, not reported" in n]
    assert note.startswith("the spectral peak at 31") and "band_hz" in note, note
    alone = identify(v, FS, band=(250.0, 400.0)).modes
    assert len(alone) == 1
    mode = alone[0]
    assert abs(mode.frequency_hz / HEAVY[0] - 1.0) < 1e-3
    assert abs(mode.quadratic.value("a") / a - 1.0) < 0.03
    low, high = mode.quadratic.interval("beta", 0.95)
    assert low <= beta <= high


def test_a_single_lightly_damped_mode_gets_no_such_note():
    t = np.arange(int(DURATION * FS)) / FS
    v, _, _ = _decay(*LIGHT, t)
    v = v + 0.0018 * float(np.max(np.abs(v))) * np.random.default_rng(4).standard_normal(t.size)
    found = identify(v, FS)
    assert len(found.modes) == 1
    assert not [n for n in found.notes if "heavily damped mode" in n]
