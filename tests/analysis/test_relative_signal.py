"""The base motion is subtracted at the channel's own sample times (t0 may differ)."""

import numpy as np

from fsi_lab.contract import AnalysisContext, ChannelData
from fsi_lab.plugins.analysis._hvd import relative_signal


def test_base_motion_is_aligned_on_t0():
    fs, delay = 10000.0, 1.1e-3
    t = np.arange(40000) / fs
    f_base, f_beam = 30.0, 17.0
    base_velocity = lambda time: 0.02 * np.sin(2 * np.pi * f_base * time)
    base_acc = lambda time: 0.02 * 2 * np.pi * f_base * np.cos(2 * np.pi * f_base * time)
    relative = 0.05 * np.sin(2 * np.pi * f_beam * t)
    # the vibrometer channel starts `delay` earlier than the accelerometer channel
    tip_time = t - delay
    tip = ChannelData("tip", relative + base_velocity(tip_time), fs, "velocity", "m/s", -delay)
    ref = ChannelData("base", base_acc(t), fs, "acceleration", "m/s^2", 0.0)
    context = AnalysisContext(channel=tip, channels={"tip": tip, "base": ref}, results={},
                              reference="base")
    data, used = relative_signal(context, "auto")
    assert used == "base"
    inner = slice(4000, -4000)
    error = np.max(np.abs(data[inner] - relative[inner])) / 0.05
    assert error < 0.01, error


def test_a_base_that_cannot_be_integrated_is_named_as_the_reference():
    """A base accelerometer clipped flat (or unplugged: all zeros) is the reference's fault:
    the error names the reference channel and the way out, not only the channel analysed."""
    import pytest

    from fsi_lab.errors import AnalysisError

    fs = 5000.0
    t = np.arange(20000) / fs
    tip_data = 0.05 * np.exp(-2.0 * t) * np.sin(2 * np.pi * 17.0 * t)
    for base_data, fault in ((np.clip(3.0 * np.sin(2 * np.pi * 30.0 * t), -2.5, 2.5),
                              "looks clipped"),
                             (-0.0 * t, "is constant (every sample is 0)")):
        tip = ChannelData("tip", tip_data, fs, "velocity", "m/s")
        ref = ChannelData("base_acc", base_data, fs, "acceleration", "m/s^2")
        context = AnalysisContext(channel=tip, channels={"tip": tip, "base_acc": ref},
                                  results={}, reference="base_acc")
        with pytest.raises(AnalysisError) as caught:
            relative_signal(context, "auto")
        text = str(caught.value)
        assert "the base acceleration reference 'base_acc' cannot be integrated" in text, text
        assert fault in text and "--set analysis.hvd.relative=no" in text, text
