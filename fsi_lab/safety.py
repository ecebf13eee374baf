"""The safety check every run passes before anything reaches an instrument.

It assesses the voltage the source puts out, not only the samples it is given. A source holds
each sample until the next (``arb_filter = "off"`` on the Keysight 33500) or reconstructs a
band-limited signal through its output filter (``"normal"``, ``"step"``), which overshoots the
samples next to fast edges; and the shaker model runs at no fewer than
:data:`STROKE_SAMPLES_PER_PERIOD` samples per suspension period, whatever the source's rate, so
that ringing at the suspension resonance cannot fall between the arb samples.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Iterator

import numpy as np

from fsi_lab.errors import SafetyError
from fsi_lab.lti import interpolate
from fsi_lab.shaker import stroke_of_blocks_mm

#: The stroke model runs at this many samples per suspension period at least (at 20 its
#: discrete-time step response would fall 0.7 % short of the continuous one; at 100, 0.02 %).
STROKE_SAMPLES_PER_PERIOD = 100
#: A band-limited reconstruction is computed at this many points per source sample, so that
#: its overshoot between the samples is seen.
OVERSAMPLING = 8
#: Margin on the peak of a band-limited reconstruction, for the peaks between its computed
#: points (at most about 2 % at 8 points per sample for content up to half the source rate)
#: and the difference between this model and the source's own filter.
BAND_LIMITED_MARGIN = 1.03
#: Most points per source sample the output is modelled at: a source rate below
#: STROKE_SAMPLES_PER_PERIOD x suspension_hz / MAX_OVERSAMPLING is refused.
MAX_OVERSAMPLING = 4096
#: Beyond this many samples per suspension period the shaker model's filter loses precision:
#: the source output is averaged down to DECIMATED_SAMPLES_PER_PERIOD for it.
MAX_STROKE_SAMPLES_PER_PERIOD = 10_000
DECIMATED_SAMPLES_PER_PERIOD = 1_000
#: Source samples of context on each side of a block (the reconstruction filter spans 10).
CONTEXT = 16
#: Output points modelled at a time (bounds the memory of a long waveform).
BLOCK = 1 << 20
HOLD = "sample-and-hold"
BAND_LIMITED = "band-limited"
#: How the source reconstructs its output for each ``arb_filter`` setting.
RECONSTRUCTIONS = {"off": (HOLD,), "normal": (BAND_LIMITED,), "step": (BAND_LIMITED,)}


@dataclass(frozen=True)
class SafetyReport:
    """Figures compared with the profile's ``[safety]`` limits, and the verdict.

    ``peak_drive_v`` is the peak of the source output as the source reconstructs it (V), which
    may exceed the peak of the waveform's samples; ``predicted_stroke_mm`` is the largest base
    displacement the ``[shaker]`` model predicts for that output (mm).
    """

    peak_drive_v: float
    max_drive_v: float
    gain: float
    max_gain: float
    predicted_stroke_mm: float
    max_stroke_mm: float
    problems: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.problems

    def as_dict(self) -> dict:
        data = asdict(self)
        data["problems"] = list(self.problems)
        data["ok"] = self.ok
        return data


def reconstructions_of(arb_filter: str | None) -> tuple[str, ...]:
    """The output models to assess for a source's ``arb_filter`` setting.

    An unknown or absent filter (a source that does not say how it reconstructs) gets both
    models, and the check keeps the worse figure of the two.
    """
    return RECONSTRUCTIONS.get(arb_filter or "", (HOLD, BAND_LIMITED))


def output_oversampling(sample_rate: float, reconstruction: str, suspension_hz: float) -> int:
    """Points per source sample at which ``reconstruction`` of the output is modelled.

    Parameters
    ----------
    sample_rate
        Source (arb) sample rate, Sa/s.
    reconstruction
        :data:`HOLD` or :data:`BAND_LIMITED`.
    suspension_hz
        Suspension resonance of the shaker, Hz: the model rate is at least
        :data:`STROKE_SAMPLES_PER_PERIOD` times it.
    """
    needed = math.ceil(STROKE_SAMPLES_PER_PERIOD * suspension_hz / sample_rate - 1e-9)
    return min(max(needed, OVERSAMPLING if reconstruction == BAND_LIMITED else 1, 1),
               MAX_OVERSAMPLING)


def lowest_source_rate(suspension_hz: float) -> float:
    """Lowest source sample rate, Sa/s, whose output the shaker model can follow at
    :data:`STROKE_SAMPLES_PER_PERIOD` points per suspension period (``suspension_hz``, Hz)."""
    return STROKE_SAMPLES_PER_PERIOD * suspension_hz / MAX_OVERSAMPLING


def source_output(waveform: np.ndarray, factor: int, reconstruction: str,
                  edges: bool = False) -> Iterator[np.ndarray]:
    """The source output, V, at ``factor`` points per sample of ``waveform`` (V), in blocks.

    :data:`HOLD` repeats each sample; :data:`BAND_LIMITED` interpolates through a windowed-sinc
    filter cut off at half the source rate (that of ``scipy.signal.resample_poly``, as the
    simulated source does, computed by :func:`fsi_lab.lti.interpolate`). The output spans the
    waveform, from its first sample on, to its last (what the source rests at afterwards is
    :func:`output_stroke_mm`'s concern); with ``edges`` it also includes the reconstruction's
    ringing before the first and after the last sample, for its peak.
    """
    n, step = waveform.size, max(1, BLOCK // factor)
    if reconstruction == HOLD:
        for start in range(0, n, step):
            yield np.repeat(waveform[start:start + step], factor)
        return
    first, last = (-CONTEXT, n + CONTEXT) if edges else (0, n)
    for start in range(first, last, step):
        stop = min(start + step, last)
        # waveform samples start - CONTEXT .. stop + CONTEXT (zero outside): the block and
        # its context
        lo, hi = start - CONTEXT, stop + CONTEXT
        segment = np.concatenate([np.zeros(max(0, -lo)), waveform[max(lo, 0):min(hi, n)],
                                  np.zeros(max(0, hi - n))])
        out = interpolate(segment, factor)
        yield out[CONTEXT * factor:(CONTEXT + stop - start) * factor]


def output_peak_v(waveform: np.ndarray, sample_rate: float, reconstruction: str,
                  suspension_hz: float) -> float:
    """Upper bound of the absolute source output, V, for ``waveform`` (V) at ``sample_rate``
    (Sa/s) reconstructed as ``reconstruction``; a band-limited one includes
    :data:`BAND_LIMITED_MARGIN`."""
    if reconstruction == HOLD:
        return float(np.max(np.abs(waveform)))
    factor = output_oversampling(sample_rate, reconstruction, suspension_hz)
    peak = max(float(np.max(np.abs(block)))
               for block in source_output(waveform, factor, reconstruction, edges=True))
    return max(peak * BAND_LIMITED_MARGIN, float(np.max(np.abs(waveform))))


def output_stroke_mm(waveform: np.ndarray, sample_rate: float, reconstruction: str,
                     gain: float, shaker: dict) -> float:
    """Largest base displacement, mm, the ``[shaker]`` model predicts for the source output
    (``waveform`` in V at ``sample_rate`` Sa/s, reconstructed as ``reconstruction``) amplified
    by ``gain`` (V/V).

    After the waveform a source rests at 0 V, or at the waveform's first sample (a Keysight
    33500 in triggered burst mode idles at the first point): the worse of the two is kept.
    """
    # The shaker only needs STROKE_SAMPLES_PER_PERIOD points per period: at a source rate
    # above that the samples serve as they are (the filter's overshoot is far above its band),
    # and far above it they are averaged in groups (see stroke_model_input).
    rests = {0.0, float(waveform[0])} if waveform.size else {0.0}
    factor = output_oversampling(sample_rate, HOLD, shaker["suspension_hz"])
    if factor > 1:
        blocks, rate = source_output(waveform, factor, reconstruction), sample_rate * factor
        return max(stroke_of_blocks_mm(blocks, rate, gain, shaker, rest) for rest in rests)
    drive, rate = stroke_model_input(waveform, sample_rate, shaker["suspension_hz"])
    return max(stroke_of_blocks_mm([drive], rate, gain, shaker, rest) for rest in rests)


def stroke_model_input(waveform: np.ndarray, sample_rate: float,
                       suspension_hz: float) -> tuple[np.ndarray, float]:
    """The held source output (``waveform`` in V at ``sample_rate`` Sa/s) at the rate the
    shaker model runs at: itself, or, beyond :data:`MAX_STROKE_SAMPLES_PER_PERIOD` samples per
    suspension period (``suspension_hz``, Hz), its averages over groups of samples, which keep
    each group's area (what moves the armature) at :data:`DECIMATED_SAMPLES_PER_PERIOD` points
    per period. The model's discrete filter loses its precision at millions of samples per
    period (it would predict no stroke at all), and its tail would not fit in memory.

    Returns
    -------
    drive, rate
        Volts, and their rate in Sa/s.
    """
    if sample_rate <= MAX_STROKE_SAMPLES_PER_PERIOD * suspension_hz:
        return waveform, sample_rate
    group = int(sample_rate // (DECIMATED_SAMPLES_PER_PERIOD * suspension_hz))
    starts = np.arange(0, waveform.size, group)
    sums = np.add.reduceat(waveform, starts) if waveform.size else waveform
    counts = np.diff(np.append(starts, waveform.size))
    return sums / counts, sample_rate / group


def assess(waveform: np.ndarray, sample_rate: float, gain: float, safety: dict,
           shaker: dict, arb_filter: str | None = None) -> SafetyReport:
    """Compare a drive waveform and amplifier gain with the limits.

    Parameters
    ----------
    waveform
        Source voltage samples, V.
    sample_rate
        Rate the source plays ``waveform`` at, Sa/s.
    gain
        Amplifier gain the run will set, V/V.
    safety
        The profile's ``[safety]`` values (max_drive_v, max_gain, max_stroke_mm).
    shaker
        The profile's ``[shaker]`` model, used to predict the stroke.
    arb_filter
        How the source reconstructs its output: ``"off"`` (sample and hold), ``"normal"`` or
        ``"step"`` (band-limited); None (or another value) assesses both and keeps the worse.

    Returns
    -------
    SafetyReport
        The peak drive at the source output (V) and the predicted stroke (mm) of the worse
        reconstruction, and a problem for each exceeded limit.
    """
    waveform = np.asarray(waveform, dtype=float).ravel()
    problems = []
    models = reconstructions_of(arb_filter)
    if not np.all(np.isfinite(waveform)):
        problems.append("the excitation waveform contains NaN or infinite samples")
        peak = stroke = float("inf")
    elif waveform.size == 0:
        peak = stroke = 0.0
    else:
        peak = max(output_peak_v(waveform, sample_rate, m, shaker["suspension_hz"])
                   for m in models)
        stroke = max(output_stroke_mm(waveform, sample_rate, m, gain, shaker) for m in models)
    if sample_rate < lowest_source_rate(shaker["suspension_hz"]):
        problems.append(
            f"source sample rate {sample_rate:g} Sa/s is too low for the shaker model to follow "
            f"its output; expected at least {lowest_source_rate(shaker['suspension_hz']):.3g} "
            "Sa/s: raise bench.source.sample_rate (or run.sample_rate when it is unset)"
        )
    if peak > safety["max_drive_v"]:
        problems.append(_drive_problem(peak, waveform, safety["max_drive_v"], models))
    if gain > safety["max_gain"]:
        problems.append(
            f"amplifier gain {gain:g} exceeds safety.max_gain = {safety['max_gain']:g}; "
            "lower bench.amplifier.gain"
        )
    if stroke > safety["max_stroke_mm"] and np.isfinite(stroke):
        problems.append(
            f"predicted stroke {stroke:.3g} mm exceeds safety.max_stroke_mm = "
            f"{safety['max_stroke_mm']:g} mm (shaker model: {shaker['mm_per_volt']:g} mm/V, "
            f"{shaker['suspension_hz']:g} Hz; source output modelled as "
            f"{' and as '.join(models)}{', the worse kept' if len(models) > 1 else ''}); "
            "lower the amplitude or the gain"
        )
    return SafetyReport(peak, safety["max_drive_v"], gain, safety["max_gain"], stroke,
                        safety["max_stroke_mm"], tuple(problems))


def _drive_problem(peak: float, waveform: np.ndarray, limit: float,
                   models: tuple[str, ...]) -> str:
    """The message for a peak drive beyond ``limit``, saying when it is the reconstruction's
    overshoot rather than the samples that exceeds it."""
    text = f"peak drive {peak:.4g} V exceeds safety.max_drive_v = {limit:g} V"
    samples = float(np.max(np.abs(waveform))) if np.all(np.isfinite(waveform)) else peak
    if BAND_LIMITED in models and samples < peak:
        text += (f" (the samples peak at {samples:.4g} V; the source's band-limited "
                 "reconstruction (arb_filter 'normal' or 'step') overshoots them near fast "
                 f"edges, bound with a {BAND_LIMITED_MARGIN - 1:.0%} margin)")
    return text + "; lower the excitation amplitude or raise the limit"


def require_safe(report: SafetyReport, where: str) -> None:
    """Raise SafetyError listing every exceeded limit; ``where`` names the profile."""
    if not report.ok:
        raise SafetyError(f"{where}: refused before anything was sent: "
                          + "; ".join(report.problems))
