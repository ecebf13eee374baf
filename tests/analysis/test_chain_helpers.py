"""Helpers the analysis plugins share: the channel noise (one cached estimate for the whole
chain, HVD's automatic start included) and the runs of decay labels (one helper for the
damping fits and the per-decay moving average)."""

from __future__ import annotations

import numpy as np
import pytest

from _analysis_sims import decaying_tone, noisy, time_axis
from test_analysis_plugins import run
from fsi_lab.contract import AnalysisContext, ChannelData
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis import _chain
from fsi_lab.dsp.decays import decay_runs, smooth_per_decay
from fsi_lab.dsp.damping import damping_from_peaks


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
    assert _chain.channel_noise(context) is _chain.channel_noise(context)   # cached


def test_hvd_automatic_start_asks_the_shared_channel_noise(monkeypatch):
    calls = []
    shared = _chain.channel_noise

    def counted(context):
        calls.append(context.channel.name)
        return shared(context)

    monkeypatch.setattr(_chain, "channel_noise", counted)
    _, summary = run({"tip": noisy_tone()}, ("hvd",),
                     params={"hvd": {"components": 1, "method": "hvd"}})
    assert "errors" not in summary["tip"], summary["tip"].get("errors")
    assert "tip" in calls


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
