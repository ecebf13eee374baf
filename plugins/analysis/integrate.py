"""Integration in the frequency domain: velocity to displacement, acceleration to velocity.

The paper (Section 5.3) integrates the measured velocity and removes the zero-frequency content
in the frequency domain, so that the displacement oscillates about zero. Here:

1. both ends are extended by linear prediction (:func:`._signal.predict_pad`: a damped-
   exponential model with a constant level fitted to the first and last cycles, continued
   without a phase jump, a decay allowed to grow backwards by up to ``PAD_GROWTH``) to a fast
   FFT length, so the record does not wrap around with a jump and an offset stays an offset;
2. (no detrending in the time domain: a least-squares line through a free decay is not zero
   and removing it would distort the displacement);
3. the spectrum is divided by ``(i 2 pi f)^order`` and multiplied by a zero-phase high-pass:
   gain 0 up to ``highpass / 2``, 1 from ``highpass`` up, infinitely smooth between. The
   default ``highpass`` is half the lowest significant spectral peak of the record, so the
   modes pass unchanged and the zero-frequency and drift content is removed;
4. back to the time domain, cropped to the record.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.fft as sfft

from fsi_lab.plugins.analysis._signal import (
    FFT_WORKERS, as_record, check_rate, fail, highpass_gain, predict_pad,
)
from fsi_lab.plugins.analysis.spectrum import free_decay_peaks

#: Default high-pass corner as a fraction of the lowest significant spectral peak.
HIGHPASS_FRACTION = 0.5
#: Each end is extended by PAD_PERIODS periods of the high-pass corner.
PAD_PERIODS = 4.0
#: Largest growth of the predicted extension: a decay continued backwards in time grows, and
#: letting it (instead of mirroring) avoids an envelope kink at the record start, whose low
#: frequency content the high-pass would otherwise distort.
PAD_GROWTH = 100.0


def lowest_mode(x: np.ndarray, fs: float, func: str) -> tuple[float, np.ndarray]:
    """Lowest significant spectral peak (Hz) of a record, and all significant peaks (of its
    decays' averaged spectrum when it holds several: :func:`.spectrum.free_decay_peaks`)."""
    peaks = free_decay_peaks(x, fs, min_relative=0.01, smoothing=0.05)
    if peaks.frequencies.size == 0:
        raise fail(func, "found no spectral peak above the lowest resolvable frequency "
                         f"{2.0 * fs / x.size:.3g} Hz, so no high-pass corner can be chosen; "
                         "give highpass (Hz) explicitly")
    return float(peaks.frequencies.min()), peaks.frequencies


def integrate(x: Any, fs: float, *, order: int = 1, highpass: float | None = None) -> np.ndarray:
    """Integrate a record ``order`` times in the frequency domain, drift removed.

    Parameters
    ----------
    x
        Samples in unit U (e.g. velocity, m/s, or acceleration, m/s^2); 1-D, finite, not
        constant, not clipped, at least 64 samples.
    fs
        Sample rate, Hz.
    order
        1 (velocity -> displacement, acceleration -> velocity) or 2 (acceleration ->
        displacement).
    highpass
        High-pass corner, Hz: content below ``highpass / 2`` is removed, above ``highpass`` kept
        exactly. Default: half the lowest significant spectral peak of the record.

    Returns
    -------
    numpy.ndarray
        The integral, unit U s^order (m for a velocity in m/s), same length as ``x``, with zero
        mean content below the high-pass.

    Raises
    ------
    AnalysisError
        Bad sample rate, NaN/inf, constant, clipped or too short record, order not 1 or 2, a
        high-pass corner not in (0, fs/2), or no spectral peak to set the default corner.
    """
    func = "integrate"
    fs = check_rate(fs, func)
    x = as_record(x, func, min_samples=64)
    if isinstance(order, bool) or order not in (1, 2):
        raise fail(func, f"order = {order!r}; expected 1 or 2")
    f_lo, peaks = lowest_mode(x, fs, func)
    if highpass is None:
        highpass = HIGHPASS_FRACTION * f_lo
    highpass = float(highpass)
    if not math.isfinite(highpass) or not (0 < highpass < fs / 2):
        raise fail(func, f"highpass = {highpass!r} Hz; expected a corner between 0 and "
                         f"{fs / 2:g} Hz (Nyquist)")
    n = x.size
    y = x
    pad = min(int(math.ceil(PAD_PERIODS * fs / highpass)), 4 * n)
    m = sfft.next_fast_len(n + 2 * pad, real=True)
    yp = predict_pad(y, fs, peaks, pad, m - n - pad, PAD_GROWTH)
    spec = sfft.rfft(yp, workers=FFT_WORKERS)
    f = np.arange(spec.size) * (fs / m)
    gain = highpass_gain(f, highpass)
    gain[0] = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(f > 0, gain / (2j * np.pi * np.where(f > 0, f, 1.0)) ** order, 0.0)
    out = sfft.irfft(spec * factor, n=m, workers=FFT_WORKERS)
    return out[pad:pad + n].copy()


# ----------------------------------------------------------------------------- plugin
from fsi_lab.contract import AnalysisContext, AnalysisPlugin, AnalysisResult  # noqa: E402
from fsi_lab.errors import AnalysisError  # noqa: E402
from fsi_lab.hookspecs import hookimpl  # noqa: E402
from fsi_lab.params import Param  # noqa: E402
from fsi_lab.plugins.analysis._chain import (  # noqa: E402
    SI_UNITS, ComponentSignals, components, error_entries, guarded, per_component, stack_rows,
    where,
)

_ORDER = {("velocity", "displacement"): 1, ("acceleration", "velocity"): 1,
          ("acceleration", "displacement"): 2}


def _run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
    ch = context.channel
    target = params["target"]
    if ch.quantity == target:
        order = 0                                     # nothing to do: passed through
    elif (ch.quantity, target) in _ORDER:
        order = _ORDER[(ch.quantity, target)]
    else:
        raise AnalysisError(
            f"{where('integrate', context)}: cannot integrate a {ch.quantity!r} channel "
            f"({ch.unit}) to {target}; expected a velocity or acceleration channel (or "
            f"target = the channel's own quantity)")
    comps = components(context, order)

    def work(c):
        if order == 0:
            return c.signal
        with guarded("integrate", context):
            return integrate(c.signal, c.sample_rate, order=order, highpass=params["highpass_hz"])

    done, errors = per_component("integrate", context, comps, work)
    unit = SI_UNITS[target]
    entries = [{"index": k, f"{target}_peak": float(np.max(np.abs(s)))} for k, s in done.items()]
    err_entries, err_attrs = error_entries(errors, "integrate")
    values = ComponentSignals(quantity=target, unit=unit, sample_rate=float(ch.sample_rate),
                              signals=done,
                              edge_masks={c.index: c.edge_mask for c in comps},
                              noise_floors={c.index: c.noise_floor for c in comps},
                              settles={c.index: c.settle for c in comps},
                              t0s={c.index: c.t0 for c in comps},
                              frequencies={c.index: c.frequency for c in comps})
    return AnalysisResult(
        datasets={"signals": stack_rows(done, len(comps))},
        units={"signals": unit},
        attrs={"quantity": target, "order": order, "from_quantity": ch.quantity,
               "start_s": comps[0].t0,
               "highpass_hz": params["highpass_hz"] if params["highpass_hz"] is not None
               else "auto (half the lowest spectral peak)", **err_attrs},
        summary={"components": entries + err_entries}, values=values)


PLUGIN = AnalysisPlugin(
    name="integrate",
    params=(
        Param("target", "str", "", "displacement", choices=("displacement", "velocity"),
              help="Quantity wanted: displacement (from velocity or acceleration) or velocity "
                   "(from acceleration)."),
        Param("highpass_hz", "float", "Hz", None, minimum=0.0, exclusive_minimum=True,
              help="High-pass corner: content below half of it is removed; unset = half the "
                   "lowest spectral peak of the record."),
    ),
    run=_run,
    help="Integrates velocity to displacement (or acceleration to velocity/displacement) in "
         "the frequency domain with the zero-frequency and drift content removed, per HVD "
         "component when hvd ran earlier.",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]
