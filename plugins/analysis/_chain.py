"""What the analysis plugins share: components of a channel, errors, JSON helpers.

Conventions of the chain (documented for plugin users in each plugin's help):

- Components are numbered from 0 (``"index"`` in the summary, row of the 2-D HVD datasets).
  When ``hvd`` ran earlier on the channel its components are analysed one by one; otherwise
  the whole channel is component 0.
- Amplitudes in summaries are in metres of displacement (``integrate`` output when it ran,
  else the channel integrated on the fly, or the channel itself if it is a displacement).
- A failure on one component is recorded (``summary`` entry ``"error"`` and attribute
  ``component_<k>_error``) and the others go on; the plugin fails only if every component does.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from fsi_lab.contract import AnalysisContext
from fsi_lab.errors import AnalysisError

#: Units of the displacement, velocity and acceleration quantities.
SI_UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}


@dataclass
class Component:
    """One component of a channel.

    Attributes
    ----------
    index
        0-based component number.
    signal
        Samples, in ``unit``.
    quantity
        ``displacement``, ``velocity``, ``acceleration`` or ``voltage``.
    unit
        Unit of ``signal``.
    sample_rate
        Hz.
    edge_mask
        True where samples are not trusted (HVD record ends), or None.
    """

    index: int
    signal: np.ndarray
    quantity: str
    unit: str
    sample_rate: float
    edge_mask: np.ndarray | None = None


@dataclass
class ComponentSignals:
    """Signals per component handed down the chain (``integrate`` values)."""

    quantity: str
    unit: str
    sample_rate: float
    signals: dict[int, np.ndarray]
    edge_masks: dict[int, np.ndarray | None]


def where(plugin: str, context: AnalysisContext) -> str:
    return f"{plugin} on channel {context.channel.name!r}"


@contextmanager
def guarded(plugin: str, context: AnalysisContext) -> Iterator[None]:
    """Prefix AnalysisErrors with the plugin and channel names."""
    try:
        yield
    except AnalysisError as exc:
        text = str(exc)
        prefix = where(plugin, context)
        raise AnalysisError(text if text.startswith(prefix) else f"{prefix}: {text}") from None


def components(context: AnalysisContext) -> list[Component]:
    """The channel's components: HVD's if it ran earlier in the chain, else the channel."""
    ch = context.channel
    hvd = context.results.get("hvd")
    if hvd is not None and hvd.values is not None:
        res = hvd.values
        return [Component(k, res.components[k], ch.quantity, ch.unit, res.sample_rate,
                          res.edge_mask[k]) for k in range(res.components.shape[0])]
    return [Component(0, np.asarray(ch.data, dtype=np.float64), ch.quantity, ch.unit,
                      float(ch.sample_rate), None)]


def displacement_components(context: AnalysisContext, plugin: str) -> list[Component]:
    """Components as displacement (m): from ``integrate`` if it ran, else integrated here."""
    from fsi_lab.plugins.analysis.integrate import integrate

    integ = context.results.get("integrate")
    if integ is not None and isinstance(integ.values, ComponentSignals) \
            and integ.values.quantity == "displacement":
        v = integ.values
        return [Component(k, sig, "displacement", v.unit, v.sample_rate, v.edge_masks.get(k))
                for k, sig in sorted(v.signals.items())]
    comps = components(context)
    quantity = context.channel.quantity
    if quantity == "displacement":
        return comps
    if quantity not in ("velocity", "acceleration"):
        raise AnalysisError(
            f"{where(plugin, context)}: the channel measures {quantity!r} ({context.channel.unit})"
            "; displacement amplitudes need a calibrated displacement, velocity or acceleration "
            "channel")
    order = 1 if quantity == "velocity" else 2
    out = []
    for c in comps:
        out.append(Component(c.index, integrate(c.signal, c.sample_rate, order=order),
                             "displacement", "m", c.sample_rate, c.edge_mask))
    return out


def velocity_components(context: AnalysisContext) -> list[Component] | None:
    """Components as velocity (m/s), or None when the channel is not a velocity or an
    acceleration (a displacement is not differentiated: it would amplify noise)."""
    from fsi_lab.plugins.analysis.integrate import integrate

    quantity = context.channel.quantity
    if quantity == "velocity":
        return components(context)
    integ = context.results.get("integrate")
    if integ is not None and isinstance(integ.values, ComponentSignals) \
            and integ.values.quantity == "velocity":
        v = integ.values
        return [Component(k, sig, "velocity", v.unit, v.sample_rate, v.edge_masks.get(k))
                for k, sig in sorted(v.signals.items())]
    if quantity == "acceleration":
        return [Component(c.index, integrate(c.signal, c.sample_rate, order=1), "velocity",
                          "m/s", c.sample_rate, c.edge_mask) for c in components(context)]
    return None


def per_component(plugin: str, context: AnalysisContext, comps: list[Component],
                  work: Callable[[Component], Any]) -> tuple[dict[int, Any], dict[int, str]]:
    """Run ``work`` on each component; collect results and per-component error messages.

    Raises AnalysisError (naming plugin, channel and every component's reason) when all fail.
    """
    done: dict[int, Any] = {}
    errors: dict[int, str] = {}
    for c in comps:
        try:
            done[c.index] = work(c)
        except AnalysisError as exc:
            errors[c.index] = str(exc)
    if not done:
        reasons = "; ".join(f"component {k}: {m}" for k, m in errors.items())
        raise AnalysisError(f"{where(plugin, context)}: {reasons}")
    return done, errors


def error_entries(errors: dict[int, str], key: str) -> tuple[list[dict], dict[str, str]]:
    """Summary entries and attributes recording per-component failures."""
    entries = [{"index": k, key: {"error": m}} for k, m in errors.items()]
    attrs = {f"component_{k}_error": m for k, m in errors.items()}
    return entries, attrs


def trusted_times(times: np.ndarray, comp: Component, period: float) -> np.ndarray:
    """Boolean mask of ``times`` (s) not in the component's untrusted edge and at least one
    ``period`` (s) from either record end."""
    n = comp.signal.size
    fs = comp.sample_rate
    ok = (times >= period) & (times <= (n - 1) / fs - period)
    if comp.edge_mask is not None and comp.edge_mask.any():
        idx = np.clip(np.rint(times * fs).astype(np.int64), 0, n - 1)
        ok &= ~comp.edge_mask[idx]
    return ok


def jsonable(values: Any) -> Any:
    """Python floats / lists with NaN and inf replaced by None."""
    if isinstance(values, np.ndarray):
        values = values.tolist()
    if isinstance(values, (list, tuple)):
        return [jsonable(v) for v in values]
    if isinstance(values, (np.floating, float)):
        v = float(values)
        return v if math.isfinite(v) else None
    if isinstance(values, np.integer):
        return int(values)
    return values


def stack_rows(rows: dict[int, np.ndarray], count: int) -> np.ndarray:
    """2-D array (count x max length) of 1-D rows by index, padded with NaN."""
    width = max((r.size for r in rows.values()), default=0)
    out = np.full((count, width), np.nan)
    for k, r in rows.items():
        out[k, :r.size] = r
    return out
