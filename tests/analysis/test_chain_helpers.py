"""Helpers the analysis plugins share: the channel's record shared by the chain (its spectrum
computed once, at a fast FFT length, and its noise level) and the runs of decay labels (one
helper for the damping fits and the per-decay moving average)."""

from __future__ import annotations

import traceback

import numpy as np
import pytest
import scipy.fft
from _analysis_sims import decaying_tone, linear_decay, noisy, time_axis
from test_analysis_plugins import DEFAULT_CHAIN, run

from fsi_lab.contract import AnalysisContext, ChannelData, SharedRecord, record_spectrum
from fsi_lab.dsp.damping import damping_from_peaks
from fsi_lab.dsp.decays import decay_runs, smooth_per_decay
from fsi_lab.dsp.instantaneous import noise_rms
from fsi_lab.dsp.spectrum import amplitude_spectrum, free_decay_peaks
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis import _chain


def noisy_tone(fs: float = 2000.0, sigma: float = 1e-3) -> ChannelData:
    """A decaying 12 Hz tone (zeta 0.002, amplitude 1) with white noise of RMS ``sigma``."""
    t = time_axis(10.0, fs)
    x = decaying_tone(t, 1.0, 12.0, 0.002, 0.3)[0]
    return ChannelData("tip", noisy(x, sigma, seed=7, reference=1.0), fs, "velocity", "m/s")


def test_channel_noise_is_the_white_noise_rms_computed_once():
    ch = noisy_tone()
    context = AnalysisContext(channel=ch, channels={"tip": ch}, results={})
    sigma, f_dom = _chain.channel_noise(context)
    assert sigma == pytest.approx(1e-3, rel=0.1)
    assert f_dom == pytest.approx(12.0, rel=0.01)
    assert _chain.channel_noise(context) is _chain.channel_noise(context)   # computed once
    # the library's estimate on the record itself, within the scatter of a median (0.5 %)
    assert sigma == pytest.approx(noise_rms(ch.data, ch.sample_rate, f_dom), rel=0.005)
    # Another context on the same shared record asks nothing again.
    other = AnalysisContext(channel=ch, channels={"tip": ch}, results={}, shared=context.shared)
    assert _chain.channel_noise(other) is _chain.channel_noise(context)


def test_the_shared_spectrum_is_the_library_one_at_a_fast_length():
    """A record of a prime number of samples is transformed at the next fast length (5-smooth):
    the spectrum is the library's, zero-padded, and a sinusoid's peak keeps its amplitude."""
    fs, n = 1000.0, 100_003                           # prime
    t = np.arange(n) / fs
    x = 0.3 * np.sin(2 * np.pi * 37.25 * t) + 0.01 * np.random.default_rng(4).standard_normal(n)
    spectrum = record_spectrum(x, fs, "hann")
    assert spectrum.samples == n and spectrum.nfft == scipy.fft.next_fast_len(n, real=True)
    m = spectrum.nfft
    for p in (2, 3, 5):
        while m % p == 0:
            m //= p
    assert m == 1 and n <= spectrum.nfft < 1.02 * n
    f, a = amplitude_spectrum(x, fs, window="hann", nfft=spectrum.nfft)
    np.testing.assert_array_equal(spectrum.frequency, f)
    np.testing.assert_array_equal(spectrum.amplitude, a)
    k = int(np.argmax(spectrum.amplitude))
    assert spectrum.frequency[k] == pytest.approx(37.25, abs=fs / n)
    assert spectrum.amplitude[k] == pytest.approx(0.3, rel=0.16)    # Hann scalloping <= 15 %
    shared = SharedRecord(ChannelData("x", x, fs, "velocity", "m/s"))
    assert shared.spectrum("hann") is shared.spectrum("hann")


def test_free_decay_peaks_from_the_shared_spectrum_are_the_library_ones():
    """Peaks of the shared spectrum, for one decay and for an impulse train (several decays:
    the decays' averaged spectrum), as :func:`fsi_lab.dsp.spectrum.free_decay_peaks` finds them
    (within the finer frequency step of the fast length)."""
    fs = 2000.0
    t = time_axis(8.0, fs)
    one = decaying_tone(t, 1.0, 12.0, 0.004, 0.3)[0] + 0.2 * decaying_tone(t, 1.0, 47.0, 0.003,
                                                                            1.0)[0]
    train = np.zeros_like(t)
    for start in (0.0, 2.0, 4.0, 6.0):
        late = t >= start
        train[late] += linear_decay(t[late] - start, 1.0, 12.0, 0.01, 0.0)[0]
    for x in (one, train):
        x = noisy(x, 1e-3, seed=3)
        ch = ChannelData("tip", x, fs, "displacement", "m")
        context = AnalysisContext(channel=ch, channels={"tip": ch}, results={})
        ours = _chain.free_decay_peaks_of(context)
        theirs = free_decay_peaks(x, fs, min_relative=0.01, smoothing=0.05)
        assert ours.frequencies.size == theirs.frequencies.size > 0
        np.testing.assert_allclose(np.sort(ours.frequencies), np.sort(theirs.frequencies),
                                   rtol=2e-3)


