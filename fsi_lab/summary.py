"""The analysis summary as text (``fsi-lab run``, ``analyze``, ``show``) and its plain values.

The core shows what the summary's layout defines (docs/json-output.md): each channel, its
``notes``, ``warnings`` and ``errors``, its components with their ``index``, ``frequency_hz``
(and its ``frequency_ci95_hz``), ``warnings`` and the per-component errors of any analysis, and
the ``warnings`` an analysis keeps under its own key (``frf``'s at channel level). Everything
else is the plugins': each says what it shows of its keys through the
``fsi_lab_summary_lines`` hook (:class:`fsi_lab.presentation.SummaryText`), and the values of
the keys no plugin claims are shown as ``key: value`` lines when they are numbers, strings or
tables of them (:func:`plain_values`), so that a third-party analysis's scalar results are in
the text summary without any code that knows it.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from fsi_lab.contract import failed_provider, for_want_of
from fsi_lab.errors import FsiLabError
from fsi_lab.presentation import SummaryText

#: Keys of a channel's summary the core shows itself.
CHANNEL_KEYS = ("components", "notes", "errors", "warnings")
#: Keys of a component entry the core shows itself.
COMPONENT_KEYS = ("index", "frequency_hz", "frequency_ci95_hz", "warnings")


def json_safe(obj: Any) -> Any:
    """``obj`` with NaN and infinities (not valid JSON) replaced by None: an undetermined
    standard error or an unbounded interval is stored and printed as null."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj


def _registry(registry):
    if registry is None:
        from fsi_lab.registry import load_registry

        registry = load_registry()
    return registry


def warnings_of(entry: dict[str, Any]) -> list[tuple[str, str]]:
    """Every warning of a channel's or a component's summary as (key, sentence): its own
    ``warnings`` (key "") and those of each analysis that keeps them under its key (``frf``'s
    at channel level, for one); a channel's components are not looked into."""
    found = [("", w) for w in entry.get("warnings", [])]
    for key, value in entry.items():
        if isinstance(value, dict):
            found.extend((key, w) for w in value.get("warnings", []))
    return found


def interval_words(bounds: Any) -> str:
    """``(95 %: 0.6429 to 0.654)``: a 95 % interval with four significant digits, or nothing
    when ``bounds`` does not hold two numbers."""
    if not isinstance(bounds, (list, tuple)) or len(bounds) != 2 or None in bounds:
        return ""
    return f"(95 %: {bounds[0]:.4g} to {bounds[1]:.4g})"


def coefficient_words(entry: dict[str, Any]) -> str:
    """``C_i = 0.6509 kg/(m s) (95 %: 0.65 to 0.6517), C_f = 32.69 kg/m^2 (95 %: ...)``: the
    damping coefficients of a JSON entry holding ``c_i``, ``c_f`` and, where known, their
    ``c_i_ci95`` and ``c_f_ci95``."""
    return ", ".join(
        " ".join(part for part in (f"{label} = {entry[key]:.4g} {unit}",
                                   interval_words(entry.get(f"{key}_ci95"))) if part)
        for key, label, unit in (("c_i", "C_i", "kg/(m s)"), ("c_f", "C_f", "kg/m^2")))


def fluid_power_words(power: float, ci95: Any = None) -> str:
    """``, fluid term as |v|^2.01 (95 %: 1.94 to 2.08)``: the power of the velocity a fluid
    term grows with (2 for the quadratic law), and its interval when ``ci95`` holds two
    numbers."""
    text = f", fluid term as |v|^{power:.2f}"
    if isinstance(ci95, (list, tuple)) and len(ci95) == 2 and None not in ci95:
        text += f" (95 %: {ci95[0]:.2f} to {ci95[1]:.2f})"
    return text


