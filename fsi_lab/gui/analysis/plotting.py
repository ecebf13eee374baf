"""Plotting primitives of the analysis figures: colours, decimated curves, points, ranges."""

from __future__ import annotations

import html
import re
from typing import Sequence

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtGui import QFontMetricsF

from fsi_lab.gui.decimate import min_max_decimate
from fsi_lab.gui.figure import MIN_PLOT_WIDTH

#: Colours of the components (component k in ``COLOURS[k % len(COLOURS)]``).
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
           "#17becf")
#: Components drawn at most in one figure.
MAX_COMPONENTS_DRAWN = 6

#: Curves are drawn decimated to two points (the min and max of a bin: no peak is lost) per
#: pixel of the figure's width, within these bounds. The run file keeps every sample.
DRAW_POINTS = 4000
MIN_DRAW_POINTS = 1200


#: The widest line of an x axis label, in pixels: the axis of a plot at its smallest (a
#: figure's plots keep MIN_PLOT_WIDTH) less the y axis beside it.
LABEL_LINE_WIDTH = MIN_PLOT_WIDTH - 60
#: Where a label may break: at a space, except around "=" and "/" (a formula stays whole)
#: and before the last word (no word alone on the last line, as the "m" of "x = 0.08 m").
_BREAK = re.compile(r"(?<![=/]) (?![=/]|\S+$)")


def set_bottom_label(plot: pg.PlotItem, text: str, units: str | None = None) -> None:
    """Label the x axis of ``plot`` with ``text`` (and ``units``, which pyqtgraph appends
    with an SI prefix), broken into lines of at most :data:`LABEL_LINE_WIDTH` where it can
    be: plots side by side share a row's width, and a label on one line as long as
    "displacement amplitude at the measuring point" runs into its neighbours'. A text with
    markup (pyqtgraph's labels are HTML) is set as it is."""
    if "<" in text:
        plot.setLabel("bottom", text, units=units)
        return
    metrics = QFontMetricsF(plot.getAxis("bottom").label.font())
    suffix = " (mm)" if units else ""  # as wide as a prefixed unit
    lines: list[list[str]] = []
    for chunk in _BREAK.split(text):
        if lines and metrics.horizontalAdvance(" ".join([*lines[-1], chunk])) \
                <= LABEL_LINE_WIDTH:
            lines[-1].append(chunk)
        else:
            lines.append([chunk])
    if lines and len(lines[-1]) > 1 \
            and metrics.horizontalAdvance(" ".join(lines[-1]) + suffix) > LABEL_LINE_WIDTH:
        lines.append([lines[-1].pop()])
    plot.setLabel("bottom", "<br>".join(html.escape(" ".join(line)) for line in lines),
                  units=units)


def display_points(plot: pg.PlotItem) -> int:
    """How many points a curve of ``plot`` needs: two per pixel of the widest view showing it."""
    scene = plot.scene()
    views = scene.views() if scene is not None else []
    width = max([v.width() for v in views] + [plot.width()])
    return int(min(DRAW_POINTS, max(MIN_DRAW_POINTS, 2 * width)))


def draw_line(plot: pg.PlotItem, x, y, colour: str, name: str | None = None,
              width: float = 1.2, style=Qt.PenStyle.SolidLine) -> pg.PlotDataItem:
    """A curve of ``y`` against ``x`` in ``plot``, decimated to :func:`display_points` (NaN
    gaps are kept as gaps)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    points = display_points(plot)
    if y.size > points and np.all(np.isfinite(y)):
        x, y = min_max_decimate(x, y, points)
    elif y.size > points:
        step = int(np.ceil(y.size / points))
        x, y = x[::step], y[::step]
    return plot.plot(x, y, pen=pg.mkPen(colour, width=width, style=style), name=name,
                     connect="finite", skipFiniteCheck=False)


def draw_points(plot: pg.PlotItem, x, y, colour: str, name: str | None = None, size: int = 5
                ) -> pg.PlotDataItem:
    """Round markers of ``y`` against ``x`` in ``plot``, every point drawn."""
    return plot.plot(np.asarray(x, dtype=float), np.asarray(y, dtype=float), pen=None,
                     symbol="o", symbolSize=size, symbolBrush=colour, symbolPen=None, name=name)


def robust_range(plot: pg.PlotItem, values: Sequence[np.ndarray], axis: str = "y",
                 low: float = 2.0, high: float = 98.0) -> None:
    """Scale one axis to the bulk of the data (outliers of noisy record ends stay reachable by
    zooming out: the view's "View all")."""
    data = np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in values] or [[]])
    data = data[np.isfinite(data)]
    if data.size < 5:
        return
    lo, hi = np.percentile(data, [low, high])
    if hi <= lo:
        return
    margin = 0.15 * (hi - lo)
    if axis == "y":
        plot.setYRange(lo - margin, hi + margin, padding=0)
    else:
        plot.setXRange(max(lo - margin, 0.0) if lo >= 0 else lo - margin, hi + margin, padding=0)


