"""A run file read for display: its attributes, channels and every ``/analysis`` group.

Reading happens on a worker thread. A missing, corrupt or foreign file raises
:class:`fsi_lab.errors.InputFileError` (the core's :func:`~fsi_lab.runfile.read_run` decides what a
run file is); a run file without analysis, or with some groups missing or failed, reads fine:
the views say "not computed" or show the failure message. A long record's per-sample results
are read every so many samples (at most :data:`DISPLAY_SAMPLES` along the record).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from fsi_lab.contract import ChannelData
from fsi_lab.errors import InputFileError
from fsi_lab.runfile import read_attrs, read_run

#: Samples along the record the views read of a long record's per-sample dataset (every
#: so many of them): they draw a few thousand points of it at a time anyway.
DISPLAY_SAMPLES = 1 << 20


@dataclass
class PluginResult:
    """``/analysis/<channel>/<plugin>``: status, scalar results, parameters and datasets."""

    channel: str
    plugin: str
    status: str
    error: str = ""
    attrs: dict[str, Any] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    datasets: dict[str, np.ndarray] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    #: the dataset each dataset is drawn against (its ``axis`` attribute), by name
    axes: dict[str, str] = field(default_factory=dict)
    #: samples of the channel between two samples of the per-sample datasets held here (a
    #: long record's are stored and read every so many samples)
    stride: int = 1

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def get(self, *names: str) -> np.ndarray | None:
        """The first of ``names`` that the group holds (datasets, then numeric attributes)."""
        for name in names:
            if name in self.datasets:
                return self.datasets[name]
        for name in names:
            value = self.attrs.get(name)
            if isinstance(value, (list, tuple)) and value and all(
                    isinstance(v, (int, float)) for v in value):
                return np.asarray(value, dtype=float)
        return None

    def scalar(self, *names: str) -> Any:
        for name in names:
            if name in self.attrs:
                return self.attrs[name]
        return None


@dataclass
class RunResults:
    """What the views show of one run file."""

    path: Path
    attrs: dict[str, Any]
    channels: dict[str, ChannelData]
    instruments: dict[str, dict[str, Any]]
    excitation: dict[str, Any] | None
    analysis: dict[str, dict[str, PluginResult]]
    summary: dict[str, Any] | None

    @property
    def name(self) -> str:
        return self.attrs.get("run_name") or self.path.name

    @property
    def exit_status(self) -> str:
        return str(self.attrs.get("exit_status", "unknown"))

    @property
    def profile_text(self) -> str:
        return self.attrs.get("profile", "") or ""

    def result(self, channel: str, plugin: str) -> PluginResult | None:
        return self.analysis.get(channel, {}).get(plugin)

    def analysed_channels(self) -> list[str]:
        return list(self.analysis)

    def components(self, channel: str) -> list[dict[str, Any]]:
        """The summary's component entries of ``channel`` (empty when there are none)."""
        if not self.summary:
            return []
        return list(self.summary.get("channels", {}).get(channel, {}).get("components", []))


def _read_group(channel: str, plugin: str, group: h5py.Group) -> PluginResult:
    attrs = read_attrs(group)
    status = str(attrs.pop("status", "ok"))
    error = str(attrs.pop("error", "") or "")
    attrs.pop("traceback", None)
    result = PluginResult(channel, plugin, status, error, attrs)
    if "params" in group and isinstance(group["params"], h5py.Group):
        result.params = read_attrs(group["params"])

    def visit(name: str, node: Any) -> None:
        if isinstance(node, h5py.Dataset) and not name.startswith("params"):
            try:
                stored = node.attrs.get("sample_stride")
                if stored is not None and node.ndim and node.shape[-1] > DISPLAY_SAMPLES:
                    step = -(-node.shape[-1] // DISPLAY_SAMPLES)
                    result.datasets[name] = node[..., ::step]
                    result.stride = int(stored) * step
                else:
                    result.datasets[name] = node[()]
                    if stored is not None:
                        result.stride = int(stored)
            except (OSError, ValueError, TypeError):
                return
            for attribute, into in (("units", result.units), ("axis", result.axes)):
                value = node.attrs.get(attribute)
                if value is not None:
                    into[name] = value.decode() if isinstance(value, bytes) else str(value)

    group.visititems(visit)
    return result


def load_results(path: str | Path) -> RunResults:
    """Read a run file for display (raises InputFileError for what is not a run file)."""
    path = Path(path)
    run = read_run(path)
    analysis: dict[str, dict[str, PluginResult]] = {}
    summary = None
    try:
        with h5py.File(path, "r") as handle:
            root = handle.get("analysis")
            if isinstance(root, h5py.Group):
                text = root.attrs.get("summary")
                if isinstance(text, bytes):
                    text = text.decode()
                if text:
                    try:
                        summary = json.loads(text)
                    except ValueError:
                        summary = None
                for channel, channel_group in root.items():
                    if not isinstance(channel_group, h5py.Group):
                        continue
                    for plugin, group in channel_group.items():
                        if isinstance(group, h5py.Group):
                            analysis.setdefault(channel, {})[plugin] = _read_group(
                                channel, plugin, group)
    except OSError as exc:
        raise InputFileError(f"{path}: the analysis cannot be read ({exc})") from None
    return RunResults(path, run.attrs, run.channels, run.instruments, run.excitation, analysis,
                      summary)