def two_channel_record() -> dict[str, ChannelData]:
    """A tip velocity (two decaying modes, 6 and 31 Hz) over a base acceleration reference
    (a decaying 3 Hz shake), 6 s at 2 kHz, a little noise on both."""
    fs = 2000.0
    t = time_axis(6.0, fs)
    _, v1 = linear_decay(t, 5e-3, 6.0, 0.01, 0.2)
    _, v2 = linear_decay(t, 4e-4, 31.0, 0.005, 0.9)
    base = decaying_tone(t, 0.05, 3.0, 0.2, 0.0)[0]
    return {"tip": ChannelData("tip", noisy(v1 + v2, 2e-3, seed=1), fs, "velocity", "m/s"),
            "base": ChannelData("base", noisy(base, 1e-3, seed=2), fs, "acceleration",
                                "m/s^2")}


def whole_record_transforms(monkeypatch, n: int) -> list[str]:
    """Patch the real FFTs to list, for each transform of a whole record (``n`` samples, or
    the fast length of it), who asked for it: the first function of fsi-lab outside
    ``fsi_lab/dsp`` (the analysis plugins, the chain's shared record), or the library's entry
    point when the library asked itself."""
    sizes = {n, scipy.fft.next_fast_len(n, real=True)}
    asked: list[str] = []

    def counting(original):
        def transform(x, n=None, *args, **kwargs):
            if (n or np.shape(x)[-1]) in sizes:
                frames = [f for f in traceback.extract_stack()[:-1] if "fsi_lab" in f.filename
                          or "/plugins/" in f.filename]
                outside = [f for f in frames if "/dsp/" not in f.filename]
                first_dsp = next((f for f in frames if "/dsp/" in f.filename), None)
                caller = outside[-1].name if outside else "?"
                asked.append(first_dsp.name if first_dsp is not None
                             and caller != "record_spectrum" else caller)
            return original(x, n, *args, **kwargs)
        return transform

    monkeypatch.setattr(scipy.fft, "rfft", counting(scipy.fft.rfft))
    monkeypatch.setattr(np.fft, "rfft", counting(np.fft.rfft))
    return asked


def test_one_spectrum_per_record_and_window_for_the_whole_chain(monkeypatch):
    """The default chain over a channel with a base reference used to compute the whole
    record's spectrum 8 times (measured with this counter before the chain shared it: the
    spectrum plugin, the lowest mode for the base subtraction, the channel noise twice, the
    identification three times and the base's integration once). The plugins now ask the
    shared record, which computes one spectrum per window (``decay`` and ``hann``); what is
    left is the library's own work inside identify and integrate (of other records: the
    channel minus its base, and the base)."""
    channels = two_channel_record()
    asked = whole_record_transforms(monkeypatch, channels["tip"].data.size)
    _, summary = run(channels, DEFAULT_CHAIN, mass_per_length=0.1,
                     analysis={"channels": ["tip"], "reference": "base"})
    assert "errors" not in summary["tip"], summary["tip"]["errors"]
    assert asked.count("record_spectrum") == 2, asked
    assert set(asked) <= {"record_spectrum", "identify", "integrate"}, asked
    assert len(asked) <= 6, asked


def test_decay_runs_serve_the_fits_and_the_moving_average():
    labels = np.array([0, 0, 0, 1, 1, 3, 3, 3, 3])
    runs = decay_runs(labels, labels.size)
    assert [(r.start, r.stop) for r in runs] == [(0, 3), (3, 5), (5, 9)]
    assert decay_runs(None, 4) == [slice(0, 4)]
    # A level per decay: an average that mixed two decays would leave it.
    levels = np.array([1.0, 5.0, 2.0])[np.repeat(np.arange(3), [3, 2, 4])]
    np.testing.assert_array_equal(smooth_per_decay(levels, labels, 2), levels)
    t = np.arange(9) * 0.1
    with pytest.raises(AnalysisError, match=r"damping: decay labels have shape \(8,\); "
                                            r"expected one per point \(9\)"):
        damping_from_peaks(t, np.exp(-t), 5.0, decay=labels[:-1])
