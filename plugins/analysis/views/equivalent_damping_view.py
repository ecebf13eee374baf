"""The C_q figure: equivalent damping against amplitude, its first-order fit, C_i and C_f."""

from __future__ import annotations

from typing import Any, Iterator

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel, QWidget

from fsi_lab.gui.analysis.datasets import finite_pairs, format_ci, per_component
from fsi_lab.gui.analysis.plotting import (
    COLOURS,
    amplitude_weighted_range,
    draw_line,
    draw_points,
    plain_numbers,
)
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import PluginResult, RunResults
from fsi_lab.plugins.analysis.views.labels import cq_amplitude
from fsi_lab.plugins.analysis.views.names import CQ, CQ_AMPLITUDE


class EquivalentDampingView(View):
    """C_q points and fit lines per component; below them C_i, C_f, their 95 % intervals and
    R^2 of each component (``compact``, as in the Overview: three significant digits)."""

    title = "Cq fit"
    plugins = ("equivalent-damping",)

    def __init__(self, compact: bool = False, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.compact = compact
        self.values = QLabel()
        self.values.setObjectName("cq-values")
        self.values.setWordWrap(True)
        self.values.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.values.setVisible(False)
        self.column.addWidget(self.values)

    def clear(self) -> None:
        super().clear()
        self.values.setText("")
        self.values.setVisible(False)

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        result = results.result(channel, "equivalent-damping")
        if result is None or not result.ok:
            return False
        components = results.components(channel)
        # A long record's components are pooled over its segments: their C_i and C_f are the
        # component's own (docs/json-output.md, "Long records").
        summaries = {c.get("index"): c["equivalent_damping"]
                     if isinstance(c.get("equivalent_damping"), dict)
                     else {k: c.get(k) for k in ("c_i", "c_i_ci95", "c_f", "c_f_ci95")}
                     for c in components}
        frequencies = {c.get("index"): c.get("frequency_hz") for c in components}
        rows_w = per_component(result, CQ_AMPLITUDE)
        rows_cq = per_component(result, CQ)
        if not rows_cq:
            return False
        convention = result.scalar("amplitude_convention")
        amplitude = cq_amplitude(results, convention)
        plot = self.add_plot(0, 0, "C_q", amplitude, "kg/(m s)", "m")
        plain_numbers(plot)  # no "mkg/(m s)"
        yield
        lines, points, fits = [], [], []
        for k, (w_row, cq_row) in enumerate(zip(rows_w, rows_cq)):
            pairs = finite_pairs([(w_row, cq_row)])
            if not pairs:
                continue
            w, cq = pairs[0]
            points.append((w, cq))
            colour = COLOURS[k % len(COLOURS)]
            draw_points(plot, w, cq, colour, f"C_q, component {k}", 5)
            yield
            summary = summaries.get(k) or {}
            if summary.get("c_i") is not None and summary.get("c_f") is not None \
                    and frequencies.get(k):
                # Eq. 24 with the identified coefficients at the component's mean frequency
                # (equivalent-damping stores the coefficients, not the fitted line)
                omega = 2 * np.pi * float(frequencies[k])
                span = np.array([0.0, float(np.max(w))])
                line = summary["c_i"] + 8 * summary["c_f"] * omega * span / (3 * np.pi)
                fits.append(line)
                draw_line(plot, span, line, colour, f"fit, component {k}", 1.8,
                          Qt.PenStyle.DashLine)
                yield
            values = self._values(result, summary, k, self.compact)
            if values:
                lines.append(f"<b>component {k}</b>: {values}")
        if not lines:
            return False
        # the fits and the points that carry them, not the noise floor of the smallest
        # amplitudes (C_q scatters as 1/W there)
        shown = amplitude_weighted_range(plot, points, fits)
        clipped = 0 if shown is None else sum(
            int(np.sum((cq < shown[0]) | (cq > shown[1]))) for _, cq in points)
        if not self.compact:
            lines.append("<span style='color:#555'>in brackets: 95 % intervals</span>")
        self.values.setText("<br>".join(lines))
        self.values.setVisible(True)
        w = "q" if amplitude.startswith("modal") else "W"
        note = (f"C_q against {w}, its fit C_q = C_i + 8 C_f ω {w} / 3π (Eq. 24) and 95 % "
                "intervals" if self.compact else
                f"C_q = 2 ζ (μ + M) 2π f against the amplitude {w}, and its first-order fit "
                f"C_q = C_i + 8 C_f ω {w} / 3π (Eq. 24)")
        if clipped:
            note += f"; {clipped} point(s) beyond the range shown (View all shows them)"
        self.set_note(note)
        if convention:
            self.note.setToolTip(f"amplitudes: {convention}")
        return True

    @staticmethod
    def _values(result: PluginResult, summary: dict[str, Any], k: int,
                compact: bool = False) -> str:
        source = dict(summary)
        digits = 3 if compact else 4
        ci_units, cf_units = " kg/(m s)", " kg/m²"
        for key in ("c_i", "c_f", "r2"):
            if source.get(key) is None:
                source[key] = result.scalar(f"component_{k}_{key}")
        if not isinstance(source.get("c_i"), (int, float)):
            return ""
        parts = [f"C<sub>i</sub> = {source['c_i']:.{digits}g} "
                 f"{format_ci(source.get('c_i_ci95'), digits)}{ci_units}"]
        if isinstance(source.get("c_f"), (int, float)):
            parts.append(f"C<sub>f</sub> = {source['c_f']:.{digits}g} "
                         f"{format_ci(source.get('c_f_ci95'), digits)}{cf_units}")
        if isinstance(source.get("r2"), (int, float)):
            parts.append(f"R² = {source['r2']:.{digits - 1}f}")
        return (", " if compact else " &nbsp;·&nbsp; ").join(parts)
