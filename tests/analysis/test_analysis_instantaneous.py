"""Zero-crossing frequency, extremum amplitude, backbone curves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _analysis_sims import (
    decaying_tone,
    duffing_exact_backbone,
    duffing_hb_backbone,
    duffing_record,
    middle,
    noisy,
    time_axis,
)

from fsi_lab.dsp.backbone import backbone
from fsi_lab.dsp.hvd import hvd
from fsi_lab.dsp.instantaneous import half_cycles, instantaneous
from fsi_lab.errors import AnalysisError


@pytest.mark.parametrize("fs", [80.0, 200.0, 2000.0])     # 8, 20 and 200 samples per cycle
def test_damped_tone_frequency_and_amplitude(fs):
    t = time_axis(10.0, fs)
    x, env, freq = decaying_tone(t, 1.0, 10.0, 0.01, 0.3)
    r = instantaneous(x, fs)
    assert np.max(np.abs(r.frequency / freq[0] - 1)) < 1e-4
    truth = np.exp(-0.01 * 2 * math.pi * 10.0 * r.frequency_times)
    assert np.max(np.abs(r.amplitude / truth - 1)) < 2e-3
    # Extrema at the envelope times cos(phase shift): amplitude ratio constant, decay exact.
    pk = r.peak_amplitudes
    rate = -np.diff(np.log(pk)) / np.diff(r.peak_times)
    np.testing.assert_allclose(rate, 0.01 * 2 * math.pi * 10.0, rtol=5e-3)


def test_offset_is_removed_before_the_crossings():
    fs = 2000.0
    t = time_axis(10.0, fs)
    x, _, freq = decaying_tone(t, 1.0, 10.0, 0.01, 0.3)
    shifted = x + 0.01                                  # 1 % of the initial amplitude
    good = instantaneous(shifted, fs)
    assert abs(good.offset - 0.01) < 2e-4
    assert np.max(np.abs(good.frequency / freq[0] - 1)) < 1e-3
    # Without offset removal the late, small cycles are badly biased (the trap of SCIENCE.md).
    bad = instantaneous(shifted, fs, offset="none")
    assert np.max(np.abs(bad.frequency / freq[0] - 1)) > 0.02


def test_moving_average_of_the_paper():
    fs = 2000.0
    t = time_axis(10.0, fs)
    x, _, freq = decaying_tone(t, 1.0, 10.0, 0.005, 0.0)
    xn = noisy(x, 0.01, seed=3)
    raw = instantaneous(xn, fs)
    smooth = instantaneous(xn, fs, smooth=5)
    assert smooth.frequency.size == raw.frequency.size
    assert np.std(smooth.frequency - freq[0]) < 0.5 * np.std(raw.frequency - freq[0])


def test_noise_tail_is_dropped():
    fs = 2000.0
    t = time_axis(10.0, fs)
    x, _, _ = decaying_tone(t, 1.0, 10.0, 0.02, 0.0)    # decays to 3.5e-6
    r = instantaneous(noisy(x, 0.002, seed=4), fs)
    # Cycles below 10 x the noise RMS (2e-3) are left out: none below 1e-2. The crossing
    # jitter of the faintest cycles kept (10 x the noise) is a few per cent.
    assert r.amplitude.min() > 0.015
    assert np.max(np.abs(r.frequency / (10.0 * math.sqrt(1 - 0.02 ** 2)) - 1)) < 0.03
    big = r.amplitude > 0.1
    assert np.max(np.abs(r.frequency[big] / (10.0 * math.sqrt(1 - 0.02 ** 2)) - 1)) < 0.01


def test_duffing_backbone_matches_harmonic_balance():
    duffing = duffing_record()
    fs, w0, alpha = duffing["fs"], duffing["w0"], duffing["alpha"]
    bb = backbone(duffing["x"], fs)
    sel = middle(bb.amplitude.size)
    a, f = bb.amplitude[sel], bb.frequency[sel]
    # The decay spans a wide range: from 3 alpha A^2 / (4 w0^2) = 0.5 down to about 0.05.
    kappa = 3 * alpha * a ** 2 / (4 * w0 ** 2)
    assert kappa.max() > 0.35 and kappa.min() < 0.1
    assert np.max(np.abs(f / duffing_hb_backbone(a, w0, alpha) - 1)) < 0.01
    assert np.max(np.abs(f / duffing_exact_backbone(a, w0, alpha) - 1)) < 1e-3


def test_duffing_backbone_through_hvd():
    duffing = duffing_record()
    """The chain as used on data: HVD component (default settings), then the backbone."""
    fs, w0, alpha = duffing["fs"], duffing["w0"], duffing["alpha"]
    comp = hvd(duffing["x"], fs, 1)
    bb = backbone(comp.components[0], fs)
    sel = middle(bb.amplitude.size)
    a, f = bb.amplitude[sel], bb.frequency[sel]
    assert np.max(np.abs(f / duffing_hb_backbone(a, w0, alpha) - 1)) < 0.01


def test_linear_backbone_is_flat():
    fs = 2000.0
    t = time_axis(8.0, fs)
    x, _, freq = decaying_tone(t, 2e-3, 12.0, 0.01, 1.0)
    bb = backbone(x, fs, smooth=5)
    assert np.ptp(bb.frequency) / freq[0] < 1e-3
    # flat over a wide range: the points span more than a decade of amplitude
    assert bb.amplitude.max() > 10 * bb.amplitude.min()


@pytest.mark.parametrize("bad, match", [
    (lambda t: np.exp(-t), "zero crossing"),                              # no oscillation
    (lambda t: np.cos(2 * np.pi * 0.05 * t), "zero crossing"),          # one crossing only
    (lambda t: np.cos(2 * np.pi * 300.0 * t) * np.exp(-t), "too low"),  # 3.3 samples/cycle
    (lambda t: np.where(t > 1, np.nan, np.cos(2 * np.pi * 10 * t)), "NaN"),
    (lambda t: np.zeros_like(t), "constant"),
    (lambda t: np.clip(np.cos(2 * np.pi * 10 * t), -0.5, 0.5), "clipped"),
    (lambda t: np.cos(2 * np.pi * 10 * t)[:5], "too short"),
])
def test_bad_records_are_refused(bad, match):
    t = time_axis(5.0, 1000.0)
    with pytest.raises(AnalysisError, match=match) as info:
        instantaneous(bad(t), 1000.0, offset="none" if match == "zero crossing" else "cycles")
    assert str(info.value).startswith("instantaneous:")


def test_bad_parameters_are_refused():
    t = time_axis(2.0, 1000.0)
    x = np.cos(2 * np.pi * 10 * t)
    with pytest.raises(AnalysisError, match="smooth"):
        instantaneous(x, 1000.0, smooth=-1)
    with pytest.raises(AnalysisError, match="offset"):
        instantaneous(x, 1000.0, offset="median")
    with pytest.raises(AnalysisError, match="min_amplitude"):
        instantaneous(x, 1000.0, min_amplitude=1.5)


@pytest.mark.parametrize("offset", [0.15, -0.3, 0.45])
def test_half_cycles_place_an_extremum_between_samples_on_its_side(offset):
    """Below 20 samples per cycle an extremum is the sinusoid through its three largest samples
    (exact for a sinusoid): a peak ``offset`` samples after a sample lies there, for maxima and
    minima alike. It was mirrored about the sample (0.15 read -0.15), which left up to 0.34 %
    in C_i and C_f of noise-free decays at 480-520 Hz, depending on where the samples fell."""
    fs, f = 500.0, 17.0
    t = np.arange(2000) / fs
    peak = (6 + offset) / fs
    hc = half_cycles(np.cos(2 * np.pi * f * (t - peak)), fs, f)
    expected = peak + np.arange(4) / (2 * f)
    np.testing.assert_allclose(hc.times[:4], expected, atol=1e-9)
    np.testing.assert_allclose(np.abs(hc.values[:4]), 1.0, atol=1e-9)