def plain_numbers(plot: pg.PlotItem, side: str = "left") -> None:
    """Tick labels of one axis as the values are, without an SI prefix on its unit or an
    "(x0.001)" scale: for units that take no prefix (%, kg/(m s))."""
    axis = plot.getAxis(side)
    axis.setLabel(axis.labelText, units=axis.labelUnits or None, siPrefixEnableRanges=())
    axis.updateAutoSIPrefix()


def active_span(t: np.ndarray, envelope: np.ndarray, fraction: float = 0.01
                ) -> tuple[float, float] | None:
    """The time span where ``envelope`` exceeds ``fraction`` of its peak."""
    env = np.asarray(envelope, dtype=float)
    good = np.isfinite(env)
    if not good.any():
        return None
    above = np.flatnonzero(good & (env > fraction * np.nanmax(env)))
    if above.size < 2:
        return None
    t0, t1 = float(t[above[0]]), float(t[above[-1]])
    pad = 0.05 * (t1 - t0)
    return t0 - pad, t1 + pad


def weighted_percentiles(values, weights, percents: Sequence[float]) -> np.ndarray | None:
    """Percentiles of ``values`` where each counts with its weight (NaN and non-positive
    weights left out); None without any value to count."""
    v, w = np.ravel(np.asarray(values, dtype=float)), np.ravel(np.asarray(weights, dtype=float))
    keep = np.isfinite(v) & np.isfinite(w) & (w > 0)
    if not keep.any():
        return None
    v, w = v[keep], w[keep]
    order = np.argsort(v)
    v, w = v[order], w[order]
    cumulative = (np.cumsum(w) - 0.5 * w) / w.sum()
    return np.interp(np.asarray(percents, dtype=float) / 100.0, cumulative, v)


def amplitude_weighted_range(plot: pg.PlotItem, series, extra=(), low: float = 5.0,
                             high: float = 95.0) -> tuple[float, float] | None:
    """Set the y range of ``plot`` to the points that carry the curve, not the noise floor.

    ``series``: ``(amplitude, y)`` per component. A quantity derived from a decaying envelope
    scatters roughly as 1/amplitude, so each component's points count with their amplitude:
    the ``low``-``high`` amplitude-weighted percentiles of each component, together with the
    ``extra`` values (a fitted curve, which is always shown), make the range. Points outside it
    stay reachable by zooming out ("View all"). Returns the range, None when nothing is set."""
    bounds = [np.ravel(np.asarray(e, dtype=float)) for e in extra]
    for amplitude, y in series:
        found = weighted_percentiles(y, np.abs(np.asarray(amplitude, dtype=float)),
                                     (low, high))
        if found is not None:
            bounds.append(found)
    data = np.concatenate(bounds or [np.zeros(0)])
    data = data[np.isfinite(data)]
    if data.size == 0:
        return None
    lo, hi = float(data.min()), float(data.max())
    if hi <= lo:
        hi, lo = hi + max(abs(hi) * 0.05, 1e-12), lo - max(abs(lo) * 0.05, 1e-12)
    margin = 0.15 * (hi - lo)
    lo, hi = lo - margin, hi + margin
    plot.setYRange(lo, hi, padding=0)
    return lo, hi
