"""Channels read from a run file when, and only as far as, they are used.

The analysis reads a run's channels through :class:`DatasetSource` (an ``h5py.Dataset`` of the
file, opened for each read, so that nothing of the record stays in memory between reads) and
:class:`LazyChannelData` (a :class:`~fsi_lab.contract.ChannelData` whose ``data`` is read from
its source on first use, once). Steps that need only part of a record, or one pass over it, read
through the source a chunk at a time (:func:`chunks`); a step that still needs the whole record
in memory asks for ``data``, which is counted (:func:`whole_reads`) and can be refused beyond a
size (:func:`whole_read_limit`): the list of those reads is what is left to make streaming
(docs/streaming-analysis.md).
"""

from __future__ import annotations

import contextlib
import math
import threading
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from fsi_lab.contract import ChannelData
from fsi_lab.errors import AnalysisError

#: Samples read at a time by :func:`chunks` (a multiple of the run file's chunk of 16384).
CHUNK = 1 << 20


class _SliceSource:
    """What every source shares: ``len``, ``read(start, stop)`` clipped to the source, and
    slicing like an array (steps of 1 only). A subclass sets ``length`` and ``label`` (for
    messages) and reads a slice already clipped and not empty in ``_read``."""

    length: int
    label: str

    def __len__(self) -> int:
        return self.length

    def read(self, start: int, stop: int) -> np.ndarray:
        """Samples ``[start, stop)`` (clipped to the source), float64."""
        start, stop = max(0, int(start)), min(self.length, int(stop))
        if stop <= start:
            return np.empty(0)
        return self._read(start, stop)

    def __getitem__(self, index: slice) -> np.ndarray:
        if not isinstance(index, slice) or index.step not in (None, 1):
            raise TypeError(f"{self.label}: a source is read by slices of step 1, not {index!r}")
        start, stop, _ = index.indices(self.length)
        return self.read(start, stop)


class DatasetSource(_SliceSource):
    """One 1-D dataset of a run file, read a slice at a time (as float64).

    Parameters
    ----------
    path
        The run file.
    name
        The dataset's path in it, e.g. ``"/channels/tip_velocity"``.
    length
        Samples of the dataset used, from its start (None: all; not more than it holds).

    Sliced like an array (``source[a:b]``, steps of 1 only), it reads that slice; ``len`` is
    ``length``.
    """

    def __init__(self, path: str | Path, name: str, length: int | None = None) -> None:
        self.path = Path(path)
        self.name = self.label = name
        if length is None:
            import h5py

            with h5py.File(self.path, "r") as handle:
                length = int(handle[name].shape[0])
        self.length = max(0, int(length))

    def _read(self, start: int, stop: int) -> np.ndarray:
        import h5py

        with h5py.File(self.path, "r") as handle:
            return np.asarray(handle[self.name][start:stop], dtype=np.float64)

    def head(self, length: int) -> DatasetSource:
        """The same dataset up to ``length`` samples."""
        return DatasetSource(self.path, self.name, max(0, min(int(length), self.length)))


class WindowSource(_SliceSource):
    """Samples ``[start, stop)`` of an array or a source, read by slices as a source (a
    segment of a long record: :mod:`fsi_lab.segmented`)."""

    def __init__(self, data: Any, start: int, stop: int) -> None:
        self.data, self.start = data, int(start)
        self.length = max(0, int(stop) - self.start)
        self.label = f"samples {self.start} to {self.start + self.length}"

    def _read(self, start: int, stop: int) -> np.ndarray:
        return np.asarray(self.data[self.start + start:self.start + stop], dtype=np.float64)

    def head(self, length: int) -> WindowSource:
        """The same window up to ``length`` samples."""
        return WindowSource(self.data, self.start, self.start + min(int(length), self.length))


def chunks(data: Any, size: int | None = None) -> Iterator[tuple[int, np.ndarray]]:
    """``(start, samples)`` of consecutive chunks of ``size`` samples (default :data:`CHUNK`)
    of ``data`` (an array or a source), float64."""
    n = int(len(data))
    size = int(size or CHUNK)
    for start in range(0, n, size):
        yield start, np.asarray(data[start:min(n, start + size)], dtype=np.float64)


_STATE = threading.local()
_READS: list[tuple[str, int]] = []


