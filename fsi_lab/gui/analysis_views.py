"""Analysis views: what the analysis chain stored in a run file, drawn as the paper draws it.

Views (each reads ``/analysis/<channel>/<plugin>/`` of the run file; a missing or failed group
is shown as "not computed" or with its failure message, never as an exception):

- HVD components with their envelopes (paper Fig. 6);
- instantaneous frequency against time (HVD and zero crossings);
- backbone: frequency against displacement and velocity amplitude (Figs. 14-16);
- damping ratio against displacement and velocity amplitude (Figs. 19-20);
- the equivalent damping C_q against displacement amplitude with its first-order fit, R^2 and
  95 % intervals of C_i and C_f (Fig. 21);
- the modal model overlaid on the measurement;
- spectra and FRF; a table of the identified values; and every dataset of every plugin
  (third-party ones included) in a browser.

The parameter panel edits the chain's parameters with forms from the plugins' schemas; a change
re-runs the analysis as ``fsi-lab analyze RUN.h5 --set ...`` in a child process (see
:mod:`fsi_lab.gui.analysis_job`; the chain runs in order because later plugins use earlier
results), then the views reload.

Drawing keeps the window responsive: the run file is read on a worker thread
(:func:`fsi_lab.gui.results.load_results`); a view is drawn only when its tab is shown, a step
(a plot, a curve) at a time, by a :class:`Stepper` that gives the event loop back every few
milliseconds and lets each figure be painted once, when it is complete; the parameter forms of
a new run are built after its figures, a form at a time. Curves are decimated for display to
two points (the min and max of a bin) per pixel of the figure's width
(:func:`fsi_lab.gui.decimate.min_max_decimate`); the run file keeps every sample. A figure
takes the space the layout gives it, so that drawing one never resizes (and repaints) the
others.
"""

from __future__ import annotations

import inspect
import time
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QObject, Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QComboBox, QGridLayout, QGroupBox, QHBoxLayout, QHeaderView, QLabel, QPushButton, QScrollArea,
    QSizePolicy, QSplitter, QTabWidget,
    QTableWidget, QTableWidgetItem, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget,
)

from fsi_lab.chain import DEFAULT_CHAIN
from fsi_lab.errors import FsiLabError
from fsi_lab.gui.analysis_job import AnalysisJob
from fsi_lab.gui.forms import ParamForm
from fsi_lab.gui.results import PluginResult, RunResults
from fsi_lab.gui.decimate import min_max_decimate
from fsi_lab.gui.worker import TaskPool
from fsi_lab.profile import ANALYSIS_PARAMS, parse_profile
from fsi_lab.registry import Registry

COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
           "#17becf")
MAX_COMPONENTS_DRAWN = 6

# Names under which the analysis plugins store what each view draws (first found wins).
TIME = ("time", "t", "times")
HVD_COMPONENTS = ("components", "component", "waveforms")
HVD_ENVELOPES = ("envelopes", "envelope", "amplitudes")
HVD_FREQUENCIES = ("frequencies", "frequency", "frequency_hz", "instantaneous_frequency")
HVD_EDGE = ("edge_mask", "edges", "untrusted")
ZC_TIME = ("frequency_times", "times", "time", "t")
ZC_FREQUENCY = ("frequency", "frequency_hz", "frequencies")
DISPLACEMENT_AMPLITUDE = ("displacement_amplitude", "amplitude_displacement", "amplitude",
                          "amplitudes", "amplitude_m")
VELOCITY_AMPLITUDE = ("velocity_amplitude", "amplitude_velocity", "amplitude_m_s")
FREQUENCY = ("frequency_hz", "frequency", "frequencies")
ZETA = ("zeta", "damping_ratio", "damping")
CQ = ("c_q", "cq", "C_q", "equivalent_damping")
CQ_AMPLITUDE = ("displacement_amplitude", "modal_amplitude", "amplitude", "amplitudes")
CQ_FIT = ("c_q_fit", "fit", "fitted")
CQ_BAND_LOW = ("c_q_fit_low", "fit_low", "ci_low", "fit_lower")
CQ_BAND_HIGH = ("c_q_fit_high", "fit_high", "ci_high", "fit_upper")
SPECTRUM_FREQUENCY = ("frequency_hz", "frequency", "frequencies", "freqs")
SPECTRUM_AMPLITUDE = ("amplitude", "spectrum", "magnitude")
SPECTRUM_PEAKS = ("peaks_hz", "peak_frequencies", "peak_frequency_hz", "spectrum_peaks_hz")


# --------------------------------------------------------------------------- data helpers
def rows(array: np.ndarray | None) -> list[np.ndarray]:
    """A 2-D dataset as its rows (components), a 1-D one as a single row."""
    if array is None:
        return []
    array = np.asarray(array)
    if array.ndim == 1:
        return [array]
    if array.ndim == 2:
        if array.shape[0] > array.shape[1]:
            array = array.T
        return list(array)
    return []


def per_component(result: PluginResult | None, names: Sequence[str]) -> list[np.ndarray]:
    """Per-component arrays: a 2-D dataset, a 1-D one, or ``<k>/<name>`` subgroups."""
    if result is None:
        return []
    found = rows(result.get(*names))
    if found:
        return [np.asarray(r, dtype=float) for r in found]
    nested: dict[str, np.ndarray] = {}
    for key, value in result.datasets.items():
        prefix, _, leaf = key.rpartition("/")
        if prefix and leaf in names and prefix not in nested:
            nested[prefix] = value
    return [np.asarray(nested[k], dtype=float).ravel() for k in sorted(nested, key=_natural)]


def finite_pairs(pairs) -> list[tuple[np.ndarray, np.ndarray]]:
    """Matching ``(x, y)`` rows without their NaN padding; empty rows are dropped."""
    out = []
    for x, y in pairs:
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if x.size != y.size:
            continue
        keep = np.isfinite(x) & np.isfinite(y)
        if keep.any():
            out.append((x[keep], y[keep]))
    return out


def _natural(key: str) -> tuple:
    digits = "".join(ch for ch in key if ch.isdigit())
    return (int(digits) if digits else 0, key)


def summary_series(results: RunResults, channel: str, section: str, x: str, y: str
                   ) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(x, y)`` pairs per component from the summary's ``components[i][section]``."""
    series = []
    for component in results.components(channel):
        block = component.get(section)
        if not isinstance(block, dict):
            continue
        xs, ys = block.get(x), block.get(y)
        if isinstance(xs, list) and isinstance(ys, list) and xs and len(xs) == len(ys):
            series.append((np.asarray([np.nan if v is None else v for v in xs], dtype=float),
                           np.asarray([np.nan if v is None else v for v in ys], dtype=float)))
    return finite_pairs(series)


def time_axis(results: RunResults, channel: str, result: PluginResult | None, n: int
              ) -> np.ndarray:
    """Sample times of a dataset of ``n`` samples: its own time dataset, else the channel's
    sample times from where the decomposition started (``start_s`` of hvd)."""
    if result is not None:
        t = result.get(*TIME)
        if t is not None and np.asarray(t).size == n:
            return np.asarray(t, dtype=float)
    data = results.channels.get(channel)
    if data is not None and data.sample_rate > 0:
        return origin(results, channel, result) + np.arange(n) / data.sample_rate
    return np.arange(n, dtype=float)


