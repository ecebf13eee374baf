"""Axis labels that say which amplitude a figure shows: the displacement measured at the
measuring point (backbone, damping) or the modal amplitude q the C_q coefficients belong to."""

from __future__ import annotations

import tomllib

from fsi_lab.gui.results import RunResults


def measuring_point(results: RunResults) -> float | None:
    """``[specimen] measurement_point`` of the run's profile (m), or None when it has none."""
    try:
        specimen = tomllib.loads(results.profile_text).get("specimen", {})
        value = float(specimen["measurement_point"])
    except (tomllib.TOMLDecodeError, KeyError, TypeError, ValueError, AttributeError):
        return None
    return value


def measured_amplitude(results: RunResults, quantity: str = "displacement") -> str:
    """"displacement amplitude at x = 0.08 m" (the measuring point of the run's specimen)."""
    point = measuring_point(results)
    where = f"x = {point:g} m" if point is not None else "the measuring point"
    return f"{quantity} amplitude at {where}"


#: The modal amplitude of equivalent-damping's modal convention (Eq. 15, int W^2 = L).
MODAL_AMPLITUDE = "modal amplitude q = w(x_m) / W(x_m)"


def cq_amplitude(results: RunResults, convention: str | None) -> str:
    """The C_q figure's amplitude axis, from equivalent-damping's ``amplitude_convention``
    ("component 0: modal: q_2 = ...; component 1: ..." or a single convention): modal,
    measured, or both (components of either kind)."""
    text = str(convention or "")
    parts = [p.split(":", 1)[1] if p.strip().startswith("component") else p
             for p in text.split(";")] if text else []
    kinds = {("modal" if p.strip().startswith("modal") else "measured") for p in parts}
    if kinds == {"modal"}:
        return MODAL_AMPLITUDE
    if kinds == {"modal", "measured"}:
        return f"{MODAL_AMPLITUDE} or measured amplitude (per component: see tooltip)"
    return measured_amplitude(results)
