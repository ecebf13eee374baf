"""The C_q figure: equivalent damping against amplitude, its first-order fit, C_i and C_f."""

from __future__ import annotations

from typing import Any, Iterator

import numpy as np
from PySide6.QtCore import Qt

from fsi_lab.gui.analysis.datasets import finite_pairs, format_ci, per_component
from fsi_lab.gui.analysis.names import CQ, CQ_AMPLITUDE
from fsi_lab.gui.analysis.plotting import COLOURS, draw_line, draw_points, robust_range
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import PluginResult, RunResults


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
                draw_line(plot, span, line, colour,
                          f"fit: C_i + 8 C_f ω W / 3π (component {k})", 1.8,
                          Qt.PenStyle.DashLine)
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
                source[key] = result.scalar(f"component_{k}_{key}")
        if not isinstance(source.get("c_i"), (int, float)):
            return ""
        parts = [f"C<sub>i</sub> = {source['c_i']:.4g} {format_ci(source.get('c_i_ci95'))} "
                 "kg/(m s)"]
        if isinstance(source.get("c_f"), (int, float)):
            parts.append(f"C<sub>f</sub> = {source['c_f']:.4g} "
                         f"{format_ci(source.get('c_f_ci95'))} kg/m²")
        if isinstance(source.get("r2"), (int, float)):
            parts.append(f"R² = {source['r2']:.3f}")
        return "<br>&nbsp;&nbsp;".join(parts)
