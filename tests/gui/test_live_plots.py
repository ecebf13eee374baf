"""Live plots: ring buffers and decimated drawing whose cost does not grow with the run."""

import numpy as np

from fsi_lab.events import DataBlock
from fsi_lab.gui.decimate import min_max_decimate
from fsi_lab.gui.live_plots import LivePlots, RingBuffer


def test_ring_buffer_keeps_the_latest_samples_in_order():
    ring = RingBuffer(5)
    ring.extend(np.arange(3))
    assert ring.latest().tolist() == [0, 1, 2]
    ring.extend(np.arange(3, 7))
    assert ring.latest().tolist() == [2, 3, 4, 5, 6]
    assert ring.latest(2).tolist() == [5, 6]
    ring.extend(np.arange(100, 112))
    assert ring.latest().tolist() == [107, 108, 109, 110, 111] and ring.total == 19


def test_decimation_keeps_peaks():
    t = np.arange(100_000) / 1e4
    y = np.zeros_like(t)
    y[12_345] = 5.0
    y[54_321] = -3.0
    td, yd = min_max_decimate(t, y, 2000)
    assert yd.size <= 2001 and yd.max() == 5.0 and yd.min() == -3.0
    assert np.all(np.diff(td) >= 0)


def test_display_is_bounded_while_data_grows(qtbot):
    plots = LivePlots(window_s=2.0, max_points=1000)
    qtbot.addWidget(plots)
    plots.configure({"a": "V", "b": "m/s"}, 5000.0)
    plots.show()
    rng = np.random.default_rng(1)
    for i in range(60):                                   # 6 s of data, window 2 s
        block = {name: rng.normal(size=500) for name in ("a", "b")}
        plots.on_block(DataBlock(i * 0.1, 5000.0, block))
    plots.refresh(force=True)
    assert plots.buffers["a"].count == 10_000 and plots.buffers["a"].total == 30_000
    assert plots.samples_shown("a") <= 1001
    x, _ = plots.curves["a"].getData()
    assert 5.99 <= x[-1] < 6.0 and x[0] >= 4.0 - 1e-9
    frames = plots.frames
    plots.refresh()                                       # nothing new: nothing drawn
    assert plots.frames == frames


def test_unknown_channel_or_rate_reconfigures(qtbot):
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.on_block(DataBlock(0.0, 1000.0, {"x": np.ones(100)}))
    assert set(plots.buffers) == {"x"} and plots.sample_rate == 1000.0


def test_empty_plots_show_the_window_the_header_names_and_whole_decades(qtbot):
    plots = LivePlots(window_s=10.0)
    qtbot.addWidget(plots)
    plots.resize(900, 500)
    plots.show()
    qtbot.waitExposed(plots)
    plots.configure({"drive": "V", "tip_velocity": "m/s"}, 1000.0)
    assert "window 10 s" in plots.status.text()
    qtbot.waitUntil(lambda: all(np.allclose(p.viewRange()[0], [0.0, 10.0], atol=0.01)
                                for p in plots.time_plots.values()), timeout=30000)
    for spec in plots.spectrum_plots.values():
        low, high = spec.viewRange()[1]  # log10 of the amplitude
        decades = [d for d in range(-12, 12) if low <= d <= high]
        assert len(decades) >= 2, (low, high)  # labelled decades, not ticks 2 to 9 alone
    plots.time_plots["drive"].setXRange(3.0, 4.0, padding=0)
    plots.configure({"drive": "V", "tip_velocity": "m/s"}, 1000.0)  # the same channels again
    assert np.allclose(plots.time_plots["drive"].viewRange()[0], [0.0, 10.0])
