"""The spectrum figure: amplitude spectrum with its peaks, and the FRF with its coherence."""

from __future__ import annotations

from typing import Iterator

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt

from fsi_lab.gui.analysis.datasets import rows
from fsi_lab.gui.analysis.plotting import COLOURS, draw_line
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import RunResults
from fsi_lab.plugins.analysis.views.names import (
    SPECTRUM_AMPLITUDE,
    SPECTRUM_FREQUENCY,
    SPECTRUM_PEAKS,
)

#: Heights (fractions of the plot) of the labels of successive spectrum peaks.
PEAK_LABEL_HEIGHTS = (0.95, 0.85, 0.75)


class SpectrumView(View):
    title = "Spectrum / FRF"
    plugins = ("spectrum", "frf")
    cells = ((0, 0), (1, 0), (2, 0))

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        drawn = False
        spectrum = results.result(channel, "spectrum")
        if spectrum is not None and spectrum.ok:
            freqs = spectrum.get(SPECTRUM_FREQUENCY)
            amps = spectrum.get(SPECTRUM_AMPLITUDE)
            if freqs is not None and amps is not None:
                unit = results.channels[channel].unit if channel in results.channels else ""
                plot = self.add_plot(0, 0, f"|{channel}|", "frequency", unit or None, "Hz")
                yield
                plot.setLogMode(y=True)
                plot.getAxis("left").enableAutoSIPrefix(False)  # decades read as they are
                for k, a in enumerate(rows(amps)):
                    if a.size == np.asarray(freqs).size:
                        draw_line(plot, freqs, np.maximum(np.abs(a), 1e-300),
                                  COLOURS[k % len(COLOURS)],
                                  "amplitude spectrum" if k == 0 else None, 1.2)
                        yield
                peaks = spectrum.get(SPECTRUM_PEAKS)
                if peaks is None and results.summary:
                    peaks = results.summary.get("channels", {}).get(channel, {}).get(
                        "spectrum_peaks_hz")
                peak_list = np.ravel(peaks if peaks is not None else [])
                if peak_list.size:
                    plot.setXRange(0, 3 * float(np.max(peak_list[:10])), padding=0)
                for i, f in enumerate(sorted(float(f) for f in peak_list[:10])):
                    # labels of neighbouring peaks at staggered heights: they never pile up
                    plot.addItem(pg.InfiniteLine(
                        f, pen=pg.mkPen("#9e9e9e", style=Qt.PenStyle.DotLine),
                        label=f"{f:.2f} Hz",
                        labelOpts={"position": PEAK_LABEL_HEIGHTS[i % len(PEAK_LABEL_HEIGHTS)],
                                   "color": "#555", "fill": (255, 255, 255, 200)}))
                    yield
                drawn = True
        frf = results.result(channel, "frf")
        if frf is not None and frf.ok:
            freqs = frf.get(SPECTRUM_FREQUENCY)
            if freqs is not None:
                plot = self.add_plot(1 if drawn else 0, 0, "|H|", "frequency", None, "Hz")
                yield
                plot.setLogMode(y=True)
                plot.getAxis("left").enableAutoSIPrefix(False)
                for k, name in enumerate(("h1", "h2")):
                    h = frf.get(f"{name}_magnitude")
                    if h is not None and np.asarray(h).size == np.asarray(freqs).size:
                        draw_line(plot, freqs, np.maximum(np.abs(h), 1e-300), COLOURS[k],
                                  name.upper())
                        yield
                coherence = frf.get("coherence")
                if coherence is not None and np.asarray(coherence).size == np.asarray(freqs).size:
                    coh = self.add_plot(2 if drawn else 1, 0, "coherence", "frequency", None, "Hz")
                    yield
                    coh.setXLink(plot)
                    draw_line(coh, freqs, coherence, "#2ca02c", "coherence")
                    yield
                drawn = True
        if drawn:
            self.set_note(f"spectra of {channel}")
        return drawn