def whole_reads() -> list[tuple[str, int]]:
    """``(channel, samples)`` of every whole-record read of a :class:`LazyChannelData` so far
    in this process (in order)."""
    return list(_READS)


@contextlib.contextmanager
def whole_read_limit(samples: int) -> Iterator[None]:
    """Within the block, a whole-record read of more than ``samples`` samples (of a
    :class:`LazyChannelData`) raises AnalysisError naming the channel."""
    before = getattr(_STATE, "limit", None)
    _STATE.limit = int(samples)
    try:
        yield
    finally:
        _STATE.limit = before


class LazyChannelData(ChannelData):
    """A :class:`~fsi_lab.contract.ChannelData` whose samples are read from ``source`` when
    ``data`` is first asked for, and kept from then on.

    Parameters
    ----------
    name, sample_rate, quantity, unit, t0
        As :class:`~fsi_lab.contract.ChannelData`.
    data
        A source (:class:`DatasetSource`, or anything with ``len`` and slices), or an array
        (then it is the data: as :func:`dataclasses.replace` builds one).
    """

    def __init__(self, name: str, data: Any, sample_rate: float, quantity: str, unit: str,
                 t0: float = 0.0) -> None:
        loaded = data if isinstance(data, np.ndarray) else None
        for key, value in (("name", name), ("source", data), ("sample_rate", sample_rate),
                           ("quantity", quantity), ("unit", unit), ("t0", t0),
                           ("_loaded", loaded)):
            object.__setattr__(self, key, value)

    @property
    def data(self) -> np.ndarray:  # type: ignore[override]
        """The whole record, float64 (read on first use)."""
        if self._loaded is None:
            n = len(self.source)
            limit = getattr(_STATE, "limit", None)
            if limit is not None and n > limit:
                raise AnalysisError(f"channel {self.name!r}: a whole-record read of {n} samples "
                                    f"asked for, more than the {limit} allowed here")
            _READS.append((self.name, n))
            object.__setattr__(self, "_loaded", np.asarray(self.source[0:n], dtype=np.float64))
        return self._loaded

    @property
    def loaded(self) -> bool:
        """Whether ``data`` has been read."""
        return self._loaded is not None

    def samples(self) -> Any:
        """The samples without reading them all: the array once read, else the source."""
        return self._loaded if self._loaded is not None else self.source

    def head(self, length: int) -> LazyChannelData:
        """The channel up to ``length`` samples (not read)."""
        source = self._loaded[:length] if self._loaded is not None else (
            self.source.head(length) if hasattr(self.source, "head") else self.source[0:length])
        return LazyChannelData(self.name, source, self.sample_rate, self.quantity, self.unit,
                               self.t0)

    def __repr__(self) -> str:
        return (f"LazyChannelData(name={self.name!r}, samples={len(self.samples())}, "
                f"sample_rate={self.sample_rate!r}, quantity={self.quantity!r}, "
                f"unit={self.unit!r}, t0={self.t0!r})")


def samples_of(channel: ChannelData) -> Any:
    """A channel's samples for a chunked read: the source of a :class:`LazyChannelData` not yet
    read, else its array."""
    return channel.samples() if isinstance(channel, LazyChannelData) else channel.data


def head_of(channel: ChannelData, length: int) -> ChannelData:
    """``channel`` up to ``length`` samples, without reading a lazy one."""
    import dataclasses

    if isinstance(channel, LazyChannelData):
        return channel.head(length)
    return dataclasses.replace(channel, data=channel.data[:length])


def is_source(data: Any) -> bool:
    """Whether ``data`` is a source read by slices (:class:`DatasetSource`, or anything with
    ``len`` and ``read``) rather than samples in memory."""
    return hasattr(data, "read") and hasattr(data, "__len__") and not isinstance(data,
                                                                                np.ndarray)


