"""Amplitude spectra and FRFs against known tones and a simulated base-excited oscillator."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal as ssig
from _analysis_sims import decaying_tone, time_axis

from fsi_lab.dsp.frf import frf
from fsi_lab.dsp.spectrum import amplitude_spectrum, spectral_peaks
from fsi_lab.errors import AnalysisError


def test_amplitude_spectrum_of_tones():
    fs = 1000.0
    t = time_axis(10.0, fs)
    x = 0.7 * np.cos(2 * np.pi * 12.34 * t) + 0.2 * np.cos(2 * np.pi * 81.7 * t) + 0.05
    f, a = amplitude_spectrum(x, fs, window="flattop")
    assert a[np.argmin(np.abs(f - 12.34))] == pytest.approx(0.7, rel=0.01)
    peaks = spectral_peaks(x, fs, window="hann", min_relative=0.05)
    np.testing.assert_allclose(peaks.frequencies, [12.34, 81.7], atol=0.01)   # 1/10 bin
    np.testing.assert_allclose(peaks.amplitudes, [0.7, 0.2], rtol=0.03)
    peaks = spectral_peaks(x, fs, window="flattop", min_relative=0.05)
    np.testing.assert_allclose(peaks.amplitudes, [0.7, 0.2], rtol=0.005)


def test_spectral_peaks_of_a_two_mode_decay():
    fs = 2000.0
    t = time_axis(8.0, fs)
    x = decaying_tone(t, 1.0, 2.73, 0.05, 0.0)[0] + decaying_tone(t, 0.3, 18.67, 0.02, 1.0)[0]
    peaks = spectral_peaks(x, fs, window="decay", min_relative=0.02)
    np.testing.assert_allclose(np.sort(peaks.frequencies), [2.73, 18.67], rtol=0.01)


def base_excited(fs, n, fn, zeta, seed, output_noise=0.0):
    """Relative tip velocity of z'' + 2 zeta w z' + w^2 z = -a_b under white a_b (exact ZOH).

    Returns input, output and the discrete system (its exact frequency response is the truth).
    """
    w = 2 * math.pi * fn
    sys = ssig.StateSpace([[0.0, 1.0], [-w * w, -2 * zeta * w]], [[0.0], [-1.0]],
                          [[0.0, 1.0]], [[0.0]])
    d = sys.to_discrete(1.0 / fs, method="zoh")
    rng = np.random.default_rng(seed)
    a_b = rng.standard_normal(n)
    _, y, _ = ssig.dlsim(d, a_b)
    y = y[:, 0]
    return a_b, y + output_noise * np.std(y) * rng.standard_normal(n), d


def test_frf_natural_frequency_and_half_power_damping():
    fs = 500.0
    a_b, v, _ = base_excited(fs, 2 ** 18, 18.67, 0.02, seed=5)
    res = frf(a_b, v, fs, segment=2 ** 14)
    assert res.natural_frequencies.size >= 1
    k = int(np.argmax(res.peak_magnitudes))
    assert res.natural_frequencies[k] == pytest.approx(18.67, rel=0.005)
    assert res.damping_ratios[k] == pytest.approx(0.02, rel=0.1)
    band = (res.frequency > 5) & (res.frequency < 100)
    assert np.min(res.coherence[band]) > 0.95


def test_h1_is_unbiased_by_output_noise_and_h2_is_not():
    fs = 500.0
    a_b, v, d = base_excited(fs, 2 ** 18, 18.67, 0.02, seed=6, output_noise=0.3)
    res = frf(a_b, v, fs, segment=2 ** 12)
    z = np.exp(2j * math.pi * res.frequency / fs)
    exact = np.abs([(d.C @ np.linalg.solve(zk * np.eye(2) - d.A, d.B) + d.D)[0, 0]
                    for zk in z])
    band = (res.frequency > 40) & (res.frequency < 80)          # away from the resonance
    assert np.median(np.abs(res.h1[band]) / exact[band]) == pytest.approx(1.0, rel=0.03)
    assert np.median(np.abs(res.h2[band]) / exact[band]) > 1.5


@pytest.mark.parametrize("kwargs, match", [
    (dict(y=np.sin(np.arange(100.0))), "different lengths"),
    (dict(segment=4), "segment"),
    (dict(segment=4096), "segment"),
    (dict(overlap=1.0), "overlap"),
])
def test_frf_bad_input(kwargs, match):
    rng = np.random.default_rng(0)
    args = dict(x=rng.standard_normal(4096), y=rng.standard_normal(4096))
    args.update(kwargs)
    with pytest.raises(AnalysisError, match=match):
        frf(args.pop("x"), args.pop("y"), 1000.0, **args)


def test_frf_needs_two_segments():
    rng = np.random.default_rng(0)
    with pytest.raises(AnalysisError, match="at least 2"):
        frf(rng.standard_normal(1000), rng.standard_normal(1000), 1000.0, segment=800)


def test_spectrum_bad_input():
    with pytest.raises(AnalysisError, match="NaN"):
        amplitude_spectrum(np.array([1.0, np.nan] * 20), 100.0)
    with pytest.raises(AnalysisError, match="window"):
        amplitude_spectrum(np.sin(np.arange(100)), 100.0, window="kaiser")
