"""Frequency-domain integration against exact free decays."""

from __future__ import annotations

import numpy as np
import pytest
from _analysis_sims import linear_decay, noisy, time_axis

from fsi_lab.dsp.integrate import integrate
from fsi_lab.errors import AnalysisError

FS = 5000.0
T = time_axis(8.0, FS)

# Two-mode free decays: moderately damped, and the heavily damped wet first mode.
CASES = {
    "moderate": ((1e-3, 3.1, 0.02, 0.0), (2e-4, 19.3, 0.01, 1.0)),
    "heavy": ((1e-3, 2.7, 0.10, 0.0), (3e-5, 18.7, 0.03, 1.0)),
    "light": ((1e-3, 12.1, 0.002, 2.0), (1e-5, 72.3, 0.001, 1.0)),
}


def two_modes(name):
    (x1, v1), (x2, v2) = (linear_decay(T, *CASES[name][0]), linear_decay(T, *CASES[name][1]))
    return x1 + x2, v1 + v2


@pytest.mark.parametrize("name", sorted(CASES))
def test_velocity_with_offset_and_noise(name):
    x, v = two_modes(name)
    vm = noisy(v + 0.002 * np.max(np.abs(v)), 0.01, seed=11)   # 0.2 % offset, 1 % noise
    d = integrate(vm, FS)
    assert np.max(np.abs(d - x)) < 0.03 * np.max(np.abs(x))


@pytest.mark.parametrize("name", sorted(CASES))
def test_clean_velocity_is_integrated_accurately(name):
    x, v = two_modes(name)
    d = integrate(v + 0.002 * np.max(np.abs(v)), FS)
    assert np.max(np.abs(d - x)) < 0.01 * np.max(np.abs(x))


def test_acceleration_to_velocity_and_displacement():
    w = 2 * np.pi * 7.0
    x, v = linear_decay(T, 1e-3, 7.0, 0.01, 0.5)
    # a = -w^2 x - 2 zeta w v for the viscous oscillator
    a = -w * w * x - 2 * 0.01 * w * v
    vel = integrate(a, FS, order=1)
    disp = integrate(a, FS, order=2)
    assert np.max(np.abs(vel - v)) < 0.01 * np.max(np.abs(v))
    assert np.max(np.abs(disp - x)) < 0.01 * np.max(np.abs(x))


def test_given_highpass_removes_a_slow_drift():
    x, v = linear_decay(T, 1e-3, 10.0, 0.01, 0.0)
    drift = 0.01 * np.max(np.abs(v)) * np.sin(2 * np.pi * 0.2 * T)   # below the corner
    d = integrate(v + drift, FS, highpass=4.0)
    assert np.max(np.abs(d - x)) < 0.03 * np.max(np.abs(x))


@pytest.mark.parametrize("bad, kwargs, match", [
    (lambda v: np.where(np.arange(v.size) == 9, np.nan, v), {}, "NaN"),
    (lambda v: np.ones_like(v), {}, "constant"),
    (lambda v: v[:30], {}, "too short"),
    (lambda v: np.clip(v, -0.5 * v.max(), 0.5 * v.max()), {}, "clipped"),
    (lambda v: v, {"order": 3}, "order"),
    (lambda v: v, {"highpass": 0.0}, "highpass"),
    (lambda v: v, {"highpass": 1e4}, "highpass"),
])
def test_bad_input_is_refused(bad, kwargs, match):
    _, v = linear_decay(T, 1e-3, 10.0, 0.01, 0.0)
    with pytest.raises(AnalysisError, match=match) as info:
        integrate(bad(v), FS, **kwargs)
    assert str(info.value).startswith("integrate:")
