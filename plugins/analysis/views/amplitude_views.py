"""Figures against amplitude: backbone and damping ratio vs displacement and velocity amplitude."""

from __future__ import annotations

from typing import Iterator

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QWidget

from fsi_lab.gui.analysis.datasets import finite_pairs, per_component, summary_series
from fsi_lab.gui.analysis.plotting import (
    COLOURS,
    MAX_COMPONENTS_DRAWN,
    amplitude_weighted_range,
    draw_line,
    draw_points,
    plain_numbers,
    robust_range,
)
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import RunResults
from fsi_lab.plugins.analysis.views.labels import measured_amplitude
from fsi_lab.plugins.analysis.views.names import (
    DISPLACEMENT_AMPLITUDE,
    FREQUENCY,
    VELOCITY_AMPLITUDE,
    VELOCITY_FREQUENCY,
    ZETA,
)


class _AmplitudeView(View):
    """Two plots of a quantity against displacement and velocity amplitude."""

    #: the dataset drawn against displacement amplitude, and the one against velocity
    #: amplitude (the same when empty)
    y_name = ""
    velocity_y_name = ""
    summary_velocity_section = ""
    y_label = ""
    y_units: str | None = None
    #: where the curves are read from a run whose datasets lack them
    summary_section = ""
    summary_y = ""
    #: the modal-model datasets of the model's curve: amplitudes against displacement and
    #: velocity ("" where modal-model does not compute it) and the quantity drawn
    model_x = ""
    model_velocity_x = ""
    model_y = ""

    def __init__(self, compact: bool = False, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.compact = compact
        self.cells = ((0, 0),) if compact else ((0, 0), (0, 1))

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        result = results.result(channel, self.plugins[0])
        ok = result is not None and result.ok
        y = per_component(result, self.y_name) if ok else []
        y_v = per_component(result, self.velocity_y_name or self.y_name) if ok else []
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
        self.prepare(results, channel, [b for _, b in pairs_d or pairs_v])
        pairs_d = [(a, self.shown(k, b)) for k, (a, b) in enumerate(pairs_d)]
        pairs_v = [(a, self.shown(k, b)) for k, (a, b) in enumerate(pairs_v)]
        left = self.add_plot(0, 0, self.y_label, measured_amplitude(results), self.y_units,
                             "m")
        yield
        for k, (a, b) in enumerate(pairs_d[:MAX_COMPONENTS_DRAWN]):
            self._series(left, a, b, k)
            yield
        self.y_range(left, pairs_d)
        right = None
        if not self.compact:
            right = self.add_plot(0, 1, self.y_label, measured_amplitude(results, "velocity"),
                                  self.y_units, "m/s")
            yield
            for k, (a, b) in enumerate(pairs_v[:MAX_COMPONENTS_DRAWN]):
                self._series(right, a, b, k)
                yield
            self.y_range(right, pairs_v)
            if not pairs_v:
                right.setTitle("velocity amplitude: not computed")
        yield from self.overlay_model(results, channel, left, right)
        self.set_note(f"{self.title} of {channel}, {len(pairs_d or pairs_v)} component(s)")
        return True

    def prepare(self, results: RunResults, channel: str, rows: list[np.ndarray]) -> None:
        """Work out what :meth:`shown` needs before a drawing (``rows``: the quantity of each
        component)."""

    def shown(self, k: int, values: np.ndarray) -> np.ndarray:
        """Component ``k``'s quantity as drawn (as it is, unless a view says otherwise)."""
        return values

    def component_name(self, k: int) -> str:
        return f"component {k}"

    def y_range(self, plot: pg.PlotItem, pairs) -> None:
        robust_range(plot, [b for _, b in pairs])

    def _series(self, plot: pg.PlotItem, a: np.ndarray, b: np.ndarray, k: int) -> None:
        colour = COLOURS[k % len(COLOURS)]
        if a.size > 400:
            draw_line(plot, a, b, colour, self.component_name(k), 1.4)
        else:
            draw_points(plot, a, b, colour, self.component_name(k), 5)

    def overlay_model(self, results, channel, left, right) -> Iterator[None]:
        """The modal model's curve (dashed) over the measured one, where it computed it."""
        model = results.result(channel, "modal-model")
        if model is None or not model.ok:
            return
        y = per_component(model, self.model_y)
        for plot, name in ((left, self.model_x), (right, self.model_velocity_x)):
            if plot is None or not name:
                continue
            shown = [self.shown(k, row) for k, row in enumerate(y)]
            for k, (a, b) in enumerate(finite_pairs(zip(per_component(model, name), shown))):
                a, b = model_trend(a, b)
                draw_line(plot, a, b, COLOURS[k % len(COLOURS)],
                          "modal model" if k == 0 else None, 1.6, Qt.PenStyle.DashLine)
                yield


#: A model curve is drawn as the medians of groups of MODEL_GROUP or more of its points of
#: neighbouring amplitudes, at most MODEL_BINS groups.
MODEL_GROUP, MODEL_BINS = 8, 40


def model_trend(amplitude: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A modal model's curve (``values`` against ``amplitude``, one point per half cycle) as a
    line: the medians of both in groups of :data:`MODEL_GROUP` or more points of neighbouring
    amplitudes, of equal counts (a decay's half cycles crowd its small amplitudes, and its
    largest stay drawn), :data:`MODEL_BINS` at most; by increasing amplitude when there are
    fewer than two groups' worth. Its half cycles scatter (the other modes and the base's
    last motion beat with it, most at the smallest amplitudes), and a line through them by
    amplitude zig-zagged across the plot."""
    order = np.argsort(amplitude)
    a, v = amplitude[order], values[order]
    count = min(a.size // MODEL_GROUP, MODEL_BINS)
    if count < 2:
        return a, v
    groups = np.array_split(np.arange(a.size), count)
    return (np.array([np.median(a[g]) for g in groups]),
            np.array([np.median(v[g]) for g in groups]))


class BackboneView(_AmplitudeView):
    """Each component's frequency relative to its own identified frequency f_n, in %: modes
    tens of hertz apart share one axis and each one's curvature shows."""

    title = "Backbone"
    plugins = ("backbone",)
    y_name = FREQUENCY
    velocity_y_name = VELOCITY_FREQUENCY
    summary_velocity_section = "backbone_velocity"
    y_label = "frequency shift (f − f_n) / f_n (%)"  # no unit: pyqtgraph would prefix "%"
    summary_section = "backbone"
    summary_y = "frequency_hz"
    model_x = "backbone_amplitude_model"
    model_y = "backbone_frequency_model"

    def __init__(self, compact: bool = False, parent: QWidget | None = None) -> None:
        super().__init__(compact, parent)
        #: each component's reference frequency f_n (Hz): the summary's identified frequency,
        #: else the median of its backbone
        self.references: list[float] = []

    def prepare(self, results: RunResults, channel: str, rows: list[np.ndarray]) -> None:
        identified = {c.get("index"): c.get("frequency_hz")
                      for c in results.components(channel)}
        self.references = []
        for k, row in enumerate(rows):
            f_n = identified.get(k)
            if not isinstance(f_n, (int, float)) or not np.isfinite(f_n) or f_n <= 0:
                finite = row[np.isfinite(row)]
                f_n = float(np.median(finite)) if finite.size else np.nan
            self.references.append(float(f_n))

    def shown(self, k: int, values: np.ndarray) -> np.ndarray:
        f_n = self.references[k] if k < len(self.references) else np.nan
        return 100.0 * (np.asarray(values, dtype=float) - f_n) / f_n

    def component_name(self, k: int) -> str:
        if k < len(self.references) and np.isfinite(self.references[k]):
            return f"component {k} (f_n = {self.references[k]:.4g} Hz)"
        return f"component {k}"

    def y_range(self, plot: pg.PlotItem, pairs) -> None:
        # the backbone at the amplitudes that carry it, not the noise floor of the smallest;
        # percent as it is (no "x0.001" scale on the axis)
        amplitude_weighted_range(plot, pairs)
        plain_numbers(plot)


class DampingView(_AmplitudeView):
    title = "Damping"
    plugins = ("damping",)
    y_name = ZETA
    y_label = "damping ratio ζ"
    summary_section = "damping"
    summary_y = "zeta"
    model_x = "damping_amplitude_model"
    model_velocity_x = "damping_velocity_amplitude_model"
    model_y = "damping_zeta_model"
