"""Live plots: every channel in a rolling time window, and its amplitude spectrum.

Blocks from the run are copied into one fixed-size ring buffer per channel (the rolling window);
a timer redraws at most ``fps`` times a second, and only when new data came in. What is drawn is
decimated (min and max per pixel-wide bin, so no peak disappears) to a fixed number of points, and
the spectrum is computed over a fixed number of the latest samples: a frame costs the same at the
first second of a run and at the last hour. Storage is the runner's business: it writes every
sample to the run file, whatever is shown here.
"""

from __future__ import annotations

import time
from typing import Mapping

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QEvent, QTimer
from PySide6.QtWidgets import QLabel, QVBoxLayout, QWidget

from fsi_lab.events import DataBlock
from fsi_lab.gui.decimate import min_max_decimate
from fsi_lab.gui.figure import Figure, scrolled

COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
           "#17becf")
#: Smallest plot of a channel (axes included); the last row also carries the time axis.
MIN_ROW_PLOT = (180, 110)
MIN_LAST_ROW_HEIGHT = 150
#: Fewest decades a spectrum's amplitude axis spans.
MIN_DECADES = 2.0
#: The spectra's amplitude axis before any data (log10 of the unit): whole, labelled decades.
EMPTY_DECADES = (-3.0, 0.0)


class RingBuffer:
    """The latest ``capacity`` samples of one channel."""

    def __init__(self, capacity: int) -> None:
        self.capacity = max(1, int(capacity))
        self._data = np.zeros(self.capacity)
        self.total = 0  # samples ever written

    def extend(self, values: np.ndarray) -> None:
        values = np.asarray(values, dtype=float).ravel()
        n = values.size
        if n == 0:
            return
        if n >= self.capacity:
            self.total += n
            start = (self.total - self.capacity) % self.capacity
            self._data[:] = np.roll(values[-self.capacity:], start)
            return
        pos = self.total % self.capacity
        first = min(n, self.capacity - pos)
        self._data[pos:pos + first] = values[:first]
        if first < n:
            self._data[:n - first] = values[first:]
        self.total += n

    @property
    def count(self) -> int:
        return min(self.total, self.capacity)

    def latest(self, n: int | None = None) -> np.ndarray:
        """The last ``n`` samples (all held when None), oldest first."""
        count = self.count if n is None else min(int(n), self.count)
        if count == 0:
            return np.zeros(0)
        end = self.total % self.capacity
        if self.total >= self.capacity and end == 0:
            end = self.capacity
        start = end - count
        if start >= 0:
            return self._data[start:end].copy()
        return np.concatenate([self._data[start:], self._data[:end]])


