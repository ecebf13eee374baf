"""Isolated spikes (a vibrometer's dropouts, a digitiser's glitches): found, replaced, named.

Ground truth: the oscillators of ``validation.cases`` (DOP853 at rtol 1e-10) with spikes added
at known samples.
"""

from __future__ import annotations

import numpy as np
import pytest

from fsi_lab.dsp.identify import identify
from fsi_lab.dsp.spikes import find_spikes, without_spikes
from validation.cases import WET_C_F, WET_C_I, WET_F, WET_MASS, Case, Mode, clean_record, trial


def decay(fs: float, noise: float = 0.005, duration: float = 2.0, frequency: float = WET_F,
          **mode) -> Case:
    return Case("spiky", (Mode(frequency, c_f=mode.pop("c_f", WET_C_F), x0=1e-3, **mode),),
                fs=fs, duration=duration, noise=noise)


def with_spikes(x: np.ndarray, count: int, size: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``x`` with ``count`` spikes of ``size`` times its largest value, at least 5 samples
    apart and from the ends; and their samples."""
    rng = np.random.default_rng(seed)
    at = np.sort(rng.choice(np.arange(5, x.size - 5, 5), count, replace=False))
    y = x.copy()
    y[at] += size * float(np.max(np.abs(x))) * rng.choice([-1.0, 1.0], count)
    return y, at


@pytest.mark.parametrize("fs, frequency", [(800.0, 60.0), (3000.0, WET_F), (20000.0, 150.0)])
def test_find_spikes_finds_each_spike_and_nothing_else(fs, frequency):
    """From 13 to 300 samples per cycle, noise 0.5 %: every spike of a third of the largest
    value is found, and no other sample."""
    x = trial(decay(fs, frequency=frequency), 3)
    y, at = with_spikes(x, 30, 0.3, 4)
    np.testing.assert_array_equal(find_spikes(y), at)
    assert find_spikes(x).size == 0


@pytest.mark.parametrize("case", [
    decay(500.0, noise=0.001),
    decay(10000.0, noise=0.03, duration=1.0),
    decay(1000.0, noise=0.0, c_f=0.0, c_i=0.3, friction=0.4),       # dry friction: it sticks
    Case("two modes", (Mode(WET_F, c_f=WET_C_F, x0=1e-3), Mode(2.0 * WET_F, c_i=1.0, x0=3e-4)),
         fs=2000.0, duration=2.0),
])
def test_find_spikes_leaves_clean_records_alone(case):
    """No spike in records without any: noise from none to 3 %, 29 to 590 samples per cycle,
    a motion that stops dead, two modes; nor at a step or a kink (a release inside the record,
    a velocity that jumps at a kick), which is no single sample off its neighbours."""
    x = clean_record(case) if case.noise == 0.0 else trial(case, 1)
    assert find_spikes(x).size == 0
    step = x.copy()
    step[x.size // 2:] += 0.5 * float(np.max(np.abs(x)))
    still = case.noise * float(np.max(np.abs(x))) * np.random.default_rng(2).standard_normal(200)
    kink = np.concatenate([still, x])
    assert find_spikes(step).size == 0
    assert find_spikes(kink).size == 0


def test_without_spikes_gives_back_the_oscillation():
    """A spike replaced by its neighbours' cubic: within 1e-3 of the oscillation's amplitude
    at 29 samples per cycle (the cubic's own error, a sixth of (w / fs)^4)."""
    case = decay(500.0, noise=0.0)
    x = clean_record(case)
    y, at = with_spikes(x, 20, 0.5, 1)
    np.testing.assert_allclose(without_spikes(y, at), x, rtol=0,
                               atol=1e-3 * float(np.max(np.abs(x))))


def test_spikes_no_longer_bias_c_i_and_c_f():
    """40 spikes of 30 % of the largest value in a 60 Hz decay at 3 kHz, noise 0.5 %: C_i read
    about 4 % lower and C_f 6 % higher than from the same record without them, unwarned (their
    energy lifted the band's extrema). Removed, both are within 0.6 % and 1 % of what the
    record without spikes gives (and within 2 % and 5 % of the truth), and a note names
    them."""
    case = decay(3000.0, frequency=60.0, duration=1.2, c_f=WET_C_F)
    for seed in range(3):
        x = trial(case, seed)
        y, at = with_spikes(x, 40, 0.3, seed)
        clean = identify(x, case.fs).modes[0].quadratic.params
        found = identify(y, case.fs)
        a, beta = found.modes[0].quadratic.params
        assert 2 * WET_MASS * (a - clean[0]) == pytest.approx(0.0, abs=0.006 * WET_C_I)
        assert WET_MASS * (beta - clean[1]) == pytest.approx(0.0, abs=0.01 * WET_C_F)
        assert 2 * WET_MASS * a == pytest.approx(WET_C_I, rel=0.02)
        assert WET_MASS * beta == pytest.approx(WET_C_F, rel=0.05)
        assert find_spikes(y).size >= 38
        assert any(note.startswith(f"{find_spikes(y).size} isolated samples stand far off")
                   for note in found.notes)
