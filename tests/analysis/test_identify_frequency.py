"""identify()'s natural frequency on a short, heavily damped impact record with a weak line in
the mode's band: the features of pysdkit's beam record (tests/analysis/test_real_data.py), with
known truth.

The record: five decaying modes in acceleration, as a least-squares fit of damped sinusoids gives
them on the beam record's channel 0 (2560 Hz, 1280 samples = 0.5 s, the impact at sample 23):
30.703 Hz (decay rate 5.29 1/s: damping ratio 2.7 %, about 15 cycles in the record), a weak
48.79 Hz mode (6 % of the first's acceleration) inside the first mode's band, 215.77 Hz, and
586.1 and 1114.9 Hz (4.4 and 2.3 samples per cycle: left out as undersampled); white noise of
0.3 m/s^2 (the fit's residual on the record is 0.9 m/s^2 RMS, most of it above 150 Hz).

The frequency was fitted to the half periods between crossings, weighted as if each were
measured on its own: each crossing's error enters two neighbouring half periods with opposite
signs, so their weighted mean telescoped to the first and last crossings, and on a decay this
short and damped to the window's first cycles, where the filters' edge and the noise weigh
most. Measured on these records (10 seeds): -0.56 % (noise 0.3) and -0.20 % (noise 0.08) from
the truth; the beam record's channels 0 and 1 gave 30.58 and 30.47 Hz. Fitted to the crossing
times themselves: -0.07 % and -0.04 %, every 95 % interval holding the truth (20 seeds).
"""

from __future__ import annotations

import numpy as np
import pytest

from fsi_lab.dsp.identify import identify

FS, N, START = 2560.0, 1280, 23
#: (frequency Hz, decay rate 1/s, cosine and sine amplitudes m/s^2) of each mode.
MODES = ((30.703, 5.294, -0.607, 3.814), (48.793, 3.529, -0.219, -0.123),
         (215.774, 6.01, -15.152, -18.586), (586.115, 21.441, 14.869, 7.755),
         (1114.948, 16.178, 3.524, -3.667))
NOISE = 0.3
#: The target on natural frequencies (relative).
TARGET = 0.002


def beam_like(seed: int) -> np.ndarray:
    t = (np.arange(N) - START) / FS
    x = np.zeros(N)
    for f, s, a, b in MODES:
        x += np.exp(-s * t) * (a * np.cos(2 * np.pi * f * t) + b * np.sin(2 * np.pi * f * t))
    x[:START] = 0.0
    return x + NOISE * np.random.default_rng(seed).standard_normal(N)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_short_damped_mode_beside_a_weak_line_within_the_target(seed):
    found = identify(beam_like(seed), FS, quantity="acceleration")
    for truth in (MODES[0][0], MODES[2][0]):
        mode = min(found.modes, key=lambda m: abs(m.damped_frequency_hz - truth))
        damped = mode.damped_frequency_hz
        scale = damped / mode.frequency_hz
        lo, hi = mode.frequency_ci[0] * scale, mode.frequency_ci[1] * scale
        assert damped == pytest.approx(truth, rel=TARGET), (seed, truth, damped)
        assert lo <= truth <= hi, (seed, truth, damped, lo, hi)


def test_a_short_stretch_of_something_else_does_not_set_a_mode_s_first_frequency():
    """A mode's first frequency (before the fits refine it) pools its decays' half periods
    weighted by each decay's energy: a decay of 194 extrema from 1e-2 at 17.06 Hz beside a
    stretch of 8 near 1e-7 at 4.3 Hz (what the noise-free wet bench's relative signal held at
    its end, split off as a decay) gives 17.06 Hz, and so does a heavily damped decay of 12
    extrema beside a long, small one; the plain median of two gave the mean (7.6 Hz on the
    wet bench, where the fits started there never came back: the mode was reported at 5.7 Hz).
    Two decays of equal weight give the mean of their half periods."""
    from fsi_lab.dsp.identify import _pooled_half_period

    def decay(frequency, count, start, amplitude):
        crossings = start + np.arange(count + 1) / (2.0 * frequency)
        times = 0.5 * (crossings[1:] + crossings[:-1])
        values = amplitude * (-0.8) ** np.arange(count)
        return {"crossings": crossings, "times": times, "values": values}

    def frequency(decays):
        return 0.5 / _pooled_half_period(decays)

    main = decay(17.06, 194, 0.5, 1e-2)
    assert frequency([main, decay(4.3, 8, 16.5, 1e-7)]) == pytest.approx(17.06, rel=1e-9)
    assert frequency([decay(17.06, 12, 0.5, 1e-2), decay(16.0, 400, 3.0, 1e-4)]) \
        == pytest.approx(17.06, rel=1e-9)
    even = _pooled_half_period([decay(17.0, 50, 0.0, 1.0), decay(18.0, 50, 5.0, 1.0)])
    assert even == pytest.approx(0.25 * (1 / 17.0 + 1 / 18.0), rel=1e-9)
    assert frequency([main]) == pytest.approx(17.06, rel=1e-9)
    assert _pooled_half_period([]) is None