def origin(results: RunResults, channel: str, result: PluginResult | None = None) -> float:
    """Time (s, on the run's clock) of sample 0 of the analysed components: the channel's t0
    plus the start the decomposition chose (``start_s``), when there is one."""
    data = results.channels.get(channel)
    t0 = float(data.t0) if data is not None else 0.0
    for candidate in (result, results.result(channel, "hvd")):
        if candidate is not None:
            start = candidate.scalar("start_s")
            if isinstance(start, (int, float)):
                return t0 + float(start)
    return t0


def _format_ci(value: Any) -> str:
    if isinstance(value, (list, tuple)) and len(value) == 2:
        return f"[{value[0]:.4g}, {value[1]:.4g}]"
    return "" if value is None else str(value)


def chain_of(results: RunResults, registry: Registry) -> tuple[dict[str, Any], dict[str, dict]]:
    """The run's ``[analysis]`` values (chain, channels, reference) and the parameters its
    plugins last ran with."""
    params: dict[str, dict] = {}
    analysis: dict[str, Any] = {"chain": [], "channels": [], "reference": None}
    try:
        profile = parse_profile(results.profile_text, f"{results.path}:/profile", registry,
                                sections=("analysis", "specimen"))
        analysis = dict(profile.analysis)
        params = {k: dict(v) for k, v in profile.analysis_params.items()}
    except FsiLabError:
        pass
    chain = list(analysis["chain"])
    if not results.profile_text.strip() and not chain:
        chain = [name for name in DEFAULT_CHAIN if name in registry.descriptors["analysis"]]
    for groups in results.analysis.values():
        for plugin, result in groups.items():
            if plugin not in chain and plugin in registry.descriptors["analysis"]:
                chain.append(plugin)
            if result.params:
                params.setdefault(plugin, {}).update(result.params)
    analysis["chain"] = chain
    return analysis, params


# --------------------------------------------------------------------------- views
class View(QWidget):
    """One figure of the analysis; ``filled`` tells whether it shows data."""

    title = ""
    plugins: tuple[str, ...] = ()
    #: Plot cells (row, column) the view usually draws, built ahead of time by :meth:`prebuild`.
    cells: tuple[tuple[int, int], ...] = ((0, 0),)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.filled = False
        self.note = QLabel()
        self.note.setWordWrap(True)
        self.note.setObjectName("view-note")
        # Two lines are reserved whatever the note says, so that a new note does not resize
        # the figures below it (which would repaint every figure of the Overview).
        self.note.setMinimumHeight(2 * self.note.fontMetrics().lineSpacing() + 2)
        self.graphics = pg.GraphicsLayoutWidget()
        # The figure takes the space it is given, whatever its plots hint: a drawing never
        # changes the layout around it (a new layout would repaint every figure around).
        self.graphics.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        # Plot items are costly to build: they are kept between drawings and emptied.
        self._plots: dict[tuple[int, int], pg.PlotItem] = {}
        self._labels: dict[tuple[int, int], pg.LabelItem] = {}
        self._used: set[tuple[int, int]] = set()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.note)
        layout.addWidget(self.graphics, 1)

    def clear(self) -> None:
        for plot in self._plots.values():
            plot.clear()
            if plot.legend is not None:
                plot.legend.clear()
            plot.setTitle(None)
            plot.setLogMode(False, False)
            plot.enableAutoRange()
            plot.setXLink(None)
        for label in self._labels.values():
            label.setText("")
        self._used.clear()
        self.filled = False

    def prebuild(self) -> None:
        """Build the usual plot items now (idle time), hidden until a drawing uses them."""
        for row, col in self.cells:
            self.add_plot(row, col, "", "")
        self._used.clear()
        self._prune()

    def _prune(self) -> None:
        """Hide the plots and labels the last drawing did not use (kept for the next)."""
        for store in (self._plots, self._labels):
            for key, item in store.items():
                item.setVisible(key in self._used)

    def show_results(self, results: RunResults, channel: str) -> None:
        """Draw the view at once."""
        for _ in self.drawing(results, channel):
            pass

    def drawing(self, results: RunResults, channel: str) -> Iterator[None]:
        """Draw the view step by step: each ``next()`` does a little of the work (a curve, a
        plot), so that a :class:`Stepper` can spread the drawing over turns of the event loop.
        The figure is painted once, when the drawing is complete; ``filled`` is set then."""
        self.clear()
        self.graphics.setUpdatesEnabled(False)
        try:
            try:
                outcome = self.draw(results, channel)
                if inspect.isgenerator(outcome):
                    outcome = yield from outcome
                self.filled = bool(outcome)
            except Exception as exc:  # noqa: BLE001 - an odd dataset must not take the window down
                self.clear()
                self._prune()
                self._set_note(f"cannot draw this view: {type(exc).__name__}: {exc}",
                               "color: #b00020;")
                return
            if not self.filled:
                self.clear()
            self._prune()
            if not self.filled:
                self._set_note(self.missing(results, channel), "color: #666;")
        finally:
            self.graphics.setUpdatesEnabled(True)

    def missing(self, results: RunResults, channel: str) -> str:
        """Why nothing is drawn: failed with its message, or not computed."""
        for plugin in self.plugins:
            result = results.result(channel, plugin)
            if result is not None and not result.ok:
                return f"{plugin} failed on {channel}: {result.error}"
        names = " / ".join(self.plugins)
        return f"not computed: this run has no {names} results for channel {channel}"

    def draw(self, results: RunResults, channel: str) -> bool | Iterator[None]:  # pragma: no cover
        """Draw the view; True if it shows data. A generator (``yield`` between steps,
        ``return`` the verdict) can be drawn a step at a time."""
        raise NotImplementedError

    def add_plot(self, row: int, col: int, left: str, bottom: str, left_units: str | None = None,
                 bottom_units: str | None = None, colspan: int = 1) -> pg.PlotItem:
        key = (row, col)
        plot = self._plots.get(key)
        if plot is None:
            plot = self._plots[key] = self.graphics.addPlot(row=row, col=col, colspan=colspan)
            plot.addLegend(offset=(-10, 10))
        plot.setVisible(True)
        self._used.add(key)
        plot.setLabel("left", left, units=left_units)
        plot.setLabel("bottom", bottom, units=bottom_units)
        return plot

    def add_label(self, row: int, col: int, text: str) -> pg.LabelItem:
        key = (row, col)
        label = self._labels.get(key)
        if label is None:
            label = self._labels[key] = pg.LabelItem(justify="left", size="10pt")
            self.graphics.addItem(label, row=row, col=col)
        label.setVisible(True)
        self._used.add(key)
        label.setText(text, size="10pt")
        return label

    def set_note(self, text: str) -> None:
        self._set_note(text, "")

    def _set_note(self, text: str, style: str) -> None:
        # unchanged text and style are not set again: each would ask for a new layout
        if self.note.text() != text:
            self.note.setText(text)
        if self.note.styleSheet() != style:
            self.note.setStyleSheet(style)


