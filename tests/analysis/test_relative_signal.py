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