def test_the_noise_s_shift_of_the_first_crossings_is_not_read_as_a_frequency():
    """A heavily damped 30.78 Hz mode (2.8 %) under a 215.6 Hz mode of 2.2 times its
    acceleration, from an impact at sample 3, with white noise of 2.2 % of the first mode's
    largest acceleration. The noise changes the prediction that pads the window's ends for the
    band filters, and with it the first crossings of the 31 Hz band (by about 1.5 ms, a tenth
    of a half period, the same sign on every noise record); the noise-free model's crossings
    do not move so. Paired with those, the frequency read 0.18 % low on average over these
    six records (each -0.15 to -0.20 %): most of the 0.2 % target on this mode alone. With
    the model's crossings moved by their mean shift over its noisy realisations: -0.03 % on
    average (each -0.08 to +0.02 %); asserted within 0.06 %."""
    fs, n, start = 2560.0, 1280, 3
    t = np.clip((np.arange(n) - start) / fs, 0.0, None)
    errors = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        x = np.zeros(n)
        for (f, zeta), amplitude, phase in zip(((30.78, 0.028), (215.6, 0.0047)), (4.5, 10.0),
                                               rng.uniform(0.0, 2 * np.pi, 2)):
            w = 2 * np.pi * f
            x += amplitude * np.exp(-zeta * w * t) * np.sin(w * t + phase)
        x[:start] = 0.0
        x += 0.1 * rng.standard_normal(n)
        found = identify(x, fs, quantity="acceleration")
        mode = min(found.modes, key=lambda m: abs(m.damped_frequency_hz - 30.78))
        errors.append(mode.damped_frequency_hz / 30.78 - 1.0)
    assert abs(np.mean(errors)) < 6e-4, errors
    assert max(abs(e) for e in errors) < TARGET, errors


@pytest.mark.parametrize("drift", [0.0, 0.002])
def test_a_frequency_that_drifts_over_the_decay_is_warned_and_its_interval_widened(drift):
    """A linear decay whose frequency drifts (a temperature change, say) by 0.2 % over 4 s:
    the crossings fit one frequency to it with an interval of 0.001 % that holds the frequency
    of no part of the decay. The early, middle and late cycles disagree beyond their noise, so
    the frequency is warned and its interval widened to hold the decay's own frequencies; the
    same decay without the drift is not."""
    fs, duration, f0, zeta = 2000.0, 4.0, 17.0, 0.005
    t = np.arange(int(duration * fs)) / fs
    frequency = f0 * (1.0 + drift * t / duration)
    x = np.exp(-zeta * 2 * np.pi * f0 * t) * np.cos(2 * np.pi * np.cumsum(frequency) / fs)
    x += 0.01 * np.random.default_rng(0).standard_normal(t.size)
    mode = identify(x, fs).modes[0]
    wander = [w for w in mode.warnings if "frequency is not the same over each decay" in w]
    lo, hi = mode.frequency_ci
    natural = f0 / np.sqrt(1.0 - zeta ** 2)     # the cosine's is the damped frequency
    if drift == 0.0:
        assert not wander, mode.warnings
        assert lo <= natural <= hi and hi - lo < 1e-4 * f0
    else:
        assert len(wander) == 1 and "interval is widened" in wander[0], mode.warnings
        third = f0 * (1.0 + drift / 3.0)        # the frequency a third into the decay
        assert lo <= third <= hi, (lo, third, hi)