#: Curves are drawn decimated to two points (the min and max of a bin: no peak is lost) per
#: pixel of the figure's width, within these bounds. The run file keeps every sample.
DRAW_POINTS = 4000
MIN_DRAW_POINTS = 1200


def display_points(plot: pg.PlotItem) -> int:
    """How many points a curve of ``plot`` needs: two per pixel of the widest view showing it."""
    scene = plot.scene()
    views = scene.views() if scene is not None else []
    width = max([v.width() for v in views] + [plot.width()])
    return int(min(DRAW_POINTS, max(MIN_DRAW_POINTS, 2 * width)))


def _line(plot: pg.PlotItem, x, y, colour: str, name: str | None = None, width: float = 1.2,
          style=Qt.PenStyle.SolidLine) -> pg.PlotDataItem:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    points = display_points(plot)
    if y.size > points and np.all(np.isfinite(y)):
        x, y = min_max_decimate(x, y, points)
    elif y.size > points:
        step = int(np.ceil(y.size / points))
        x, y = x[::step], y[::step]
    return plot.plot(x, y, pen=pg.mkPen(colour, width=width, style=style), name=name,
                     connect="finite", skipFiniteCheck=False)


def _points(plot: pg.PlotItem, x, y, colour: str, name: str | None = None, size: int = 5
            ) -> pg.PlotDataItem:
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