def check_source(data: Any, func: str, *, min_samples: int = 16, name: str = "signal",
                 allow_constant: bool = False, check_clipping: bool = True) -> int:
    """The checks of :func:`fsi_lab.dsp._signal.as_record` (enough samples, finite, not
    constant, not clipped), a chunk at a time; returns the number of samples.

    Raises
    ------
    AnalysisError
        As :func:`~fsi_lab.dsp._signal.as_record`, with the same messages.
    """
    from fsi_lab.dsp._signal import fail

    n = int(len(data))
    if n < min_samples:
        raise fail(func, f"{name} has {n} samples, too short; need at least {min_samples} "
                         "samples")
    bad, first = 0, -1
    lo, hi = math.inf, -math.inf
    for start, chunk in chunks(data):
        finite = np.isfinite(chunk)
        if not finite.all():
            where = np.flatnonzero(~finite)
            first = start + int(where[0]) if first < 0 else first
            bad += where.size
            continue
        lo, hi = min(lo, float(chunk.min())), max(hi, float(chunk.max()))
    if bad:
        raise fail(func, f"{name} contains {bad} NaN or infinite samples (first at index "
                         f"{first}); expected finite values - remove or interpolate them")
    if not allow_constant and hi - lo <= 1e-12 * max(abs(lo), abs(hi), 1e-300):
        raise fail(func, f"{name} is constant (every sample is {lo + 0.0:g}); expected an "
                         "oscillating record")
    if check_clipping:
        where = _clipping(data, n, lo, hi)
        if where is not None:
            raise fail(func, f"{name} looks clipped: {where}; the analysis needs an unclipped "
                             "record - lower the input range or the excitation")
    return n


def _clipping(data: Any, n: int, lo: float, hi: float) -> str | None:
    """:func:`fsi_lab.dsp._signal.clipping` of a source (whose extremes are ``lo`` and
    ``hi``), a chunk at a time: runs of the extreme value are carried across chunks, and those
    that call it clipped are read again with the record around them, to tell a crest held by a
    coarse converter's grid from a clipped one."""
    from fsi_lab.dsp._signal import flat_message

    long_run = max(8, n // 1000)
    for label, value in (("maximum", hi), ("minimum", lo)):
        hold = _leading_hold(data, value, hi - lo)
        runs = [(max(a, hold), b) for a, b in _runs_at(data, n, value) if b > hold]
        if sum(b - a for a, b in runs) < 3:
            continue
        flagged = [(a, b) for a, b in runs if b - a >= 3]
        flat = np.array([b - a for a, b in flagged], dtype=np.int64)
        if not (flat.size >= 2 or (flat.size and flat.max() > long_run)):
            continue
        if all(_held_on_grid(data, n, a, b, value) for a, b in flagged):
            continue
        return flat_message(label, value, flat)
    return None


def _leading_hold(data: Any, value: float, span: float) -> int:
    """:func:`fsi_lab.dsp._signal.leading_hold` of a source at its extreme ``value``, a chunk
    at a time."""
    from fsi_lab.dsp._signal import leading_hold

    for start, chunk in chunks(data):
        held = leading_hold(np.abs(chunk - value), span)
        if held < chunk.size:
            return start + held
    return int(len(data))


def _runs_at(data: Any, n: int, value: float) -> list[tuple[int, int]]:
    """``(first, one past the last)`` sample of each run of ``value`` in a source, read a
    chunk at a time (a run across chunks counted once)."""
    from fsi_lab.dsp._signal import true_runs

    runs: list[tuple[int, int]] = []
    open_at = -1                         # the first sample of a run reaching a chunk's end
    for start, chunk in chunks(data):
        firsts, lasts = true_runs(chunk == value)
        if open_at >= 0 and not (firsts.size and firsts[0] == 0):
            runs.append((open_at, start))
            open_at = -1
        for a, b in zip(firsts.tolist(), lasts.tolist()):
            first = open_at if a == 0 and open_at >= 0 else start + a
            open_at = -1
            if b == chunk.size:
                open_at = first
            else:
                runs.append((first, start + b))
    if open_at >= 0:
        runs.append((open_at, n))
    return runs


def _held_on_grid(data: Any, n: int, a: int, b: int, value: float) -> bool:
    """:func:`fsi_lab.dsp._signal.held_on_grid` for the run ``[a, b)`` of a source, read with
    the record around it: eight times the run each side (a crest held over one grid step
    falls 16 steps below within four times that), and at least 4096 samples (four samples
    to each of the grid's levels the window crosses, on a grid of 0.05 % of its range)."""
    from fsi_lab.dsp._signal import held_on_grid

    reach = max(4096, 8 * (b - a))
    lo, hi = max(0, a - reach), min(n, b + reach)
    window = np.asarray(data[lo:hi], dtype=np.float64)
    return held_on_grid(window, a - lo, b - lo, value)
