"""Figures against time: HVD components with their envelopes, and the instantaneous frequency."""

from __future__ import annotations

from typing import Iterator

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QWidget

from fsi_lab.gui.analysis.datasets import channel_t0, finite_pairs, per_component, time_axis
from fsi_lab.gui.analysis.plotting import (
    COLOURS,
    MAX_COMPONENTS_DRAWN,
    active_span,
    draw_line,
    draw_points,
    robust_range,
)
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import RunResults
from fsi_lab.plugins.analysis.views.names import (
    HVD_COMPONENTS,
    HVD_EDGE,
    HVD_ENVELOPES,
    HVD_FREQUENCIES,
    ZC_FREQUENCY,
    ZC_TIME,
)


class HVDView(View):
    """The decomposed record with the sum of the components (unless ``record`` is False, as
    in the Overview), then each component with its envelope, one plot each."""

    title = "HVD components"
    plugins = ("hvd",)
    cells = ((0, 0), (1, 0), (2, 0))

    def __init__(self, max_components: int = MAX_COMPONENTS_DRAWN, record: bool = True,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.max_components = max_components
        self.record = record
        if not record:
            self.cells = ((1, 0),)

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
        top = self.add_plot(0, 0, channel, "time", unit or None, "s") if self.record else None
        if top is not None:
            yield
            yield from self._record(top, results, channel, hvd, components, t, n)
        count = min(max(len(components), len(envelopes)), self.max_components)
        for k in range(count):
            colour = COLOURS[k % len(COLOURS)]
            plot = self.add_plot(k + 1, 0, f"component {k}", "time", unit or None, "s")
            yield
            if top is None:
                top = plot  # the others follow its time axis
            else:
                plot.setXLink(top)
            if k < len(components):
                draw_line(plot, t, components[k], colour, f"component {k}", 1.0)
                yield
            if k < len(envelopes):
                draw_line(plot, t, envelopes[k], "#000000", "envelope", 1.4)
                yield
                draw_line(plot, t, -envelopes[k], "#000000", None, 1.4)
                yield
        if envelopes and top is not None:
            span = active_span(t, envelopes[0])
            if span is not None:
                top.setXRange(*span, padding=0)
        # The "bands" method's components are its modes' bands; HVD's have low-pass cut-offs.
        bands, cutoffs = hvd.get("bands"), hvd.get("cutoffs")
        if bands is not None and np.ndim(bands) == 2:
            extra = "; bands " + ", ".join(f"{lo:.3g} to {hi:.3g}" for lo, hi in bands) + " Hz"
        elif cutoffs is not None:
            extra = f"; cut-offs {', '.join(f'{c:.3g}' for c in np.ravel(cutoffs))} Hz"
        else:
            extra = ""
        self.set_note(f"HVD of {channel}: {count} of {max(len(components), len(envelopes))} "
                      f"component(s), by decreasing amplitude{extra}")
        return True

    @staticmethod
    def _record(top, results: RunResults, channel: str, hvd, components, t, n: int
                ) -> Iterator[None]:
        """The record HVD decomposed (or the measured channel) and the sum of the components."""
        residual = hvd.get("residual")
        if components and residual is not None and np.asarray(residual).size == n:
            record = np.sum(components, axis=0) + np.asarray(residual, dtype=float)
            relative = hvd.scalar("relative_to")
            draw_line(top, t, record, "#9e9e9e",
                      f"decomposed record (relative to {relative})" if isinstance(relative, str)
                      and not relative.startswith("none") else "decomposed record", 1.0)
            yield
        else:
            measured = results.channels.get(channel)
            if measured is not None and measured.data.size == n:
                draw_line(top, t, measured.data, "#9e9e9e", "measured", 1.0)
                yield
        if components:
            draw_line(top, t, np.sum(components, axis=0), "#000000", "sum of components", 1.0,
                      Qt.PenStyle.DashLine)
            yield


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
                draw_line(plot, t, f, COLOURS[k % len(COLOURS)], f"HVD component {k}", 1.4)
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
            shift = channel_t0(results, channel)  # the times count from the channel's start
            for k, (t, f) in enumerate(finite_pairs(zip(times, freqs))):
                draw_points(plot, t + shift, f, COLOURS[k % len(COLOURS)],
                            f"zero crossings, component {k}", 4)
                yield
                shown.append(f)
                drawn = True
        if drawn:
            robust_range(plot, shown)
            self.set_note(f"instantaneous frequency of {channel}; samples near the record's "
                          "ends, which HVD does not trust, are left out")
        return drawn
