"""The safety check every run passes before anything reaches an instrument."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fsi_lab.errors import SafetyError
from fsi_lab.shaker import predicted_stroke_mm


@dataclass(frozen=True)
class SafetyReport:
    """Figures compared with the profile's ``[safety]`` limits, and the verdict."""

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


def assess(waveform: np.ndarray, sample_rate: float, gain: float, safety: dict,
           shaker: dict) -> SafetyReport:
    """Compare a drive waveform and amplifier gain with the limits.

    Parameters
    ----------
    waveform
        Source voltage, V.
    sample_rate
        Rate of ``waveform``, Hz.
    gain
        Amplifier gain the run will set, V/V.
    safety
        The profile's ``[safety]`` values (max_drive_v, max_gain, max_stroke_mm).
    shaker
        The profile's ``[shaker]`` model, used to predict the stroke.
    """
    waveform = np.asarray(waveform, dtype=float)
    problems = []
    if not np.all(np.isfinite(waveform)):
        problems.append("the excitation waveform contains NaN or infinite samples")
        peak = float("inf")
        stroke = float("inf")
    else:
        peak = float(np.max(np.abs(waveform))) if waveform.size else 0.0
        stroke = predicted_stroke_mm(waveform, sample_rate, gain, shaker)
    if peak > safety["max_drive_v"]:
        problems.append(
            f"peak drive {peak:.4g} V exceeds safety.max_drive_v = {safety['max_drive_v']:g} V; "
            "lower the excitation amplitude or raise the limit"
        )
    if gain > safety["max_gain"]:
        problems.append(
            f"amplifier gain {gain:g} exceeds safety.max_gain = {safety['max_gain']:g}; "
            "lower bench.amplifier.gain"
        )
    if stroke > safety["max_stroke_mm"] and np.isfinite(stroke):
        problems.append(
            f"predicted stroke {stroke:.3g} mm exceeds safety.max_stroke_mm = "
            f"{safety['max_stroke_mm']:g} mm (shaker model: {shaker['mm_per_volt']:g} mm/V, "
            f"{shaker['suspension_hz']:g} Hz); lower the amplitude or the gain"
        )
    return SafetyReport(peak, safety["max_drive_v"], gain, safety["max_gain"], stroke,
                        safety["max_stroke_mm"], tuple(problems))


def require_safe(report: SafetyReport, where: str) -> None:
    """Raise SafetyError listing every exceeded limit; ``where`` names the profile."""
    if not report.ok:
        raise SafetyError(f"{where}: refused before anything was sent: " + "; ".join(report.problems))