class LivePlots(QWidget):
    """Rolling time traces (left) and spectra (right), one row per channel.

    Call :meth:`configure` before a run (channel names and units), then feed
    :meth:`on_block` with the run's :class:`~fsi_lab.events.DataBlock` events.
    """

    def __init__(self, window_s: float = 10.0, fps: float = 30.0, max_points: int = 2000,
                 spectrum_samples: int = 16384, spectrum_every: int = 3,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.window_s = window_s
        self.max_points = max_points
        self.spectrum_samples = spectrum_samples
        self.spectrum_every = spectrum_every
        self.units: dict[str, str] = {}
        self.buffers: dict[str, RingBuffer] = {}
        self.curves: dict[str, pg.PlotDataItem] = {}
        self.spectra: dict[str, pg.PlotDataItem] = {}
        self.time_plots: dict[str, pg.PlotItem] = {}
        self.spectrum_plots: dict[str, pg.PlotItem] = {}
        self._y_ranges: dict[str, tuple[float, float] | None] = {}
        self._s_ranges: dict[str, tuple[float, float] | None] = {}
        self.sample_rate = 0.0
        self.t_end = 0.0
        self.t_first = None
        self.frames = 0
        self.blocks = 0
        self.last_frame_s = 0.0
        self._dirty = False
        self._frame_counter = 0
        self.graphics = Figure(min_plot=MIN_ROW_PLOT)
        self.status = QLabel("No run yet: the channels appear here while a run acquires.")
        self.status.setWordWrap(True)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.status)
        # many channels scroll rather than squeeze
        layout.addWidget(scrolled(self.graphics), 1)
        self.paints = 0
        self.graphics.viewport().installEventFilter(self)
        self.timer = QTimer(self)
        self.timer.setInterval(max(1, int(1000 / fps)))
        self.timer.timeout.connect(self.refresh)
        self.timer.start()

    def eventFilter(self, watched, event) -> bool:
        if event.type() == QEvent.Type.Paint:
            self.paints += 1
        return False

    # ------------------------------------------------------------------ setup
    def configure(self, units: Mapping[str, str], sample_rate: float) -> None:
        """Empty the plots and prepare one row per channel (``units``: name -> unit).

        The plot items are kept when the channels and the rate are those already shown
        (building them is the costly part), so configuring again before a run is cheap.
        """
        same = dict(units) == self.units and float(sample_rate) == self.sample_rate \
            and bool(self.curves)
        self.units = dict(units)
        self.sample_rate = float(sample_rate)
        capacity = int(round(self.window_s * self.sample_rate)) if sample_rate > 0 else 1
        self.buffers = {name: RingBuffer(capacity) for name in self.units}
        self.t_end = 0.0
        self.t_first = None
        self.blocks = 0
        self._dirty = False
        if same:
            for name in self.units:
                self.curves[name].setData([], [])
                self.spectra[name].setData([], [])
                self._y_ranges[name] = None
                self._s_ranges[name] = None
            self._empty_ranges()
            return
        self.graphics.clear()
        self.curves.clear()
        self.spectra.clear()
        self.time_plots.clear()
        self.spectrum_plots.clear()
        self.t_end = 0.0
        self.t_first = None
        self.blocks = 0
        self._dirty = False
        first: pg.PlotItem | None = None
        last_row = len(self.units) - 1
        for row, (name, unit) in enumerate(self.units.items()):
            colour = COLOURS[row % len(COLOURS)]
            plot = self.graphics.addPlot(row=row, col=0)
            spec = self.graphics.addPlot(row=row, col=1)
            for item in (plot, spec):
                # Axes are redrawn only when their range changes, and the layout never moves:
                # fixed axis widths, y ranges that change only when the data leaves them.
                item.setMenuEnabled(False)
                item.hideButtons()
                item.getAxis("left").setWidth(64)
                item.enableAutoRange(False, False)
                if row != last_row:
                    item.hideAxis("bottom")
            plot.setLabel("left", name, units=None if not unit else unit)
            spec.setLabel("left", f"|{name}|", units=unit or None)
            spec.getAxis("left").enableAutoSIPrefix(False)  # decades read as they are
            spec.setLogMode(x=True, y=True)  # beam modes sit at a few hertz to a few hundred
            spec.setXRange(np.log10(self.sample_rate / self.spectrum_samples),
                           np.log10(self.sample_rate / 2), padding=0)
            if row == last_row:
                plot.setLabel("bottom", "time", units="s")
                spec.setLabel("bottom", "frequency", units="Hz")
                for item in (plot, spec):
                    item.setMinimumHeight(MIN_LAST_ROW_HEIGHT)
            if first is None:
                first = plot
            else:
                plot.setXLink(first)
            self.curves[name] = plot.plot(pen=pg.mkPen(colour, width=1), antialias=False)
            self.spectra[name] = spec.plot(pen=pg.mkPen(colour, width=1), antialias=False)
            self.time_plots[name] = plot
            self.spectrum_plots[name] = spec
            self._y_ranges[name] = None
            self._s_ranges[name] = None
        self.graphics.ci.layout.setColumnStretchFactor(0, 3)
        self.graphics.ci.layout.setColumnStretchFactor(1, 2)
        self._empty_ranges()
        self.graphics.fit_minimum()
        self.status.setText(
            f"{len(self.units)} channels at {self.sample_rate:g} Hz; window {self.window_s:g} s "
            "(display decimated; the run file keeps every sample)")

    def _empty_ranges(self) -> None:
        """Before any data: the time axes span the rolling window the header names, and the
        spectra a few labelled decades."""
        if self.time_plots:
            next(iter(self.time_plots.values())).setXRange(0.0, self.window_s, padding=0)
        for spec in self.spectrum_plots.values():
            spec.setYRange(*EMPTY_DECADES, padding=0)

    # ------------------------------------------------------------------ data
    def on_block(self, block: DataBlock) -> None:
        """Append one block (UI thread; called through the event forwarder)."""
        names = [n for n in block.data if n in self.buffers]
        if (not self.buffers or len(names) < len(block.data)
                or block.sample_rate != self.sample_rate):
            # a channel we were not told about, or the digitiser rounded the rate
            units = {**self.units, **{n: self.units.get(n, "") for n in block.data}}
            self.configure(units, block.sample_rate)
        n = 0
        for name, values in block.data.items():
            self.buffers[name].extend(values)
            n = len(values)
        if self.t_first is None:
            self.t_first = block.t0
        self.t_end = block.t0 + n / block.sample_rate
        self.blocks += 1
        self._dirty = True

    def samples_shown(self, name: str) -> int:
        """Points of the drawn curve of channel ``name`` (for tests)."""
        x, _ = self.curves[name].getData()
        return 0 if x is None else len(x)

    # ------------------------------------------------------------------ drawing
    def refresh(self, force: bool = False) -> None:
        """Redraw if new data came in since the last frame."""
        if not (self._dirty or force) or not self.buffers:
            return
        started = time.perf_counter()
        self._dirty = False
        rate = self.sample_rate
        with_spectrum = force or self._frame_counter % self.spectrum_every == 0
        self._frame_counter += 1
        for name, buffer in self.buffers.items():
            y = buffer.latest()
            if y.size == 0:
                continue
            t = self.t_end - (y.size - np.arange(y.size)) / rate
            td, yd = min_max_decimate(t, y, self.max_points)
            self.curves[name].setData(td, yd, skipFiniteCheck=True)
            self._y_ranges[name] = _sticky(self.time_plots[name], self._y_ranges[name],
                                           float(yd.min()), float(yd.max()))
            if with_spectrum and y.size >= 16:
                self._spectrum(name, y[-self.spectrum_samples:], rate)
        lo = max(self.t_first or 0.0, self.t_end - self.window_s)
        first = next(iter(self.time_plots.values()))
        first.setXRange(lo, max(self.t_end, lo + 1e-3), padding=0)  # the others are linked
        self.frames += 1
        self.last_frame_s = time.perf_counter() - started

    def _spectrum(self, name: str, y: np.ndarray, rate: float) -> None:
        window = np.hanning(y.size)
        amplitude = 2.0 * np.abs(np.fft.rfft((y - y.mean()) * window)) / window.sum()
        freqs = np.fft.rfftfreq(y.size, 1.0 / rate)
        amplitude[0] = np.nan
        keep = slice(1, None)
        fd, ad = freqs[keep], np.maximum(amplitude[keep], 1e-300)
        if fd.size > self.max_points:  # keep the peaks: max over bins
            bins = self.max_points
            per = fd.size // bins
            used = per * bins
            ad = ad[:used].reshape(bins, per).max(axis=1)
            fd = fd[:used].reshape(bins, per)[:, 0]
        self.spectra[name].setData(fd, ad, skipFiniteCheck=True)
        logs = np.log10(ad[ad > 1e-300])
        if logs.size:
            self._s_ranges[name] = _sticky(self.spectrum_plots[name], self._s_ranges[name],
                                           float(logs.min()), float(logs.max()), log=True)


def _sticky(plot: pg.PlotItem, current: tuple[float, float] | None, lo: float, hi: float,
            log: bool = False) -> tuple[float, float]:
    """Set the y range only when the data leaves it or fills less than a third of it."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return current or (0.0, 1.0)
    if hi <= lo:
        hi = lo + (1.0 if log else max(abs(lo) * 1e-3, 1e-12))
    if log and hi - lo < MIN_DECADES:  # at least a few decades: labelled decades, no clutter
        middle = (hi + lo) / 2
        lo, hi = middle - MIN_DECADES / 2, middle + MIN_DECADES / 2
    if current is not None:
        c_lo, c_hi = current
        inside = c_lo <= lo and hi <= c_hi
        if inside and (hi - lo) >= (c_hi - c_lo) / 3:
            return current
    margin = 0.1 * (hi - lo)
    new = (lo - margin, hi + margin)
    plot.setYRange(*new, padding=0)
    return new
