"""HVD against decaying tones with known components."""

from __future__ import annotations

import numpy as np
import pytest
from _analysis_sims import decaying_tone, middle, noisy, rel_rms, time_axis

from fsi_lab.dsp.hvd import hvd
from fsi_lab.errors import AnalysisError


def two_tones(fs=2000.0, duration=10.0, f1=8.0, f2=27.0, a2=0.3, z1=0.01, z2=0.005):
    t = time_axis(duration, fs)
    s1, e1, fr1 = decaying_tone(t, 1.0, f1, z1, 0.3)
    s2, e2, fr2 = decaying_tone(t, a2, f2, z2, 1.1)
    return t, (s1, e1, fr1), (s2, e2, fr2)


@pytest.mark.parametrize("case", [
    dict(),                                              # 8 and 27 Hz
    dict(f2=60.0, a2=0.5, z2=0.01),                      # fast-decaying second tone
    dict(fs=10000.0, f1=3.0, f2=9.5, duration=12.0),     # heavily oversampled, 3.2:1
    dict(duration=3.0),                                  # short record (24 cycles)
])
def test_two_decaying_tones_default_settings(case):
    t, one, two = two_tones(**case)
    fs = 1.0 / (t[1] - t[0])
    res = hvd(one[0] + two[0], fs, 2)
    mid = middle(t.size)
    # The envelopes never cross, so the components come out in order.
    assert rel_rms(res.components[0][mid], one[0][mid]) < 0.01
    assert rel_rms(res.components[1][mid], two[0][mid]) < 0.03
    assert rel_rms(res.envelopes[0][mid], one[1][mid]) < 0.01
    assert np.max(np.abs(res.frequencies[0][mid] / one[2][mid] - 1)) < 0.005
    assert res.residual.shape == t.shape
    np.testing.assert_allclose(res.components.sum(axis=0) + res.residual, one[0] + two[0],
                               atol=1e-9)


def test_measured_accuracy_is_far_inside_the_requirement():
    """The default settings do much better than the 1 % / 3 % requirement (record ends
    extended by prediction); this guards against silent degradation."""
    t, one, two = two_tones()
    res = hvd(one[0] + two[0], 2000.0, 2)
    mid = middle(t.size)
    assert rel_rms(res.components[0][mid], one[0][mid]) < 1e-3
    assert rel_rms(res.components[1][mid], two[0][mid]) < 5e-3
    good = ~res.edge_mask[0]
    assert rel_rms(res.components[0][good], one[0][good]) < 1e-3


def test_time_varying_frequency_is_followed():
    """A chirp (not a constant carrier): frequency rising from 10 to 14 Hz over the record."""
    fs = 2000.0
    t = time_axis(8.0, fs)
    f_inst = 10.0 + 0.5 * t
    phase = 2 * np.pi * (10.0 * t + 0.25 * t * t)
    env = np.exp(-0.1 * t)
    x = env * np.cos(phase) + 0.2 * np.exp(-0.05 * t) * np.cos(2 * np.pi * 41.0 * t)
    res = hvd(x, fs, 2)
    mid = middle(t.size)
    assert np.max(np.abs(res.frequencies[0][mid] / f_inst[mid] - 1)) < 0.005
    assert rel_rms(res.components[0][mid], (env * np.cos(phase))[mid]) < 0.01


def test_noise_stays_out_of_the_components():
    t, one, two = two_tones()
    x = noisy(one[0] + two[0], 0.01, seed=1)
    res = hvd(x, 2000.0, 2)
    mid = middle(t.size)
    assert rel_rms(res.components[0][mid], one[0][mid]) < 0.01
    assert rel_rms(res.components[1][mid], two[0][mid]) < 0.05


def test_more_than_seven_components_and_order_by_amplitude():
    fs = 4000.0
    t = time_axis(8.0, fs)
    freqs = [5.0, 11.0, 19.0, 31.0, 47.0, 70.0, 101.0, 140.0, 190.0]
    # HVD needs the largest component to dominate the sum of the others at each instant.
    amps = [0.3 ** k for k in range(9)]
    parts = [a * np.exp(-0.05 * t) * np.cos(2 * np.pi * f * t + i)
             for i, (f, a) in enumerate(zip(freqs, amps))]
    res = hvd(sum(parts), fs, 9)
    assert res.components.shape == (9, t.size)
    rms = [np.sqrt(np.mean(res.envelopes[k][~res.edge_mask[k]] ** 2)) for k in range(9)]
    assert np.all(np.diff(rms) <= 0)                    # ordered by RMS envelope
    mid = middle(t.size)
    # Down to 0.24 % of the largest amplitude (component 5) the waveforms are within 1 %.
    for k in range(6):
        assert rel_rms(res.components[k][mid], parts[k][mid]) < 0.01, k
        assert abs(res.mean_frequency(k) / freqs[k] - 1) < 0.005, k


