"""Axis labels that say which amplitude a figure shows: the displacement measured at the
measuring point (backbone, damping) or the modal amplitude q the C_q coefficients belong to.

The analysis views name one run's amplitude; the runs browser and the Sequence tab name the
amplitude of several runs at once (:func:`compared_amplitude`, :func:`compared_cq_amplitude`,
:func:`aggregate_amplitude`): what the runs share, in words that hold for each of them."""

from __future__ import annotations

import tomllib
from typing import Any

from fsi_lab.gui.results import RunResults


def measuring_point(results: RunResults) -> float | None:
    """``[specimen] measurement_point`` of the run's profile (m), or None when it has none."""
    try:
        specimen = tomllib.loads(results.profile_text).get("specimen", {})
        value = float(specimen["measurement_point"])
    except (tomllib.TOMLDecodeError, KeyError, TypeError, ValueError, AttributeError):
        return None
    return value


def measured_at(point: float | None, quantity: str = "displacement") -> str:
    """"displacement amplitude at x = 0.08 m", or "... at the measuring point" when
    ``point`` is None."""
    where = f"x = {point:g} m" if point is not None else "the measuring point"
    return f"{quantity} amplitude at {where}"


def measured_amplitude(results: RunResults, quantity: str = "displacement") -> str:
    """"displacement amplitude at x = 0.08 m" (the measuring point of the run's specimen)."""
    return measured_at(measuring_point(results), quantity)


#: The modal amplitude of equivalent-damping's modal convention (Eq. 15, int W^2 = L).
MODAL_AMPLITUDE = "modal amplitude q = w(x_m) / W(x_m)"


def convention_kinds(convention: str | None) -> set[str]:
    """The kinds of amplitude (``modal``, ``measured``) an ``amplitude_convention`` names:
    equivalent-damping's ("component 0: modal: q_2 = ...; component 1: ...", or a single
    convention) or an aggregated mode's; empty for none."""
    text = str(convention or "")
    parts = [p.split(":", 1)[1] if p.strip().startswith("component") else p
             for p in text.split(";")] if text else []
    return {("modal" if p.strip().startswith("modal") else "measured") for p in parts}


def _amplitude_of(kinds: set[str], point: float | None) -> str:
    if kinds == {"modal"}:
        return MODAL_AMPLITUDE
    if kinds == {"modal", "measured"}:
        return f"{MODAL_AMPLITUDE} or measured amplitude (per component: see tooltip)"
    return measured_at(point)


def cq_amplitude(results: RunResults, convention: str | None) -> str:
    """The C_q figure's amplitude axis, from equivalent-damping's ``amplitude_convention``:
    modal, measured, or both (components of either kind)."""
    return _amplitude_of(convention_kinds(convention), measuring_point(results))


def _shared_point(runs: list[tuple[RunResults, str]]) -> float | None:
    """The runs' measuring point when they all have the same one, else None."""
    points = {measuring_point(results) for results, _ in runs}
    return points.pop() if len(points) == 1 else None


def compared_amplitude(runs: list[tuple[RunResults, str]]) -> str:
    """The displacement amplitude axis of backbones and damping curves compared across
    ``runs`` (each a run and the channel compared): at their common measuring point, or at
    each run's own."""
    return measured_at(_shared_point(runs))


def compared_cq_amplitude(runs: list[tuple[RunResults, str]]) -> str:
    """The amplitude axis of C_q compared across ``runs`` (each a run and the channel
    compared), from each run's equivalent-damping ``amplitude_convention`` (runs without
    the analysis draw no C_q and are not counted)."""
    kinds: set[str] = set()
    drawn = []
    for results, channel in runs:
        result = results.result(channel, "equivalent-damping")
        if result is not None and result.ok:
            kinds |= convention_kinds(result.scalar("amplitude_convention")) or {"measured"}
            drawn.append((results, channel))
    if kinds == {"modal", "measured"}:
        return f"{MODAL_AMPLITUDE} or measured amplitude (per run)"
    return _amplitude_of(kinds, _shared_point(drawn))


def aggregate_amplitude(mode: dict[str, Any]) -> str:
    """The amplitude axis of an aggregated mode's curves (:mod:`fsi_lab.aggregate`: every run
    on the axis of its ``amplitude_convention``, modal or as measured)."""
    return _amplitude_of(convention_kinds(mode.get("amplitude_convention")), None)
