"""identify()'s cubic stiffness and natural frequency on strongly nonlinear decays, against
exact integrations of the oscillator with linear + quadratic damping.

A 40 Hz mode whose frequency falls 10 % at its 0.425 mm release (harmonic balance), damping
ratio 0.5 %, recorded at 5 kHz with 0.3 % noise. The step on the crossing times once left its
stiffness out (resolved by 4.5 standard errors only, short of the 5 asked of a stiffness
alone): the linear frequency, a mean over the decay's amplitudes, read 2 % low with an interval
of +-0.1 % and no word on it. Kept, it read a third low, the frequency 0.6 to 1 % low: the
model's crossings, a few per cent off in frequency, drift by a half period in twenty cycles,
and paired with the record's by nearest times, every other stretch's were another cycle's.

A stiffness the cubic term cannot describe (one growing as |x| x, a backbone straight in the
amplitude) leaves the model's frequency at zero amplitude off what the backbone measures at
the decays' smallest amplitudes: that is warned."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fsi_lab.dsp.identify import identify
from fsi_lab.dsp.laws import simulate_decay

FS, F0, ZETA, X0, SHIFT = 5000.0, 40.0, 0.005, 0.425e-3, -0.10


#: The quadratic damping: as much as the linear at the release.
BETA = 2.0 * ZETA * 3.0 * math.pi / (8.0 * X0)


def softening_release(seed: int, shift: float = SHIFT) -> np.ndarray:
    """The velocity (m/s) of the release after 0.15 s held, with 0.3 % white noise; the
    frequency falls by ``shift`` (relative, harmonic balance) at the release."""
    w0 = 2.0 * math.pi * F0
    alpha = shift * w0 ** 2 / (0.375 * X0 ** 2)       # w^2 = w0^2 (1 + shift) at X0
    t = np.arange(int(4.0 * FS)) / FS
    v = simulate_decay("quadratic", [ZETA * w0, BETA], w0, X0, 0.15, t, alpha=alpha,
                       quantity="displacement", output="velocity")
    v[t < 0.15] = 0.0
    peak = float(np.max(np.abs(v)))
    return v + 0.003 * peak * np.random.default_rng(seed).standard_normal(t.size)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("shift", [-0.10, -0.20])
def test_a_strongly_softening_decay_keeps_its_stiffness_and_frequency(seed, shift):
    """The stiffness within 3 % of the truth (0.67 before), the linear frequency within
    0.05 % (-0.6 to -1 % before; harmonic balance itself is 0.02 % off the exact backbone at
    20 % softening), C_i and C_f within the issue's 2 and 5 %, and nothing warned."""
    w0 = 2.0 * math.pi * F0
    mode = identify(softening_release(seed, shift), FS).modes[0]
    assert abs(mode.alpha / (shift * w0 ** 2 / (0.375 * X0 ** 2)) - 1.0) < 0.03
    assert abs(mode.frequency_hz / F0 - 1.0) < 5e-4
    assert abs(mode.quadratic.value("a") / (ZETA * w0) - 1.0) < 0.02
    assert abs(mode.quadratic.value("beta") / BETA - 1.0) < 0.05
    assert abs(mode.start_drift["foot_frequency"] / F0 - 1.0) < 0.002
    assert mode.warnings == []


def test_a_moderately_softening_decay_is_not_warned_of_its_foot():
    """At a quarter of the stiffness (2.5 % softening at the release) the model holds the
    backbone down to its foot: no such warning, the linear frequency within 0.2 %."""
    mode = identify(softening_release(5, 0.25 * SHIFT), FS).modes[0]
    assert abs(mode.frequency_hz / F0 - 1.0) < 0.002
    assert not [w for w in mode.warnings if w.startswith("the natural frequency (")]


@pytest.mark.parametrize("shift", [-0.10, 0.10])
def test_a_stiffness_the_cubic_term_cannot_follow_is_warned_of_its_foot(shift):
    """x'' + 2 a x' + beta |x'| x' + w0^2 x + k |x| x = 0, its frequency moved by ``shift`` at
    the release (harmonic balance: w^2 = w0^2 + 8 k A / (3 pi)): the cubic model's frequency
    at zero amplitude misses by 0.6 % or more, and the warning says so; the backbone's foot
    (still 0.2 % off: a straight backbone moves even there) lies nearer the truth."""
    w0 = 2.0 * math.pi * F0
    a = ZETA * w0
    k = shift * w0 ** 2 / (8.0 / (3.0 * math.pi) * X0)
    t = np.arange(int(4.0 * FS)) / FS
    free = t >= 0.15
    solution = solve_ivp(
        lambda _, s: [s[1], -2.0 * a * s[1] - BETA * abs(s[1]) * s[1] - w0 ** 2 * s[0]
                      - k * abs(s[0]) * s[0]],
        (0.15, t[-1]), [X0, 0.0], t_eval=t[free], method="DOP853", rtol=1e-10, atol=1e-14)
    v = np.zeros(t.size)
    v[free] = solution.y[1]
    v = v + 0.003 * float(np.max(np.abs(v))) * np.random.default_rng(0).standard_normal(t.size)
    mode = identify(v, FS).modes[0]
    assert abs(mode.frequency_hz / F0 - 1.0) > 0.006
    foot = mode.start_drift["foot_frequency"]
    assert abs(foot / F0 - 1.0) < abs(mode.frequency_hz / F0 - 1.0)
    (said,) = [w for w in mode.warnings if w.startswith("the natural frequency (")]
    assert "the backbone measured at the decays' smallest amplitudes" in said


def test_the_foot_check_needs_a_model_that_still_oscillates():
    """A phantom mode's fit (a swept sine's forced cycles taken for a decay) had its damping
    rate above its frequency: the model's frequency at the foot came out 1e-150 of it, and
    the warning printed a difference of 150 digits. Where the fitted damping or a softening
    halves the model's frequency, there is no model to compare the backbone with."""
    from fsi_lab.dsp.identify import Backbone, _backbone_foot

    n = 200
    bb = Backbone(times=np.arange(n) / 100.0, frequency=np.full(n, 100.0),
                  amplitude=np.linspace(1e-4, 1e-6, n), decay=np.zeros(n, dtype=int))
    w0 = 2 * math.pi * 100.0
    found = _backbone_foot(bb, w0, 0.0, 1.0, 1e-9, "displacement")
    assert found is not None and abs(found[0]) < 1e-12      # the check runs on a free decay
    assert _backbone_foot(bb, w0, 0.0, 1e-150, 1e-9, "displacement") is None
    # the foot is the smaller half of the amplitudes, up to 5e-5: w^2 below zero there
    softening = -2.0 * w0 ** 2 / 5e-5 ** 2
    assert _backbone_foot(bb, w0, softening, 1.0, 1e-9, "displacement") is None