class HVDView(View):
    title = "HVD components"
    plugins = ("hvd",)
    cells = ((0, 0), (1, 0), (2, 0))

    def __init__(self, max_components: int = MAX_COMPONENTS_DRAWN,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.max_components = max_components

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        hvd = results.result(channel, "hvd")
        if hvd is None or not hvd.ok:
            return False
        components = per_component(hvd, HVD_COMPONENTS)
        envelopes = per_component(hvd, HVD_ENVELOPES)
        if not components and not envelopes:
            return False
        n = (components or envelopes)[0].size
        t = time_axis(results, channel, hvd, n)
        unit = results.channels[channel].unit if channel in results.channels else ""
        top = self.add_plot(0, 0, channel, "time", unit or None, "s")
        yield
        residual = hvd.get("residual")
        if components and residual is not None and np.asarray(residual).size == n:
            record = np.sum(components, axis=0) + np.asarray(residual, dtype=float)
            relative = hvd.scalar("relative_to")
            _line(top, t, record, "#9e9e9e",
                  f"decomposed record (relative to {relative})" if isinstance(relative, str)
                  and not relative.startswith("none") else "decomposed record", 1.0)
            yield
        else:
            measured = results.channels.get(channel)
            if measured is not None and measured.data.size == n:
                _line(top, t, measured.data, "#9e9e9e", "measured", 1.0)
                yield
        if components:
            _line(top, t, np.sum(components, axis=0), "#000000", "sum of components", 1.0,
                  Qt.PenStyle.DashLine)
            yield
        count = min(max(len(components), len(envelopes)), self.max_components)
        for k in range(count):
            colour = COLOURS[k % len(COLOURS)]
            plot = self.add_plot(k + 1, 0, f"component {k}", "time", unit or None, "s")
            yield
            plot.setXLink(top)
            if k < len(components):
                _line(plot, t, components[k], colour, f"component {k}", 1.0)
                yield
            if k < len(envelopes):
                _line(plot, t, envelopes[k], "#000000", "envelope", 1.4)
                yield
                _line(plot, t, -envelopes[k], "#000000", None, 1.4)
                yield
        if envelopes:
            span = active_span(t, envelopes[0])
            if span is not None:
                top.setXRange(*span, padding=0)
        cutoffs = hvd.get("cutoffs", "cutoff")
        extra = f"; cut-offs {', '.join(f'{c:.3g}' for c in np.ravel(cutoffs))} Hz" \
            if cutoffs is not None else ""
        self.set_note(f"HVD of {channel}: {count} of {max(len(components), len(envelopes))} "
                      f"component(s), by decreasing amplitude{extra}")
        return True


class FrequencyView(View):
    title = "Instantaneous frequency"
    plugins = ("hvd", "instantaneous")

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        plot = self.add_plot(0, 0, "frequency", "time", "Hz", "s")
        yield
        drawn = False
        hvd = results.result(channel, "hvd")
        shown: list[np.ndarray] = []
        if hvd is not None and hvd.ok:
            freqs = per_component(hvd, HVD_FREQUENCIES)
            edges = per_component(hvd, HVD_EDGE)
            envelopes = per_component(hvd, HVD_ENVELOPES)
            for k, f in enumerate(freqs[:MAX_COMPONENTS_DRAWN]):
                f = np.array(f, dtype=float)
                if k < len(edges) and edges[k].size == f.size:
                    f[np.asarray(edges[k], dtype=bool)] = np.nan
                t = time_axis(results, channel, hvd, f.size)
                if k < len(envelopes) and envelopes[k].size == f.size:
                    weak = envelopes[k] < 0.01 * np.nanmax(envelopes[k])
                    f[weak] = np.nan  # no frequency where the component has died out
                _line(plot, t, f, COLOURS[k % len(COLOURS)], f"HVD component {k}", 1.4)
                yield
                shown.append(f)
                if k == 0 and k < len(envelopes) and envelopes[0].size == t.size:
                    span = active_span(t, envelopes[0])
                    if span is not None:
                        plot.setXRange(*span, padding=0)
                drawn = True
        inst = results.result(channel, "instantaneous")
        if inst is not None and inst.ok:
            times = per_component(inst, ZC_TIME)
            freqs = per_component(inst, ZC_FREQUENCY)
            shift = origin(results, channel, inst)
            for k, (t, f) in enumerate(finite_pairs(zip(times, freqs))):
                _points(plot, t + shift, f, COLOURS[k % len(COLOURS)],
                        f"zero crossings, component {k}", 4)
                yield
                shown.append(f)
                drawn = True
        if drawn:
            robust_range(plot, shown)
            self.set_note(f"instantaneous frequency of {channel}; record ends HVD does not "
                          "trust are left out")
        return drawn


class _AmplitudeView(View):
    """Two plots of a quantity against displacement and velocity amplitude."""

    y_names: Sequence[str] = ()
    velocity_y_names: Sequence[str] = ()
    summary_velocity_section = ""
    y_label = ""
    y_units: str | None = None

    def __init__(self, compact: bool = False, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.compact = compact
        self.cells = ((0, 0),) if compact else ((0, 0), (0, 1))
    summary_section = ""
    summary_y = ""

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        result = results.result(channel, self.plugins[0])
        ok = result is not None and result.ok
        y = per_component(result, self.y_names) if ok else []
        y_v = per_component(result, self.velocity_y_names or self.y_names) if ok else []
        disp = per_component(result, DISPLACEMENT_AMPLITUDE) if y else []
        vel = per_component(result, VELOCITY_AMPLITUDE) if y_v else []
        pairs_d = finite_pairs(zip(disp, y))
        pairs_v = finite_pairs(zip(vel, y_v))
        if not pairs_d and ok:
            pairs_d = summary_series(results, channel, self.summary_section, "amplitude",
                                     self.summary_y)
        if not pairs_v and ok and self.summary_velocity_section:
            pairs_v = summary_series(results, channel, self.summary_velocity_section,
                                     "amplitude", self.summary_y)
        if not pairs_d and not pairs_v:
            return False
        left = self.add_plot(0, 0, self.y_label, "displacement amplitude", self.y_units, "m")
        yield
        for k, (a, b) in enumerate(pairs_d[:MAX_COMPONENTS_DRAWN]):
            self._series(left, a, b, k)
            yield
        robust_range(left, [b for _, b in pairs_d])
        right = None
        if not self.compact:
            right = self.add_plot(0, 1, self.y_label, "velocity amplitude", self.y_units, "m/s")
            yield
            for k, (a, b) in enumerate(pairs_v[:MAX_COMPONENTS_DRAWN]):
                self._series(right, a, b, k)
                yield
            robust_range(right, [b for _, b in pairs_v])
            if not pairs_v:
                right.setTitle("velocity amplitude: not computed")
        yield from self.overlay_model(results, channel, left, right)
        self.set_note(f"{self.title} of {channel}, {len(pairs_d or pairs_v)} component(s)")
        return True

    def _series(self, plot: pg.PlotItem, a: np.ndarray, b: np.ndarray, k: int) -> None:
        colour = COLOURS[k % len(COLOURS)]
        if a.size > 400:
            _line(plot, a, b, colour, f"component {k}", 1.4)
        else:
            _points(plot, a, b, colour, f"component {k}", 5)

    def overlay_model(self, results, channel, left, right) -> Iterator[None]:
        model = results.result(channel, "modal-model")
        if model is None or not model.ok:
            return
        y = per_component(model, self.y_names)
        for plot, names in ((left, DISPLACEMENT_AMPLITUDE), (right, VELOCITY_AMPLITUDE)):
            if plot is None:
                continue
            for k, (a, b) in enumerate(finite_pairs(zip(per_component(model, names), y))):
                order = np.argsort(a)
                _line(plot, a[order], b[order], "#000000", "modal model" if k == 0 else None,
                      1.6, Qt.PenStyle.DashLine)
                yield


class BackboneView(_AmplitudeView):
    title = "Backbone"
    plugins = ("backbone",)
    y_names = FREQUENCY
    velocity_y_names = ("velocity_frequency",) + FREQUENCY
    summary_velocity_section = "backbone_velocity"
    y_label = "frequency"
    y_units = "Hz"
    summary_section = "backbone"
    summary_y = "frequency_hz"


class DampingView(_AmplitudeView):
    title = "Damping"
    plugins = ("damping",)
    y_names = ZETA
    y_label = "damping ratio ζ"
    summary_section = "damping"
    summary_y = "zeta"


class EquivalentDampingView(View):
    title = "Cq fit"
    plugins = ("equivalent-damping",)

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        result = results.result(channel, "equivalent-damping")
        if result is None or not result.ok:
            return False
        components = results.components(channel)
        summaries = {c.get("index"): c.get("equivalent_damping") for c in components
                     if isinstance(c.get("equivalent_damping"), dict)}
        frequencies = {c.get("index"): c.get("frequency_hz") for c in components}
        rows_w = per_component(result, CQ_AMPLITUDE)
        rows_cq = per_component(result, CQ)
        fits = per_component(result, CQ_FIT)
        lows = per_component(result, CQ_BAND_LOW)
        highs = per_component(result, CQ_BAND_HIGH)
        if not rows_cq:
            return False
        plot = self.add_plot(0, 0, "C_q", "displacement amplitude W", "kg/(m s)", "m")
        yield
        lines = []
        for k, (w_row, cq_row) in enumerate(zip(rows_w, rows_cq)):
            pairs = finite_pairs([(w_row, cq_row)])
            if not pairs:
                continue
            w, cq = pairs[0]
            colour = COLOURS[k % len(COLOURS)]
            _points(plot, w, cq, colour, f"C_q, component {k}", 5)
            yield
            order = np.argsort(w)
            fit = fits[k] if k < len(fits) and fits[k].size == w_row.size else None
            summary = summaries.get(k) or {}
            if fit is not None:
                keep = np.isfinite(w_row) & np.isfinite(fit)
                o = np.argsort(w_row[keep])
                _line(plot, w_row[keep][o], fit[keep][o], "#000000",
                      "first-order fit" if k == 0 else None, 1.8)
                yield
            elif summary.get("c_i") is not None and summary.get("c_f") is not None \
                    and frequencies.get(k):
                # Eq. 24 with the identified coefficients at the component's mean frequency
                omega = 2 * np.pi * float(frequencies[k])
                span = np.array([0.0, float(np.max(w))])
                line = summary["c_i"] + 8 * summary["c_f"] * omega * span / (3 * np.pi)
                _line(plot, span, line, colour, f"fit: C_i + 8 C_f ω W / 3π (component {k})",
                      1.8, Qt.PenStyle.DashLine)
                yield
            if k < len(lows) and k < len(highs) and lows[k].size == w_row.size == highs[k].size:
                low = plot.plot(w[order], lows[k][np.isfinite(w_row)][order],
                                pen=pg.mkPen("#00000040"))
                high = plot.plot(w[order], highs[k][np.isfinite(w_row)][order],
                                 pen=pg.mkPen("#00000040"))
                plot.addItem(pg.FillBetweenItem(low, high, brush=pg.mkBrush(0, 0, 0, 30)))
                yield
            values = self._values(result, summary, k)
            if values:
                lines.append(f"component {k} (95 % intervals):<br>&nbsp;&nbsp;{values}")
        if not lines:
            return False
        robust_range(plot, [finite_pairs([(w, c)])[0][1] for w, c in zip(rows_w, rows_cq)
                            if finite_pairs([(w, c)])])
        self.add_label(1, 0, "<br>".join(lines))
        convention = result.scalar("amplitude_convention")
        self.set_note("C_q = 2 ζ (μ + M) 2π f against displacement amplitude W, and its "
                      "first-order fit C_q = C_i + 8 C_f ω W / 3π (Eq. 24)")
        if convention:
            self.note.setToolTip(f"amplitudes: {convention}")
        return True

    @staticmethod
    def _values(result: PluginResult, summary: dict[str, Any], k: int) -> str:
        source = dict(summary)
        for key in ("c_i", "c_f", "r2"):
            if source.get(key) is None:
                source[key] = result.scalar(f"component_{k}_{key}", key)
        if not isinstance(source.get("c_i"), (int, float)):
            return ""
        parts = [f"C<sub>i</sub> = {source['c_i']:.4g} {_format_ci(source.get('c_i_ci95'))} "
                 "kg/(m s)"]
        if isinstance(source.get("c_f"), (int, float)):
            parts.append(f"C<sub>f</sub> = {source['c_f']:.4g} "
                         f"{_format_ci(source.get('c_f_ci95'))} kg/m²")
        if isinstance(source.get("r2"), (int, float)):
            parts.append(f"R² = {source['r2']:.3f}")
        return "<br>&nbsp;&nbsp;".join(parts)


class ModalModelView(View):
    """The modal model (Eq. 20 with the identified C_i and C_f, driven by the measured base
    motion) against the measurement: the decomposed signals, envelopes, backbone and damping."""

    title = "Modal model"
    plugins = ("modal-model",)
    cells = ((0, 0), (1, 0), (2, 0), (2, 1))

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        model = results.result(channel, "modal-model")
        if model is None or not model.ok or not model.datasets:
            return False
        data = results.channels.get(channel)
        rate = float(model.scalar("sample_rate") or (data.sample_rate if data else 1.0))
        t0 = (float(data.t0) if data is not None else 0.0) + float(model.scalar("start_s") or 0.0)
        unit = data.unit if data is not None else None
        drawn = False
        measured = model.get("velocity_measured", "signal_measured")
        simulated = model.get("velocity_model", "signal_model")
        top = None
        if measured is not None and simulated is not None:
            top = self.add_plot(0, 0, channel, "time", unit, "s", colspan=2)
            yield
            _line(top, t0 + np.arange(np.size(measured)) / rate, measured, "#9e9e9e",
                  "measured (decomposed record)", 1.0)
            yield
            _line(top, t0 + np.arange(np.size(simulated)) / rate, simulated, "#000000",
                  "modal model", 1.2, Qt.PenStyle.DashLine)
            yield
            drawn = True
        times = model.get("envelope_time")
        if times is not None:
            env = self.add_plot(1, 0, "envelope", "time", unit, "s", colspan=2)
            yield
            if top is not None:
                env.setXLink(top)
            t_env = (float(data.t0) if data is not None else 0.0) + np.asarray(times, float)
            for k, (m, s_) in enumerate(zip(per_component(model, ("envelope_measured",)),
                                            per_component(model, ("envelope_model",)))):
                colour = COLOURS[k % len(COLOURS)]
                if m.size == t_env.size:
                    _line(env, t_env, m, colour, f"measured {k}", 1.4)
                    yield
                if s_.size == t_env.size:
                    _line(env, t_env, s_, colour, f"model {k}", 1.4, Qt.PenStyle.DashLine)
                    yield
                if k == 0 and m.size == t_env.size:
                    span = active_span(t_env, m)
                    if span is not None:
                        env.setXRange(*span, padding=0)
            drawn = True
        for col, (x_name, y_name, label, units) in enumerate((
                ("backbone_amplitude", "backbone_frequency", "frequency", "Hz"),
                ("damping_amplitude", "damping_zeta", "damping ratio ζ", None))):
            meas = finite_pairs(zip(per_component(model, (f"{x_name}_measured",)),
                                    per_component(model, (f"{y_name}_measured",))))
            sim = finite_pairs(zip(per_component(model, (f"{x_name}_model",)),
                                   per_component(model, (f"{y_name}_model",))))
            if not meas and not sim:
                continue
            plot = self.add_plot(2, col, label, "displacement amplitude", units, "m")
            yield
            for k, (a, b) in enumerate(meas):
                _points(plot, a, b, COLOURS[k % len(COLOURS)], f"measured {k}", 4)
                yield
            for k, (a, b) in enumerate(sim):
                order = np.argsort(a)
                _line(plot, a[order], b[order], COLOURS[k % len(COLOURS)], f"model {k}", 1.6,
                      Qt.PenStyle.DashLine)
                yield
            robust_range(plot, [b for _, b in meas + sim])
            drawn = True
        if drawn:
            c_i, c_f = model.scalar("c_i"), model.scalar("c_f")
            source = model.scalar("c_source")
            coefficients = (f" with C_i = {c_i:.4g} kg/(m s), C_f = {c_f:.4g} kg/m²"
                            if isinstance(c_i, (int, float)) and isinstance(c_f, (int, float))
                            else "")
            self.set_note(f"modal model (Eq. 20){coefficients}"
                          + (f" ({source})" if isinstance(source, str) else "")
                          + f" against the measurement of {channel}; dashed: model")
        return drawn


class SpectrumView(View):
    title = "Spectrum / FRF"
    plugins = ("spectrum", "frf")
    cells = ((0, 0), (1, 0), (2, 0))

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        drawn = False
        spectrum = results.result(channel, "spectrum")
        if spectrum is not None and spectrum.ok:
            freqs = spectrum.get(*SPECTRUM_FREQUENCY)
            amps = spectrum.get(*SPECTRUM_AMPLITUDE)
            if freqs is not None and amps is not None:
                plot = self.add_plot(0, 0, f"|{channel}|", "frequency", None, "Hz")
                yield
                plot.setLogMode(y=True)
                for k, a in enumerate(rows(amps)):
                    if a.size == np.asarray(freqs).size:
                        _line(plot, freqs, np.maximum(np.abs(a), 1e-300), COLOURS[k % len(COLOURS)],
                              "amplitude spectrum" if k == 0 else None, 1.2)
                        yield
                peaks = spectrum.get(*SPECTRUM_PEAKS)
                if peaks is None and results.summary:
                    peaks = results.summary.get("channels", {}).get(channel, {}).get(
                        "spectrum_peaks_hz")
                peak_list = np.ravel(peaks if peaks is not None else [])
                if peak_list.size:
                    plot.setXRange(0, 3 * float(np.max(peak_list[:10])), padding=0)
                for f in peak_list[:10]:
                    plot.addItem(pg.InfiniteLine(float(f), pen=pg.mkPen("#9e9e9e", style=Qt.PenStyle.DotLine),
                                                 label=f"{float(f):.2f} Hz",
                                                 labelOpts={"position": 0.9, "color": "#555"}))
                    yield
                drawn = True
        frf = results.result(channel, "frf")
        if frf is not None and frf.ok:
            freqs = frf.get(*SPECTRUM_FREQUENCY)
            if freqs is not None:
                plot = self.add_plot(1 if drawn else 0, 0, "|H|", "frequency", None, "Hz")
                yield
                plot.setLogMode(y=True)
                for k, name in enumerate(("h1", "h2")):
                    h = frf.get(name, f"{name}_magnitude", name.upper())
                    if h is not None and np.asarray(h).size == np.asarray(freqs).size:
                        _line(plot, freqs, np.maximum(np.abs(h), 1e-300), COLOURS[k], name.upper())
                        yield
                coherence = frf.get("coherence")
                if coherence is not None and np.asarray(coherence).size == np.asarray(freqs).size:
                    coh = self.add_plot(2 if drawn else 1, 0, "coherence", "frequency", None, "Hz")
                    yield
                    coh.setXLink(plot)
                    _line(coh, freqs, coherence, "#2ca02c", "coherence")
                    yield
                drawn = True
        if drawn:
            self.set_note(f"spectra of {channel}")
        return drawn


#: Pause (ms) between two slices of a drawing spread over turns of the event loop, and the
#: longest a slice may go on before it hands the event loop back.
PAUSE_MS = 8
SLICE_S = 0.008


class Stepper(QObject):
    """Runs drawings (generators from :meth:`View.drawing`) a slice at a time, one slice per
    turn of the event loop, so that the window keeps answering while figures are built. A
    drawing that completes ends its slice: its figure is painted before the next one starts."""

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._queue: list[tuple[Iterator[Any], Any]] = []
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(PAUSE_MS)
        self._timer.timeout.connect(self.step)

    @property
    def pending(self) -> bool:
        return bool(self._queue)

    def add(self, drawing: Iterator[Any], owner: Any = None) -> None:
        """Queue ``drawing``; ``owner`` names who may :meth:`cancel` it."""
        self._queue.append((drawing, owner))
        if not self._timer.isActive():
            self._timer.start()

    def pending_for(self, owner: Any) -> bool:
        return any(o is owner for _, o in self._queue)

    def cancel(self, owner: Any = None) -> None:
        """Drop the queued drawings of ``owner`` (all with None)."""
        dropped = [d for d, o in self._queue if owner is None or o is owner]
        self._queue = [(d, o) for d, o in self._queue if not (owner is None or o is owner)]
        if not self._queue:
            self._timer.stop()
        for drawing in dropped:
            drawing.close()  # its figure is painted again (as far as it got)

    def step(self, deadline: float | None = None) -> None:
        """One slice: steps of the first drawing until ``SLICE_S`` is used or it completes."""
        if deadline is None:
            deadline = time.perf_counter() + SLICE_S
        try:
            while self._queue:
                try:
                    next(self._queue[0][0])
                except StopIteration:
                    self._queue.pop(0)
                    break
                except Exception:
                    self._queue.pop(0)  # reported by Qt's handler; the others go on
                    raise
                if time.perf_counter() >= deadline:
                    break
        finally:
            if self._queue and deadline != float("inf"):
                self._timer.start()

    def finish(self) -> None:
        """Complete every drawing at once (tests, screenshots, exports)."""
        self._timer.stop()
        while self._queue:
            self.step(deadline=float("inf"))
        self._timer.stop()


class OverviewView(QWidget):
    """The paper's figures side by side: HVD component with its envelope, instantaneous
    frequency, backbone and the C_q fit."""

    title = "Overview"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.parts = [HVDView(max_components=1), FrequencyView(), BackboneView(compact=True),
                      EquivalentDampingView()]
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        for i, part in enumerate(self.parts):
            grid.addWidget(part, i // 2, i % 2)
        for k in range(2):  # four equal quarters, whatever each figure holds
            grid.setRowStretch(k, 1)
            grid.setColumnStretch(k, 1)
        self.filled = False
        #: Draws the parts; the analysis panel gives its own, shared with its other work.
        self.stepper = Stepper(self)  # owned by the view: it dies with it

    def show_results(self, results: RunResults, channel: str) -> None:
        """Draw the four parts a slice per turn of the event loop, from the next one on, so
        that the window keeps answering (and paints each figure) while they are built."""
        self.stepper.cancel(self)
        self.filled = False
        for part in self.parts:
            self.stepper.add(self._part(part, results, channel), self)

    def _part(self, part: View, results: RunResults, channel: str) -> Iterator[None]:
        yield from part.drawing(results, channel)
        self.filled = any(p.filled for p in self.parts)

    @property
    def pending(self) -> bool:
        return self.stepper.pending_for(self)

    def cancel(self) -> None:
        self.stepper.cancel(self)

    def prebuild(self) -> None:
        for part in self.parts:
            part.prebuild()

    def finish(self) -> None:
        """Draw what is still pending at once (tests, screenshots, exports)."""
        self.stepper.finish()


class SummaryView(QWidget):
    """The identified values per component, the failures, and the status of every analysis."""

    title = "Results"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.filled = False
        self.table = QTableWidget()
        self.table.setObjectName("results-table")
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.status = QTableWidget()
        self.status.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        layout = QVBoxLayout(self)
        layout.addWidget(QLabel("Identified values"))
        layout.addWidget(self.table, 2)
        layout.addWidget(QLabel("Analyses of this channel"))
        layout.addWidget(self.status, 1)

    COLUMNS = ("component", "frequency (Hz)", "C_i (kg/(m s))", "C_i 95 %", "C_f (kg/m²)",
               "C_f 95 %", "R²")

    def show_results(self, results: RunResults, channel: str) -> None:
        rows_ = table_rows(results, channel)
        self.table.clear()
        self.table.setColumnCount(len(self.COLUMNS))
        self.table.setHorizontalHeaderLabels(list(self.COLUMNS))
        self.table.setRowCount(len(rows_))
        for r, row in enumerate(rows_):
            for c, key in enumerate(("index", "frequency_hz", "c_i", "c_i_ci95", "c_f",
                                     "c_f_ci95", "r2")):
                value = row.get(key)
                if isinstance(value, float):
                    text = f"{value:.5g}"
                elif isinstance(value, (list, tuple)):
                    text = _format_ci(value)
                else:
                    text = "" if value is None else str(value)
                self.table.setItem(r, c, QTableWidgetItem(text))
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        groups = results.analysis.get(channel, {})
        self.status.clear()
        self.status.setColumnCount(3)
        self.status.setHorizontalHeaderLabels(["analysis", "status", "message / parameters"])
        self.status.setRowCount(len(groups))
        for r, (plugin, result) in enumerate(groups.items()):
            self.status.setItem(r, 0, QTableWidgetItem(plugin))
            item = QTableWidgetItem(result.status)
            if not result.ok:
                item.setForeground(pg.mkColor("#b00020"))
            self.status.setItem(r, 1, item)
            detail = result.error or ", ".join(f"{k}={v}" for k, v in result.params.items())
            self.status.setItem(r, 2, QTableWidgetItem(detail))
        self.status.horizontalHeader().setStretchLastSection(True)
        self.filled = bool(rows_)


def table_rows(results: RunResults, channel: str) -> list[dict[str, Any]]:
    """One flat dictionary per component: index, frequency and the equivalent damping."""
    out = []
    for component in results.components(channel):
        row = {"index": component.get("index"), "frequency_hz": component.get("frequency_hz")}
        eq = component.get("equivalent_damping")
        if isinstance(eq, dict):
            for key in ("c_i", "c_i_ci95", "c_f", "c_f_ci95", "r2"):
                row[key] = eq.get(key)
        out.append(row)
    return out


class DatasetBrowser(QWidget):
    """Every group and dataset under ``/analysis/<channel>``, any plugin; select one to plot it."""

    title = "All datasets"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.filled = False
        self.results: RunResults | None = None
        self.channel = ""
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["analysis / dataset", "shape", "units"])
        self.tree.itemSelectionChanged.connect(self._selected)
        self.plot = pg.PlotWidget()
        self.plot.showGrid(x=True, y=True, alpha=0.2)
        splitter = QSplitter()
        splitter.addWidget(self.tree)
        splitter.addWidget(self.plot)
        splitter.setStretchFactor(1, 2)
        layout = QVBoxLayout(self)
        layout.addWidget(splitter)

    def show_results(self, results: RunResults, channel: str) -> None:
        self.results, self.channel = results, channel
        self.tree.clear()
        self.plot.clear()
        for plugin, result in results.analysis.get(channel, {}).items():
            top = QTreeWidgetItem([f"{plugin} ({result.status})", "", ""])
            if result.error:
                top.setToolTip(0, result.error)
            for name, array in result.datasets.items():
                child = QTreeWidgetItem([name, "x".join(map(str, np.shape(array))),
                                         result.units.get(name, "")])
                child.setData(0, Qt.ItemDataRole.UserRole, (plugin, name))
                top.addChild(child)
            self.tree.addTopLevelItem(top)
            top.setExpanded(True)
        self.filled = self.tree.topLevelItemCount() > 0

    def _selected(self) -> None:
        items = self.tree.selectedItems()
        if not items or self.results is None:
            return
        key = items[0].data(0, Qt.ItemDataRole.UserRole)
        if not key:
            return
        plugin, name = key
        result = self.results.result(self.channel, plugin)
        array = np.asarray(result.datasets[name])
        self.plot.clear()
        self.plot.setTitle(f"{plugin}/{name}")
        if not np.issubdtype(array.dtype, np.number) and array.dtype != bool:
            return
        if np.iscomplexobj(array):
            array = np.abs(array)
        for k, row in enumerate(rows(array.astype(float))[:MAX_COMPONENTS_DRAWN]):
            _line(self.plot.getPlotItem(), np.arange(row.size), row, COLOURS[k % len(COLOURS)])


# --------------------------------------------------------------------------- the panel
class AnalysisParameters(QGroupBox):
    """The chain (``[analysis]``) and a form per plugin of the chain, from the plugins' schemas.

    A valid change asks for a re-analysis (debounced); ``rerun`` carries the overrides.
    """

    rerun = Signal(list)

    def __init__(self, registry: Registry, parent: QWidget | None = None) -> None:
        super().__init__("Analysis parameters", parent)
        self.registry = registry
        self.chain_form: ParamForm | None = None
        self.forms: dict[str, ParamForm] = {}
        self.params: dict[str, dict] = {}
        self.chain_holder = QVBoxLayout()
        self.plugin = QComboBox()
        self.plugin.setObjectName("analysis-plugin")
        self.plugin.currentIndexChanged.connect(self._plugin_changed)
        self.holder = QVBoxLayout()
        self.button = QPushButton("Re-run analysis")
        self.button.setObjectName("rerun")
        self.button.clicked.connect(self.request)
        self.auto = QTimer(self)
        self.auto.setSingleShot(True)
        self.auto.setInterval(400)
        self.auto.timeout.connect(self.request)
        self.note = QLabel("")
        self.note.setWordWrap(True)
        installed = ", ".join(registry.names("analysis")) or "none"
        self.setToolTip(f"Installed analysis plugins: {installed}")
        layout = QVBoxLayout(self)
        layout.addLayout(self.chain_holder)
        layout.addWidget(QLabel("Plugin"))
        layout.addWidget(self.plugin)
        layout.addLayout(self.holder)
        layout.addStretch(1)
        layout.addWidget(self.button)
        layout.addWidget(self.note)
        self.setEnabled(False)

    def load(self, analysis: dict[str, Any], params: dict[str, dict]) -> None:
        """Forms for a run's chain and the parameters its plugins last ran with."""
        for _ in self.loading(analysis, params):
            pass

    def loading(self, analysis: dict[str, Any], params: dict[str, dict]) -> Iterator[None]:
        """:meth:`load` a form at a time (see :class:`Stepper`); the panel is disabled until
        every form is there."""
        self.setEnabled(False)
        # the forms of the run shown before go, their values with them
        for form in self.forms.values():
            form.deleteLater()
        self.forms.clear()
        if self.chain_form is not None:
            self.chain_form.deleteLater()
        self.chain_form = ParamForm(ANALYSIS_PARAMS, analysis, "analysis")
        self.chain_form.changed.connect(self._chain_changed)
        self.chain_holder.addWidget(self.chain_form)
        self.params = {k: dict(v) for k, v in params.items()}
        yield
        yield from self._forms(list(analysis.get("chain") or []))
        self.setEnabled(True)

    def _build_forms(self, chain: list[str]) -> None:
        for _ in self._forms(chain):
            pass

    def _forms(self, chain: list[str]) -> Iterator[None]:
        """A form per plugin of ``chain`` (one per step), keeping the values edited so far."""
        current = self.plugin.currentData()
        for name, form in self.forms.items():
            self.params[name] = form.values()
            form.deleteLater()
        self.forms.clear()
        self.plugin.blockSignals(True)
        self.plugin.clear()
        self.plugin.blockSignals(False)
        unknown = []
        for name in chain:
            if name not in self.registry.descriptors["analysis"]:
                unknown.append(name)
                continue
            descriptor = self.registry.get("analysis", name)
            form = ParamForm(descriptor.params, self.params.get(name, {}), f"analysis.{name}")
            form.setVisible(False)
            form.setToolTip(descriptor.help)
            form.changed.connect(self._changed)
            self.holder.addWidget(form)
            self.forms[name] = form
            self.plugin.blockSignals(True)
            self.plugin.addItem(name, name)
            self.plugin.blockSignals(False)
            yield
        self.plugin.blockSignals(True)
        if current in self.forms:
            self.plugin.setCurrentIndex(list(self.forms).index(current))
        self.plugin.blockSignals(False)
        self._plugin_changed()
        self.note.setText(f"not installed here: {', '.join(unknown)}" if unknown else "")

    def _chain_changed(self) -> None:
        if self.chain_form.is_valid():
            self._build_forms(list(self.chain_form.values()["chain"] or []))
        self._changed()

    def _plugin_changed(self) -> None:
        current = self.plugin.currentData()
        for name, form in self.forms.items():
            form.setVisible(name == current)

    def valid(self) -> bool:
        forms = [self.chain_form, *self.forms.values()] if self.chain_form else []
        return all(form.is_valid() for form in forms)

    def _changed(self) -> None:
        if self.valid():
            self.auto.start()
        else:
            self.auto.stop()

    def overrides(self) -> list[str]:
        """Every value of every form (the run's profile may hold older values than its last
        analysis, so all are given), as ``fsi-lab analyze --set`` takes them."""
        items = []
        if self.chain_form is not None:
            for field in self.chain_form.fields.values():
                if field.param.name == "chain" or field.value:
                    items.append(field.override("analysis"))
        for name, form in self.forms.items():
            items.extend(form.overrides(f"analysis.{name}"))
        return items

    def request(self) -> None:
        self.auto.stop()
        if self.valid() and self.chain_form is not None:
            self.rerun.emit(self.overrides())


class AnalysisViews(QWidget):
    """The views of one run, a channel selector and the parameter panel.

    Signals: ``reanalysed(path)`` after an analysis was stored, ``analysis_failed(path)``,
    ``message(level, text)``.
    """

    reanalysed = Signal(object)
    analysis_failed = Signal(object)
    message = Signal(str, str)

    def __init__(self, registry: Registry, pool: TaskPool, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.registry = registry
        self.pool = pool
        self.results: RunResults | None = None
        self.job: AnalysisJob | None = None
        self.title = QLabel("No run open: runs appear here when they finish or when you open "
                            "a run file.")
        self.title.setObjectName("analysis-title")
        self.title.setWordWrap(True)
        self.channel = QComboBox()
        self.channel.setObjectName("analysis-channel")
        self.channel.currentIndexChanged.connect(self._redraw)
        self.state = QLabel("")
        self.views: list[Any] = [OverviewView(), HVDView(), FrequencyView(), BackboneView(), DampingView(),
                                 EquivalentDampingView(), ModalModelView(), SpectrumView(),
                                 SummaryView(), DatasetBrowser()]
        self.tabs = QTabWidget()
        self.tabs.setObjectName("analysis-tabs")
        for view in self.views:
            self.tabs.addTab(view, view.title)
        self._drawn: set[int] = set()  # views drawn for the run and channel shown
        # Draws the figures of the tab shown, then builds the parameter forms of a new run, a
        # slice per turn of the event loop, in that order.
        self.stepper = Stepper(self)
        self.view(OverviewView).stepper = self.stepper
        self.tabs.currentChanged.connect(self._draw_current)
        # build the figures' plot items in idle time, one view per turn of the event loop
        self._prebuild = [v for v in self.views if hasattr(v, "prebuild")]
        self._prebuild_timer = QTimer(self)
        self._prebuild_timer.setSingleShot(True)
        self._prebuild_timer.timeout.connect(self._prebuild_next)
        self._prebuild_timer.start(200)
        self.parameters = AnalysisParameters(registry)
        self.parameters.rerun.connect(self.rerun)
        bar = QHBoxLayout()
        bar.addWidget(self.title, 1)
        bar.addWidget(QLabel("Channel"))
        bar.addWidget(self.channel)
        # in a scroll area: building the forms of a run does not resize the figures beside them
        parameters = QScrollArea()
        parameters.setWidgetResizable(True)
        parameters.setFrameShape(QScrollArea.Shape.NoFrame)
        parameters.setWidget(self.parameters)
        parameters.setMinimumWidth(300)
        parameters.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        splitter = QSplitter(Qt.Orientation.Horizontal)
        splitter.addWidget(self.tabs)
        splitter.addWidget(parameters)
        splitter.setStretchFactor(0, 4)
        splitter.setStretchFactor(1, 1)
        self.parameters.setMinimumWidth(280)
        layout = QVBoxLayout(self)
        layout.addLayout(bar)
        layout.addWidget(self.state)
        layout.addWidget(splitter, 1)

    def stop_drawing(self) -> None:
        """Cancel drawings scheduled for later turns of the event loop (closing)."""
        self._prebuild.clear()
        self._prebuild_timer.stop()
        self.stepper.cancel()

    def _prebuild_next(self) -> None:
        if self._prebuild and self.results is None:
            self._prebuild.pop(0).prebuild()
            self._prebuild_timer.start(0)

    def view(self, cls: type) -> Any:
        return next(v for v in self.views if isinstance(v, cls))

    def show_results(self, results: RunResults) -> None:
        """Show a run (already read off the UI thread).

        Only the title, channel and state are set now; the figures of the Overview are drawn
        one per turn of the event loop, then the parameter forms are built (see
        :attr:`pending` and :meth:`finish`)."""
        self.results = results
        status = results.exit_status
        started = results.attrs.get("start_time", "")
        self.title.setText(f"<b>{results.name}</b> — {results.path.name} — {status}"
                           + (f" — {started[:19]}" if started else ""))
        channels = results.analysed_channels() or [
            n for n, c in results.channels.items() if c.quantity in ("velocity", "displacement")
        ] or list(results.channels)
        current = self.channel.currentData()
        self.channel.blockSignals(True)
        self.channel.clear()
        for name in channels:
            self.channel.addItem(name, name)
        if current in channels:
            self.channel.setCurrentIndex(channels.index(current))
        self.channel.blockSignals(False)
        if not results.analysis:
            self.state.setText("not computed: this run file has no analysis results "
                               f"(exit status {status}); set the parameters and re-run")
        else:
            errors = [f"{r.plugin} on {r.channel}: {r.error}" for groups in results.analysis.values()
                      for r in groups.values() if not r.ok]
            self.state.setText("failed: " + "; ".join(errors) if errors else "")
        self.state.setStyleSheet("color: #b00020;" if results.analysis and
                                 self.state.text().startswith("failed") else "color: #555;")
        self._redraw()
        # the forms after the figures: the figures are what is looked at first
        self.stepper.cancel(self.parameters)
        self.stepper.add(self.parameters.loading(*chain_of(results, self.registry)),
                         self.parameters)

    @property
    def pending(self) -> bool:
        """Whether figures or the parameter forms of the run shown are still to be built."""
        return self.stepper.pending

    def finish(self) -> None:
        """Build at once what is still pending (tests, screenshots, exports)."""
        self.stepper.finish()

    def _redraw(self) -> None:
        """Views are drawn when shown: the current one now (its figures a slice per turn of
        the event loop), the others on their turn."""
        self._drawn.clear()
        for view in self.views:
            self.stepper.cancel(view)
        self._draw_current()

    def _draw_current(self, *args) -> None:
        self._draw(self.tabs.currentIndex())

    def _draw(self, index: int, now: bool = False) -> None:
        if self.results is None or index < 0 or index in self._drawn:
            return
        self._drawn.add(index)
        view, channel = self.views[index], self.channel.currentData() or ""
        if isinstance(view, OverviewView) and not now:
            view.show_results(self.results, channel)  # queues its parts on the stepper
        elif isinstance(view, View) and not now:
            self.stepper.add(view.drawing(self.results, channel), view)
        else:
            view.show_results(self.results, channel)

    def filled(self) -> dict[str, bool]:
        """Whether each view shows data (draws the views not drawn yet)."""
        for index in range(len(self.views)):
            self._draw(index, now=True)
        self.finish()
        return {view.title: view.filled for view in self.views}

    # ------------------------------------------------------------------ re-analysis
    @property
    def busy(self) -> bool:
        return self.job is not None

    def analyse(self, path: str | Path, overrides: list[str] = ()) -> bool:
        """Run the chain on ``path`` with ``overrides`` in a child process (``fsi-lab analyze``);
        ``reanalysed(path)`` or ``message`` follows. False if an analysis is already running."""
        if self.job is not None:
            return False
        self.job = AnalysisJob(path, list(overrides), self)
        self.job.succeeded.connect(self._job_done)
        self.job.failed.connect(self._job_failed)
        self.parameters.button.setEnabled(False)
        self.parameters.note.setText("analysing (fsi-lab analyze in a separate process) ...")
        self.job.start()
        return True

    def rerun(self, overrides: list[str]) -> None:
        if self.results is not None:
            self.analyse(self.results.path, overrides)

    def wait(self, timeout_ms: int = 30000) -> None:
        if self.job is not None:
            self.job.wait(timeout_ms)

    def _end_job(self) -> None:
        job, self.job = self.job, None
        if job is not None:
            job.deleteLater()
        self.parameters.button.setEnabled(True)

    def _job_done(self, path: Path, summary: object) -> None:
        self._end_job()
        self.parameters.note.setText("analysis stored in the run file")
        self.reanalysed.emit(path)

    def _job_failed(self, path: Path, message: str) -> None:
        self._end_job()
        self.parameters.note.setText(f"failed: {message}")
        self.message.emit("ERROR", f"analysis of {Path(path).name} failed: {message}")
        self.analysis_failed.emit(path)
