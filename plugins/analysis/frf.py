"""The ``frf`` analysis plugin: H1 and H2 transfer functions over the reference channel.

Declared here; the work, around :mod:`fsi_lab.dsp.frf`, is in :mod:`._frf`, imported when the
chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.presentation import SummaryText

PLUGIN = AnalysisPlugin(
    name="frf",
    params=(
        Param("segment", "int", "", None, minimum=16,
              help="Samples per Welch segment (resolution fs/segment); unset = record/8, at "
                   "most 65536."),
        Param("overlap", "float", "", 0.5, minimum=0.0, maximum=0.95,
              help="Overlap of the Welch segments (fraction)."),
        Param("window", "str", "", "hann", choices=("hann", "hamming", "blackman", "boxcar"),
              help="Window of the Welch segments."),
        Param("min_relative", "float", "", 0.05, minimum=0.0, maximum=1.0,
              exclusive_minimum=True,
              help="Natural frequencies: peaks of |H1| with at least this relative prominence."),
        Param("max_peaks", "int", "", 8, minimum=1, help="At most this many natural frequencies."),
        Param("min_coherence", "float", "", 0.0, minimum=0.0, maximum=1.0,
              help="Ignore peaks where the coherence is lower."),
    ),
    run=Deferred("fsi_lab.plugins.analysis._frf:run"),
    help="H1 and H2 frequency response of the channel over the reference channel (base "
         "acceleration) by Welch averaging, coherence; natural frequencies and damping ratios "
         "of the peaks by a modal fit that models the window's leakage, with 95 % intervals; "
         "half-power damping ratios beside them.",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


def _mode(frequency, zeta, bounds) -> str:
    text = f"{frequency:.4g} Hz"
    if zeta is None:
        return text + " (damping ratio not resolved)"
    interval = f", 95 %: {bounds[0]:.2g} to {bounds[1]:.2g}" if isinstance(
        bounds, (list, tuple)) and len(bounds) == 2 and None not in bounds else ""
    return text + f" (damping ratio {zeta:.3g}{interval})"


@hookimpl
def fsi_lab_summary_lines(summary, component):
    """The modes the FRF's modal fit found, with their damping ratios (fsi-lab shows the
    warnings it keeps under its key)."""
    if component is not None:
        return None
    frf = summary.get("frf")
    if not isinstance(frf, dict):
        return None
    frequencies = frf.get("natural_frequencies_hz") or []
    zetas = frf.get("damping_ratios") or [None] * len(frequencies)
    bounds = frf.get("damping_ratio_ci95") or [None] * len(frequencies)
    modes = [_mode(f, z, b) for f, z, b in zip(frequencies, zetas, bounds) if f is not None]
    return SummaryText(keys=("frf",), lines=(
        f"frf against {frf.get('reference')}: " + (", ".join(modes) or "no mode found"),
        *(f"frf note: {note}" for note in frf.get("notes") or ())))