def format_value(value: Any) -> str:
    """A plain value as text: numbers with four significant digits, booleans and strings as
    they are."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return str(value)
    if isinstance(value, numbers.Integral):
        return str(int(value))
    return f"{float(value):.4g}"


def _plain(value: Any) -> bool:
    return value is not None and (isinstance(value, (str, bool, numbers.Real)))


def plain_values(entry: dict[str, Any], skip: set[str] | tuple[str, ...]) -> list[tuple[str, Any]]:
    """The plain values of a summary entry outside ``skip``: ``(key, value)`` for a number,
    string or boolean, and ``(key.sub, value)`` for those of a table one level down (its
    ``error`` and ``warnings`` left out: the core shows them)."""
    out = []
    for key, value in entry.items():
        if key in skip:
            continue
        if _plain(value):
            out.append((key, value))
        elif isinstance(value, dict):
            out.extend((f"{key}.{sub}", item) for sub, item in value.items()
                       if sub not in ("error", "warnings") and _plain(item))
    return out


def _texts(registry, channel: str, info: dict[str, Any], component: dict[str, Any] | None
           ) -> tuple[list[SummaryText], set[str]]:
    texts = registry.summary_texts(channel, info, component)
    claimed = {key for text in texts for key in text.keys}
    return texts, claimed


def claimed_keys(registry, channel: str, info: dict[str, Any],
                 component: dict[str, Any] | None = None) -> set[str]:
    """Keys of a channel's summary (or of one of its components) that the core or a plugin
    shows in its own way (the others are shown as plain values)."""
    _, claimed = _texts(registry, channel, info, component)
    return claimed | set(CHANNEL_KEYS if component is None else COMPONENT_KEYS)


def format_summary(summary: dict[str, Any], registry=None) -> str:
    """The analysis summary as a few readable lines.

    Parameters
    ----------
    summary
        The ``fsi-lab analyze --json`` object (its ``channels``).
    registry
        The loaded plugins (:func:`fsi_lab.registry.load_registry`, loaded when None), whose
        ``fsi_lab_summary_lines`` hooks show their keys.
    """
    registry = _registry(registry)
    lines = []
    for channel, info in summary.get("channels", {}).items():
        texts, claimed = _texts(registry, channel, info, None)
        lines.append(f"channel {channel}" + "".join(t.inline for t in texts))
        for note in info.get("notes", []):
            lines.append(f"  note: {note}")
        lines.extend(f"  {key + ' ' if key else ''}warning: {w}" for key, w in warnings_of(info))
        lines.extend(f"  {line}" for text in texts for line in text.lines)
        lines.extend(f"  {key}: {format_value(value)}"
                     for key, value in plain_values(info, claimed | set(CHANNEL_KEYS)))
        for component in info.get("components", []):
            lines.extend(_component_lines(registry, channel, info, component))
        # An analysis that needed a failed one's result: named once, after that failure.
        said: set[str] = set()
        waiting: dict[str, list[str]] = {}
        for error in info.get("errors", []):
            provider = failed_provider(error["message"])
            if error.get("plugin") is None:     # the channel itself, before any analysis
                lines.append(f"  not analysed: {error['message']}")
            elif provider in said:
                waiting.setdefault(provider, []).append(error["plugin"])
            else:
                lines.append(f"  failed {error['plugin']}: {error['message']}")
                said.add(error["plugin"])
        lines.extend(f"  {for_want_of(provider)}: {', '.join(names)}"
                     for provider, names in waiting.items())
    return "\n".join(lines)


def _component_lines(registry, channel: str, info: dict[str, Any],
                     component: dict[str, Any]) -> list[str]:
    texts, claimed = _texts(registry, channel, info, component)
    text = f"  component {component['index']}"
    if component.get("frequency_hz") is not None:
        text += f" at {component['frequency_hz']:.3f} Hz"
        bounds = component.get("frequency_ci95_hz")
        if bounds and None not in bounds:
            text += f" (+-{0.5 * (bounds[1] - bounds[0]):.2g} Hz)"
    lines = [text + "".join(t.inline for t in texts)]
    lines.extend(f"    {key + ' ' if key else ''}warning: {w}"
                 for key, w in warnings_of(component))
    # Per-component errors (hvd's on a component that switches modes is carried by every
    # later analysis): each distinct message once.
    seen: list[str] = []
    for value in component.values():
        if isinstance(value, dict) and value.get("error") and value["error"] not in seen:
            seen.append(value["error"])
    lines.extend(f"    not analysed: {message}" for message in seen)
    lines.extend(f"    {line}" for t in texts for line in t.lines)
    lines.extend(f"    {key}: {format_value(value)}"
                 for key, value in plain_values(component, claimed | set(COMPONENT_KEYS)))
    return lines


def nothing_identified(summary: dict[str, Any], registry) -> str | None:
    """Why nothing in an analysed record was identified, or None: on every channel the analysis
    that provides its components (the decomposition into modes) was refused and none came out
    (a record of noise, or of no free decay), so the exit code says so (2: a signal the
    analysis cannot handle) although what could be computed was stored (unless the file held an
    earlier analysis that identified something: :func:`fsi_lab.batch.analyse_file` keeps that
    one). A channel missing from the run counts as refused."""
    reasons = []
    for name, info in (summary.get("channels") or {}).items():
        if info.get("components"):
            return None
        # (an error of no analysis: the channel itself is missing from the run)
        refused = [error for error in info.get("errors", [])
                   if error.get("plugin") is None
                   or provides(registry, error.get("plugin"), "components")]
        if not refused:
            return None
        reasons.append(f"channel {name}: {refused[0]['message']}")
    return "nothing was identified: " + "; ".join(reasons) if reasons else None


def uncalibrated(summary: dict[str, Any], quantities: dict[str, str]) -> str | None:
    """Why an analysed channel in volts is refused, or None: a channel whose samples are a
    sensor's volts (imported without ``--sensitivity``) gives frequencies, but the analyses
    that need the motion it measures (amplitudes, backbones, damping curves, C_i and C_f)
    fail on it, so the exit code says the input was not what they need (2), although what
    could be computed was stored. ``quantities`` holds each channel's quantity by name."""
    from fsi_lab.units import voltage_hint

    reasons = []
    for name, info in (summary.get("channels") or {}).items():
        failed = [error["plugin"] for error in info.get("errors", []) if error.get("plugin")]
        if quantities.get(name) == "voltage" and failed:
            reasons.append(f"channel {name} holds volts, not the motion its sensor measures: "
                           f"its frequencies are stored, but {', '.join(failed)} need that "
                           "motion")
    return "; ".join(reasons) + voltage_hint("voltage") if reasons else None


def provides(registry, analysis: Any, kind: str) -> bool:
    """Whether the installed analysis named ``analysis`` provides results of ``kind``."""
    try:
        return registry.get("analysis", analysis).provides == kind
    except FsiLabError:  # an analysis no longer installed provides nothing
        return False


def add_warnings(summary: dict[str, Any], warnings: list[str] | tuple[str, ...]) -> None:
    """Put ``warnings`` (about the whole record, e.g. a run that did not finish) first among
    the ``warnings`` of every channel of ``summary``, so that ``--strict`` counts them."""
    for info in (summary.get("channels") or {}).values():
        if warnings and isinstance(info, dict):
            info["warnings"] = [*warnings, *info.get("warnings", [])]
