"""Datasets picked out of a run's results: per-component rows, summary series, time axes, the
chain, and the columns of the tables of identified values."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.chain import default_chain
from fsi_lab.errors import FsiLabError
from fsi_lab.gui.results import PluginResult, RunResults
from fsi_lab.presentation import SummaryColumn
from fsi_lab.profile import parse_profile
from fsi_lab.registry import Registry
from fsi_lab.summary import claimed_keys, plain_values


def rows(array: np.ndarray | None) -> list[np.ndarray]:
    """A 2-D dataset as its rows (the plugins store one row per component, however few
    points a row holds), a 1-D one as a single row."""
    if array is None:
        return []
    array = np.asarray(array)
    if array.ndim == 1:
        return [array]
    if array.ndim == 2:
        return list(array)
    return []


def per_component(result: PluginResult | None, name: str) -> list[np.ndarray]:
    """Per-component arrays of the dataset ``name``: the rows of a 2-D dataset (the plugins
    store one row per component), a 1-D one as a single row; none when it is missing."""
    if result is None:
        return []
    return [np.asarray(r, dtype=float) for r in rows(result.get(name))]


def finite_pairs(pairs) -> list[tuple[np.ndarray, np.ndarray]]:
    """Matching ``(x, y)`` rows without their NaN padding; empty rows are dropped."""
    out = []
    for x, y in pairs:
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if x.size != y.size:
            continue
        keep = np.isfinite(x) & np.isfinite(y)
        if keep.any():
            out.append((x[keep], y[keep]))
    return out


def summary_series(results: RunResults, channel: str, section: str, x: str, y: str
                   ) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(x, y)`` pairs per component from the summary's ``components[i][section]``."""
    series = []
    for component in results.components(channel):
        block = component.get(section)
        if not isinstance(block, dict):
            continue
        xs, ys = block.get(x), block.get(y)
        if isinstance(xs, list) and isinstance(ys, list) and xs and len(xs) == len(ys):
            series.append((np.asarray([np.nan if v is None else v for v in xs], dtype=float),
                           np.asarray([np.nan if v is None else v for v in ys], dtype=float)))
    return finite_pairs(series)


def time_axis(results: RunResults, channel: str, result: PluginResult | None, n: int
              ) -> np.ndarray:
    """Sample times of a dataset of ``n`` samples of ``result`` that stores none of its own:
    the channel's sample times from where the analysis started (its ``start_s`` attribute),
    every ``result.stride``-th of them."""
    data = results.channels.get(channel)
    if data is not None and data.sample_rate > 0:
        stride = result.stride if result is not None else 1
        return origin(results, channel, result) + np.arange(n) * (stride / data.sample_rate)
    return np.arange(n, dtype=float)


def channel_t0(results: RunResults, channel: str) -> float:
    """Time (s, on the run's clock) of the channel's first sample; 0 for an unknown channel."""
    data = results.channels.get(channel)
    return float(data.t0) if data is not None else 0.0


def origin(results: RunResults, channel: str, result: PluginResult | None = None) -> float:
    """Time (s, on the run's clock) of sample 0 of ``result``'s datasets: the channel's t0 plus
    the start the analysis chose (its ``start_s`` attribute), when it has one."""
    t0 = channel_t0(results, channel)
    start = result.scalar("start_s") if result is not None else None
    if isinstance(start, (int, float)):
        return t0 + float(start)
    return t0


def format_ci(value: Any, digits: int = 4) -> str:
    """A 95 % interval ``[low, high]`` as text (``digits`` significant digits); anything else as
    it is (None as nothing)."""
    if isinstance(value, (list, tuple)) and len(value) == 2:
        return f"[{value[0]:.{digits}g}, {value[1]:.{digits}g}]"
    return "" if value is None else str(value)


def chain_of(results: RunResults, registry: Registry) -> tuple[dict[str, Any], dict[str, dict]]:
    """The run's ``[analysis]`` values (chain, channels, reference) and the parameters its
    plugins last ran with."""
    params: dict[str, dict] = {}
    analysis: dict[str, Any] = {"chain": [], "channels": [], "reference": None}
    try:
        profile = parse_profile(results.profile_text, f"{results.path}:/profile", registry,
                                sections=("analysis", "specimen"))
        analysis = dict(profile.analysis)
        params = {k: dict(v) for k, v in profile.analysis_params.items()}
    except FsiLabError:
        pass
    chain = list(analysis["chain"])
    if not results.profile_text.strip() and not chain:
        chain = default_chain(registry)
    for groups in results.analysis.values():
        for plugin, result in groups.items():
            if plugin not in chain and plugin in registry.descriptors["analysis"]:
                chain.append(plugin)
            if result.params:
                params.setdefault(plugin, {}).update(result.params)
    analysis["chain"] = chain
    return analysis, params


#: The first column of the tables of identified values: each component's frequency.
FREQUENCY_COLUMN = SummaryColumn("frequency_hz", "frequency (Hz)", "frequency_hz", order=0)


def value_columns(results: RunResults, channels: list[str], registry: Registry
                  ) -> list[SummaryColumn]:
    """Columns of a table of the identified values of ``channels`` (one row per component):
    the frequency, the columns the plugins register (``fsi_lab_addviews``), then a column for
    each plain value of the summary's components that no plugin shows in its own way; only
    those with a value in some component.

    Parameters
    ----------
    results
        The run.
    channels
        Analysed channels of the run.
    registry
        Loaded plugins.
    """
    columns = [FREQUENCY_COLUMN] + sorted(registry.views().columns, key=lambda c: c.order)
    known = {c.key for c in columns} | {c.interval for c in columns if c.interval}
    generic: dict[str, SummaryColumn] = {}
    entries = []
    for channel in channels:
        info = (results.summary or {}).get("channels", {}).get(channel, {})
        for component in results.components(channel):
            entries.append(component)
            claimed = claimed_keys(registry, channel, info, component)
            for key, _ in plain_values(component, claimed):
                if key not in known and key not in generic:
                    generic[key] = SummaryColumn(key, key, key, order=500)
    columns += list(generic.values())
    return [c for c in columns if any(c.value(e) is not None for e in entries)]