def test_more_components_than_peaks_still_decimate_to_the_band(monkeypatch):
    """Three components asked of two decaying tones (8 and 27 Hz) sampled at 10 kHz: the
    decomposition still runs on the band of the peaks (once at full rate: 0.76 s per 1e6
    samples), and the two tones come out as with two components asked."""
    from fsi_lab.dsp import hvd as module

    lengths = []
    analytic = module._analytic

    def spy(spec, m, out_len, band_gain):
        lengths.append((m, out_len))
        return analytic(spec, m, out_len, band_gain)

    monkeypatch.setattr(module, "_analytic", spy)
    t, one, two = two_tones(fs=10000.0)
    res = hvd(one[0] + two[0], 10000.0, 3)
    m, out_len = lengths[0]
    assert out_len < m / 5                         # 1/10: the spectrum to 150 Hz
    assert all(length == (out_len, out_len) for length in lengths[1:])
    mid = middle(t.size)
    assert rel_rms(res.components[0][mid], one[0][mid]) < 1e-3
    assert rel_rms(res.components[1][mid], two[0][mid]) < 5e-3


def test_edge_mask_marks_the_record_ends():
    t, one, two = two_tones()
    res = hvd(one[0] + two[0], 2000.0, 2)
    assert res.edge_mask.shape == (2, t.size)
    for k in range(2):
        edge = int(np.ceil(2000.0 / res.cutoffs[k]))
        assert res.edge_mask[k, :edge].all() and res.edge_mask[k, -edge:].all()
        assert not res.edge_mask[k, edge:-edge].any()
    # Automatic cut-offs: half of min(frequency, distance to the other peak).
    np.testing.assert_allclose(sorted(res.cutoffs), [4.0, 9.5], rtol=0.01)


def test_explicit_cutoff_and_mirror_padding():
    t, one, two = two_tones()
    res = hvd(one[0] + two[0], 2000.0, 2, cutoff=4.0, padding="mirror")
    np.testing.assert_allclose(res.cutoffs, 4.0)
    mid = middle(t.size)
    assert rel_rms(res.components[0][mid], one[0][mid]) < 0.01


@pytest.mark.parametrize("bad, match", [
    (lambda x: np.where(np.arange(x.size) == 500, np.nan, x), "NaN or infinite"),
    (lambda x: np.where(np.arange(x.size) == 7, np.inf, x), "NaN or infinite"),
    (lambda x: np.full_like(x, 0.25), "constant"),
    (lambda x: x[:20], "too short"),
    (lambda x: np.clip(x, -0.6, 0.6), "clipped"),
])
def test_bad_records_are_refused(bad, match):
    t, one, two = two_tones()
    with pytest.raises(AnalysisError, match=match) as info:
        hvd(bad(one[0] + two[0]), 2000.0, 2)
    assert str(info.value).startswith("hvd:")


def test_too_low_sample_rate_is_refused():
    t = time_axis(2.0, 100.0)
    with pytest.raises(AnalysisError, match="too low.*samples per cycle"):
        hvd(np.exp(-t) * np.cos(2 * np.pi * 40.0 * t), 100.0, 1)


def test_record_too_short_for_the_cutoff_is_refused():
    t = time_axis(0.5, 2000.0)
    x = np.cos(2 * np.pi * 8.0 * t) + 0.3 * np.cos(2 * np.pi * 27.0 * t)
    with pytest.raises(AnalysisError, match="too short for a cut-off"):
        hvd(x, 2000.0, 2)


@pytest.mark.parametrize("kwargs, match", [
    (dict(n_components=0), "n_components"),
    (dict(cutoff=-1.0), "cutoff"),
    (dict(cutoff=[1.0, 2.0, 3.0]), "cutoff has 3 values"),
    (dict(padding="zeros"), "padding"),
])
def test_bad_parameters_are_refused(kwargs, match):
    t, one, two = two_tones()
    args = dict(n_components=2)
    args.update(kwargs)
    with pytest.raises(AnalysisError, match=match):
        hvd(one[0] + two[0], 2000.0, **args)


@pytest.mark.parametrize("fs", [0.0, -5.0, float("nan"), "fast"])
def test_bad_sample_rate_is_refused(fs):
    with pytest.raises(AnalysisError, match="sample rate"):
        hvd(np.cos(np.arange(1000) * 0.3), fs, 1)
