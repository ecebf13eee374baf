"""HDF5 run files: one file per run, written as the run goes (layout: docs/run-format.md)."""

from __future__ import annotations

import contextlib
import datetime as _dt
import itertools
import json
import math
import os
import stat
import uuid as _uuid
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any, Iterator, Mapping

import h5py
import numpy as np

from fsi_lab.contract import ChannelData
from fsi_lab.errors import AnalysisError, InputFileError
from fsi_lab.inputfiles import require_regular_file
from fsi_lab.isolation import crash_or_hang, in_child
from fsi_lab.runcheck import CHANNEL_RATES_HZ, H5_ERRORS, MAX_T0_S, RunFileReader, decode_attr
from fsi_lab.runcheck import EXPECTED as RUN_FILE
from fsi_lab.signals import INTERRUPTED  # noqa: F401 - the error recorded for Ctrl+C
from fsi_lab.sources import DatasetSource, LazyChannelData, samples_of
from fsi_lab.sources import chunks as sample_chunks
from fsi_lab.units import QUANTITIES

FORMAT = "fsi-lab run"
#: The root attribute ``format`` of a sequence's record (:mod:`fsi_lab.seqfile`).
SEQUENCE_FORMAT = "fsi-lab sequence"
FORMAT_VERSION = 1
EXIT_STATUSES = ("running", "completed", "aborted", "failed")
#: A crash (even ``kill -9``) loses at most this much of the record delivered, s: the file is
#: flushed before the samples not yet flushed, with the next block, would exceed it.
FLUSH_SPAN_S = 0.5
CHUNK_SAMPLES = 16384
#: Samples read at a time when a file's channels are checked without keeping them.
SCAN_CHUNK = 64 * CHUNK_SAMPLES


def software_version() -> str:
    """Installed version of fsi-lab."""
    try:
        return metadata.version("fsi-lab")
    except metadata.PackageNotFoundError:
        return "unknown"


def utc_now() -> str:
    """Current time, ISO 8601 UTC with microseconds."""
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="microseconds")


def new_run_path(out_dir: str | Path) -> tuple[Path, str, str]:
    """A fresh run file path in ``out_dir``, the run's uuid and its start time (ISO, UTC).

    Files are named ``YYYYmmdd-HHMMSS_<first 8 hex digits of the uuid>.h5``.
    """
    started = _dt.datetime.now(_dt.timezone.utc)
    run_uuid = _uuid.uuid4().hex
    name = f"{started:%Y%m%d-%H%M%S}_{run_uuid[:8]}.h5"
    return Path(out_dir) / name, run_uuid, started.isoformat(timespec="microseconds")


def _attr(value: Any) -> Any:
    """A value HDF5 can store as an attribute (JSON text for anything structured)."""
    if value is None:
        return "null"
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, str, np.integer, np.floating)):
        return value
    if isinstance(value, (list, tuple)) and value and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
    ):
        return np.asarray(value, dtype=float)
    return json.dumps(value, default=str)


def write_attrs(node: h5py.HLObject, values: Mapping[str, Any]) -> None:
    """Store a flat mapping as attributes of ``node``."""
    for key, value in values.items():
        node.attrs[key] = _attr(value)


def read_attrs(node: h5py.HLObject) -> dict[str, Any]:
    """Attributes of ``node`` as plain Python values (:func:`~fsi_lab.runcheck.decode_attr`)."""
    return {key: decode_attr(value) for key, value in node.attrs.items()}


class RunFileWriter:
    """Creates a run file and appends to it as blocks arrive.

    After each block (:meth:`flush_if_due`) the file is flushed when the samples not yet
    flushed and a next block as long as this one would span more than :data:`FLUSH_SPAN_S`
    of the record, so that a run killed at any moment (with the next block on its way) loses
    at most that span, and leaves a file that opens with h5py and h5dump and holds every
    block up to the last flush. The rule counts samples, not time, so it holds on a slow
    machine and for a bench that runs faster than real time. Blocks must not be longer than
    :data:`FLUSH_SPAN_S` (the profile's limits see to it). The file uses the earliest HDF5 file
    format (no SWMR): after a crash it opens without ``h5clear``.
    """

    def __init__(self, path: Path, attrs: Mapping[str, Any]) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = h5py.File(self.path, "x")
        write_attrs(self._file, {"format": FORMAT, "format_version": FORMAT_VERSION,
                                 "exit_status": "running", **attrs})
        for group in ("instruments", "channels", "analysis"):
            self._file.create_group(group)
        self.samples_flushed: dict[str, int] = {}
        self._rates: dict[str, float] = {}
        self._last_block: dict[str, int] = {}
        self._file.flush()

    @property
    def file(self) -> h5py.File:
        return self._file

    @property
    def closed(self) -> bool:
        return not self._file.id.valid

    def write_instrument(self, role: str, info: Mapping[str, Any],
                         settings: Mapping[str, Any]) -> None:
        """``/instruments/<role>``: identity and plugin as attributes, settings as a group."""
        group = self._file["instruments"].require_group(role)
        write_attrs(group, info)
        write_attrs(group.require_group("settings"), settings)

    def write_final_state(self, role: str, state: Mapping[str, Any]) -> None:
        """``/instruments/<role>/final_state``: what the instrument reported after safe state."""
        group = self._file["instruments"].require_group(role)
        write_attrs(group.require_group("final_state"), state)

    def write_excitation(self, waveform: np.ndarray, sample_rate: float,
                         attrs: Mapping[str, Any], params: Mapping[str, Any]) -> None:
        """``/excitation``: the waveform sent (V), its rate (Hz) and parameters."""
        group = self._file.create_group("excitation")
        data = group.create_dataset("waveform", data=np.asarray(waveform, dtype=float))
        data.attrs["units"] = "V"
        write_attrs(group, {"sample_rate": float(sample_rate), **attrs})
        write_attrs(group.create_group("params"), params)

    def create_channel(self, name: str, attrs: Mapping[str, Any]) -> None:
        """An empty resizable ``/channels/<name>`` with its calibration attributes."""
        dataset = self._file["channels"].create_dataset(
            name, shape=(0,), maxshape=(None,), dtype="f8", chunks=(CHUNK_SAMPLES,)
        )
        write_attrs(dataset, attrs)
        self.samples_flushed[name] = 0
        self._rates[name] = float(attrs["sample_rate"])
        self._last_block[name] = 0

    def append(self, name: str, block: np.ndarray) -> None:
        """Append samples to ``/channels/<name>``."""
        dataset = self._file["channels"][name]
        start = dataset.shape[0]
        dataset.resize((start + block.size,))
        dataset[start:] = block
        self._last_block[name] = block.size

    def unflushed_s(self) -> float:
        """The longest span of record, s, a crash would lose now with a next block as long
        as the last on its way (what :meth:`flush_if_due` keeps within FLUSH_SPAN_S)."""
        channels = self._file["channels"]
        return max(((channels[name].shape[0] - flushed + self._last_block[name])
                    / self._rates[name] for name, flushed in self.samples_flushed.items()),
                   default=0.0)

    def flush_if_due(self) -> bool:
        """Flush when the record not yet flushed, with a next block as long as the last, would
        exceed :data:`FLUSH_SPAN_S`; returns whether it flushed. Call it after every block."""
        if self.unflushed_s() <= FLUSH_SPAN_S * (1 + 1e-9):
            return False
        self.flush()
        return True

    def flush(self) -> None:
        self._file.flush()
        for name, dataset in self._file["channels"].items():
            self.samples_flushed[name] = dataset.shape[0]

    def set_attrs(self, values: Mapping[str, Any]) -> None:
        write_attrs(self._file, values)

    def close(self) -> None:
        if not self.closed:
            self._file.flush()
            self._file.close()

    def abandon(self) -> None:
        """Close the file without writing more (after a write failed, e.g. a full disk)."""
        try:
            self._file.close()
        except Exception:  # noqa: BLE001 - the library's state is unknown; nothing to save
            pass


# --------------------------------------------------------------------------- reading
@dataclass
class RunData:
    """A run file read back: root attributes, channels, and the excitation if any.

    ``channel_samples`` gives each channel's length (also when its data was not loaded).
    """

    path: Path
    attrs: dict[str, Any]
    channels: dict[str, ChannelData]
    channel_attrs: dict[str, dict[str, Any]]
    instruments: dict[str, dict[str, Any]]
    excitation: dict[str, Any] | None
    channel_samples: dict[str, int] = field(default_factory=dict)

    @property
    def profile_text(self) -> str:
        return self.attrs.get("profile", "") or ""

    @property
    def reference(self) -> str:
        """Imported data: the base acceleration channel given on import, or empty."""
        return self.attrs.get("reference", "") or ""


def _open_checked(path: Path, mode: str) -> h5py.File:
    require_regular_file(path, "a run file (.h5)")
    try:
        handle = h5py.File(path, mode)
    except OSError as exc:
        raise InputFileError(
            f"{path}: not a readable HDF5 file ({exc}); expected a run file written by fsi-lab"
        ) from None
    try:
        fmt = handle.attrs.get("format")
    except H5_ERRORS:
        fmt = None
    if decode_attr(fmt) == SEQUENCE_FORMAT:
        handle.close()
        raise InputFileError(
            f"{path}: a sequence's record (written by fsi-lab sequence), not a run file; its "
            f"runs are the other .h5 files beside it: fsi-lab show {path.parent} lists them, "
            f"fsi-lab aggregate {path.parent} pools them"
        )
    if decode_attr(fmt) != FORMAT:
        handle.close()
        raise InputFileError(
            f"{path}: not an fsi-lab run file (root attribute format is missing or not "
            f"{FORMAT!r}); expected a file written by fsi-lab run, import or simulate"
        )
    return handle


#: Files a child has read without crashing, by (device, inode, size, mtime, with data): read
#: again unchanged (``show`` reads the channels, then the analysis) they need no second child.
_SURVIVED: set[tuple[int, int, int, int, bool]] = set()


def _read_safely(path: Path, read, load_data: bool = False):
    """``read(path)``, once a forked child has read the file (its nodes and analysis summary,
    its data too with ``load_data``, a chunk at a time without keeping it) without crashing or
    hanging the HDF5 library (:func:`~fsi_lab.isolation.crash_or_hang`)."""
    require_regular_file(path, "a run file (.h5)")
    info = path.stat()
    key = (info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns)
    if (*key, True) not in _SURVIVED and (*key, load_data) not in _SURVIVED:
        problem = crash_or_hang(lambda: (_read_run(path, False), _scan_channels(path)
                                         if load_data else None, _read_summary(path)),
                                info.st_size, hold=h5py._objects.phil)
        if problem:
            raise InputFileError(f"{path}: damaged: {problem}; expected {RUN_FILE}")
        _SURVIVED.add((*key, load_data))
    return read(path)


def read_run(path: str | Path, load_data: bool = True, lazy: bool = False) -> RunData:
    """Read a run file (channels fully loaded unless ``load_data`` is False; with ``lazy``,
    channels read from the file when first used: :class:`~fsi_lab.sources.LazyChannelData`).

    Raises
    ------
    InputFileError
        Missing file, not HDF5, not an fsi-lab run file, or a node or attribute that is not as
        fsi-lab writes it (named in the message), including damage that would crash HDF5.
    """
    return _read_safely(Path(path), lambda p: _read_run(p, load_data and not lazy, lazy),
                        load_data or lazy)


def _scan_channels(path: Path) -> None:
    """Read every channel of run file ``path`` a chunk at a time, keeping nothing (the crash
    check of a file whose channels are read later, lazily)."""
    with h5py.File(path, "r") as handle:
        group = handle.get("channels")
        for name in group if isinstance(group, h5py.Group) else []:
            dataset = group[name]
            if isinstance(dataset, h5py.Dataset) and dataset.ndim == 1:
                for start in range(0, dataset.shape[0], SCAN_CHUNK):
                    dataset[start:start + SCAN_CHUNK]


def _read_run(path: Path, load_data: bool, lazy: bool = False) -> RunData:
    with _open_checked(path, "r") as handle:
        reader = RunFileReader(path)
        attrs = reader.attrs(handle)
        reader.text(attrs, "profile", "/", default="")
        reference = reader.text(attrs, "reference", "/", default="")
        overrides = attrs.get("overrides", [])
        if not isinstance(overrides, list) or not all(isinstance(o, str) for o in overrides):
            raise reader.refuse("/ attribute 'overrides'", "is not a list of texts",
                                "a JSON list of the --set key=value overrides")
        channels: dict[str, ChannelData] = {}
        channel_attrs: dict[str, dict[str, Any]] = {}
        samples: dict[str, int] = {}
        group = reader.child(handle, "channels", h5py.Group)
        for name in reader.names(group) if group is not None else []:
            dataset = reader.child(group, name, h5py.Dataset, required=True)
            where = dataset.name
            meta = reader.attrs(dataset)
            quantity = reader.text(meta, "quantity", where, choices=QUANTITIES)
            unit = reader.text(meta, "units", where)
            rate = reader.number(meta, "sample_rate", where, bounds=CHANNEL_RATES_HZ)
            t0 = reader.number(meta, "t0", where, default=0.0, bounds=(-MAX_T0_S, MAX_T0_S))
            samples[name], data = reader.samples(dataset, load_data)
            channel_attrs[name] = meta
            if lazy:
                data = DatasetSource(path, where, samples[name])
            kind = LazyChannelData if lazy else ChannelData
            channels[name] = kind(name, data, rate, quantity, unit, t0)
        if reference and reference not in channels:
            raise reader.refuse("/ attribute 'reference'", f"names {reference!r}, which is not "
                                "a channel of the file",
                                "one of " + (", ".join(channels) or "none"))
        instruments = {}
        group = reader.child(handle, "instruments", h5py.Group)
        for role in reader.names(group) if group is not None else []:
            node = reader.child(group, role, h5py.Group, required=True)
            info = reader.attrs(node)
            for sub in ("settings", "final_state"):
                child = reader.child(node, sub, h5py.Group)
                if child is not None:
                    info[sub] = reader.attrs(child)
            instruments[role] = info
        excitation = None
        group = reader.child(handle, "excitation", h5py.Group)
        if group is not None:
            excitation = reader.attrs(group)
            params = reader.child(group, "params", h5py.Group)
            excitation["params"] = reader.attrs(params) if params is not None else {}
            waveform = reader.child(group, "waveform", h5py.Dataset, required=True)
            excitation["waveform"] = reader.samples(waveform, load_data or lazy)[1]
    return RunData(path, attrs, channels, channel_attrs, instruments, excitation, samples)


#: A channel's samples beyond this many times the range its instruments could record (the
#: digitiser's input range over the channel's sensitivity) are damaged or implausible data.
IMPLAUSIBLE = 2.0
#: Up to this many such samples are left to the analysis, which replaces isolated spikes (a
#: flipped bit) and says so; more are refused.
ISOLATED_GLITCHES = 8


def recorded_full_scale(run: RunData, name: str) -> tuple[float, str] | None:
    """The largest value, in the channel's units, channel ``name`` of ``run`` could hold (the
    digitiser's input range for its input, ``ranges_v`` of ``/instruments/acquisition/
    settings``, over its sensitivity) and how it follows, or None when the run file does not
    record them (imported data, an acquisition without ``ranges_v``)."""
    attrs = run.channel_attrs.get(name, {})
    settings = (run.instruments.get("acquisition") or {}).get("settings") or {}
    ranges = settings.get("ranges_v")
    try:
        number = int(attrs["input"])
        # by input number once configured; a profile's list (inputs 1, 2, ...) before that
        volts = float(ranges[str(number)] if isinstance(ranges, dict)
                      else ranges[number - 1] if number >= 1 else math.nan)
        sensitivity = float(attrs["sensitivity"])
    except (KeyError, TypeError, ValueError, IndexError):
        return None
    if not (math.isfinite(volts) and volts > 0 and math.isfinite(sensitivity)
            and sensitivity > 0):
        return None
    return volts / sensitivity, (f"the digitiser's input {int(attrs['input'])} range of "
                                 f"{volts:g} V over the sensitivity of {sensitivity:g} "
                                 f"{attrs.get('sensitivity_units', 'V per unit')}")


def require_analysable(run: RunData, minimum: int = 2) -> None:
    """Raise InputFileError unless ``run`` (read with its data, or lazily: then read a chunk at
    a time) has channels of at least ``minimum`` finite samples each (what ``fsi-lab analyze``
    needs), none of them, beyond a few isolated glitches, far outside the range the run's
    instruments could record (:func:`recorded_full_scale`)."""
    if not run.channels:
        raise InputFileError(f"{run.path}: /channels holds no channel; expected recorded "
                             "channels to analyse")
    for name, channel in run.channels.items():
        count = run.channel_samples[name]
        if count < minimum:
            raise InputFileError(
                f"{run.path}: /channels/{name} holds {count} sample{'s' if count != 1 else ''}; "
                f"expected at least {minimum} to analyse")
        count, first = 0, -1
        scale = recorded_full_scale(run, name)
        limit = IMPLAUSIBLE * scale[0] if scale is not None else math.inf
        beyond, where, value = 0, -1, 0.0
        try:
            for start, chunk in sample_chunks(samples_of(channel)):
                bad = np.flatnonzero(~np.isfinite(chunk))
                if bad.size and first < 0:
                    first = start + int(bad[0])
                count += bad.size
                far = np.flatnonzero(np.abs(np.nan_to_num(chunk)) > limit)
                if far.size and where < 0:
                    where, value = start + int(far[0]), float(chunk[far[0]])
                beyond += far.size
        except H5_ERRORS as exc:
            raise RunFileReader(run.path).refuse(
                f"/channels/{name}", f"its samples cannot be read ({exc})",
                "a 1-D dataset of real numbers") from None
        if count:
            raise InputFileError(
                f"{run.path}: /channels/{name} holds {count} NaN or infinite samples (the "
                f"first at index {first}); expected finite samples to analyse")
        if beyond > ISOLATED_GLITCHES:
            full, how = scale
            units = run.channel_attrs.get(name, {}).get("units", "")
            raise InputFileError(
                f"{run.path}: /channels/{name} holds {beyond} samples beyond {IMPLAUSIBLE:g} "
                f"times the +-{full:.4g} {units} its instruments could record ({how}), the "
                f"first at index {where}: {value:.4g} {units}; these are damaged or "
                "implausible data, not a record to analyse (a damaged file, or a channel "
                "written by another tool in other units); expected samples within the "
                "recorded range")


def write_analysis(path: str | Path, groups: Mapping[str, Mapping[str, Any]],
                   summary: Mapping[str, Any], attrs: Mapping[str, Any] | None = None) -> None:
    """Replace ``/analysis`` with new results, leaving everything else as it was.

    ``groups`` maps ``"<channel>/<plugin>"`` to a dict with ``datasets``, ``units``, ``attrs``
    and ``params``. The file is rewritten, never modified: everything but ``/analysis`` is
    copied (object for object, the channels' chunks as they are) into a temporary file beside
    it, the new results are written there, and the temporary file, synced to disk, replaces
    the run file in one rename. So the file does not grow over re-analyses (the space of the
    previous results goes with the old file), and a failure or a crash (even ``kill -9``) at any
    moment leaves the run file exactly as it was, previous results included; what a crash
    leaves of the temporary file (``.<name>.<pid>-<n>.rewrite``) is removed by the next
    analysis of the file once its process is gone. See docs/run-format.md.

    Raises
    ------
    AnalysisError
        A result HDF5 cannot store (named), or the rewritten file cannot be synced or renamed
        (a full disk); the run file is unchanged.
    InputFileError
        The run file cannot be read whole, or is read-only, or its folder does not allow the
        temporary file; the run file is unchanged.
    """
    with rewrite_analysis(path) as handle:
        _write_results(handle, path, groups, summary, attrs)


@contextlib.contextmanager
def rewrite_analysis(path: str | Path) -> Iterator[h5py.File]:
    """The rewrite of :func:`write_analysis`, for results written a part at a time: yields
    the open temporary copy of the run file (everything but ``/analysis``, and an empty
    ``/analysis`` group) to write into; when the block ends without an exception, the copy
    replaces the run file in one rename, else it is removed and the run file is unchanged.

    Raises
    ------
    AnalysisError, InputFileError
        As :func:`write_analysis`.
    """
    path = Path(path)
    with _open_checked(path, "r"):  # an fsi-lab run file, or refused
        pass
    target = Path(os.path.realpath(path))  # a symbolic link keeps pointing at the run file
    if not os.access(target, os.W_OK):
        raise InputFileError(f"{path}: is read-only; fsi-lab analyze stores its results in the "
                             "run file (make it writable, or analyse a copy)")
    _remove_stale_rewrites(target)
    temp = target.with_name(f".{target.name}.{os.getpid()}-{next(_REWRITES)}{_REWRITE_SUFFIX}")
    try:
        _copy_record(path, temp)
        with h5py.File(temp, "r+") as handle:
            yield handle
        try:
            _replace(target, temp)
        except OSError as exc:  # e.g. a full disk while syncing
            raise AnalysisError(f"{path}: the analysis cannot be stored ({exc}); the run file "
                                "is unchanged") from None
    except BaseException:
        temp.unlink(missing_ok=True)
        raise


#: The temporary files of :func:`write_analysis` end with this; numbered within a process.
_REWRITE_SUFFIX = ".rewrite"
_REWRITES = itertools.count()


def _remove_stale_rewrites(target: Path) -> None:
    """Remove temporary files of earlier rewrites of ``target`` whose process is gone (a
    ``kill -9`` or a power cut during an analysis)."""
    prefix = f".{target.name}."
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return
    for entry in entries:
        name = entry.name
        if not (name.startswith(prefix) and name.endswith(_REWRITE_SUFFIX)):
            continue
        pid = name[len(prefix):-len(_REWRITE_SUFFIX)].partition("-")[0]
        if not pid.isdigit() or _alive(int(pid)):
            continue
        try:
            os.unlink(entry.path)
        except OSError:
            pass


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (on this machine)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # it exists, owned by someone else
        return True
    return True


def _copy_record(path: Path, temp: Path) -> None:
    """Copy everything of run file ``path`` but ``/analysis`` into a new file ``temp``.

    The copy runs in a forked child (:func:`~fsi_lab.isolation.in_child`): it reads every
    node, also those fsi-lab never reads otherwise, and damage there must not crash the
    caller. When the copy fails with an ordinary error, it is redone here for the message.
    """
    _new_file(path, temp)
    problem, copied = in_child(lambda: _copy_nodes(path, temp), path.stat().st_size,
                               hold=h5py._objects.phil)
    if problem:
        raise InputFileError(f"{path}: damaged: {problem}; expected {RUN_FILE}")
    if not copied:
        _new_file(path, temp)
        _copy_nodes(path, temp)  # raises InputFileError naming what could not be copied
        raise InputFileError(f"{path}: cannot be copied for the rewrite (the copy failed in a "
                             f"child process and not in this one); expected {RUN_FILE}")


def _new_file(path: Path, temp: Path) -> None:
    """An empty HDF5 file ``temp`` (created here, so that the folder's refusal is ours to
    report), in HDF5's earliest file format like every run file."""
    try:
        temp.unlink(missing_ok=True)
        h5py.File(temp, "x").close()
    except OSError as exc:
        raise InputFileError(
            f"{path}: cannot write the temporary file {temp.name} beside it ({exc}); fsi-lab "
            "analyze rewrites the run file through a temporary file in its folder") from None


def _copy_nodes(path: Path, temp: Path) -> None:
    """Into the empty file ``temp``: ``path``'s root attributes (with their HDF5 types) and
    every member of its root but ``/analysis`` (and an unfinished ``/analysis.new`` of an older
    version), by HDF5's object copy: datasets keep their layout, chunks and attributes;
    soft and external links stay links."""
    where = "/"
    try:
        with h5py.File(path, "r") as source, h5py.File(temp, "r+") as copy:
            for index in range(h5py.h5o.get_info(source.id).num_attrs):
                attr = h5py.h5a.open(source.id, index=index)
                where = f"/ attribute {_text(attr.get_name())!r}"
                space = attr.get_space()
                new = h5py.h5a.create(copy.id, attr.get_name(), attr.get_type(), space)
                if space.get_simple_extent_type() != h5py.h5s.NULL:
                    values = np.empty(attr.shape, dtype=attr.dtype)
                    attr.read(values)
                    new.write(values)
            for name in list(source.id):
                where = "/" + _text(name)
                if name in (b"analysis", b"analysis.new"):
                    continue
                kind = source.id.links.get_info(name).type
                if kind == h5py.h5l.TYPE_HARD:
                    h5py.h5o.copy(source.id, name, copy.id, name)
                elif kind == h5py.h5l.TYPE_SOFT:
                    copy.id.links.create_soft(name, source.id.links.get_val(name))
                elif kind == h5py.h5l.TYPE_EXTERNAL:
                    copy.id.links.create_external(name, *source.id.links.get_val(name))
                else:
                    raise ValueError(f"a link of type {kind} that fsi-lab cannot copy")
            copy.create_group("analysis")
    except H5_ERRORS as exc:
        raise InputFileError(f"{path}: {where}: cannot be copied for the rewrite "
                             f"({type(exc).__name__}: {exc}); expected {RUN_FILE}") from None


def _text(name: bytes) -> str:
    return name.decode("utf-8", errors="replace")


def _write_results(handle: h5py.File, path: Path, groups: Mapping[str, Mapping[str, Any]],
                   summary: Mapping[str, Any], attrs: Mapping[str, Any] | None = None) -> None:
    """The new results into the (empty) ``/analysis`` of the open rewrite ``handle``, with
    ``attrs`` (``overrides``: what ``fsi-lab analyze`` was given) beside the summary."""
    root = handle["analysis"]
    where = "/analysis"
    try:
        write_attrs(root, {"analyzed_at": utc_now(), "summary": dict(summary), **(attrs or {})})
        for key, content in groups.items():
            where = f"/analysis/{key}"
            group = root.create_group(key)
            for name, array in content.get("datasets", {}).items():
                where = f"/analysis/{key}/{name}"
                dataset = group.create_dataset(name, data=np.asarray(array))
                unit = content.get("units", {}).get(name)
                if unit is not None:
                    dataset.attrs["units"] = unit
                axis = content.get("axes", {}).get(name)
                if axis is not None:  # the dataset it is drawn against
                    dataset.attrs["axis"] = axis
            write_attrs(group, content.get("attrs", {}))
            write_attrs(group.create_group("params"), content.get("params", {}))
    except H5_ERRORS as exc:
        raise AnalysisError(f"{path}: {where}: the analysis result cannot be stored "
                            f"({type(exc).__name__}: {exc}); the previous results are "
                            "kept") from None


def _replace(target: Path, temp: Path) -> None:
    """``temp`` synced to disk, given ``target``'s permissions (and owner, where allowed),
    then renamed over ``target``; the folder synced so that the rename is on disk too."""
    info = target.stat()
    os.chmod(temp, stat.S_IMODE(info.st_mode))
    if (info.st_uid, info.st_gid) != (os.geteuid(), os.getegid()):
        try:
            os.chown(temp, info.st_uid, info.st_gid)
        except OSError:  # not allowed: the file becomes ours, as any file we write
            pass
    _fsync(temp, os.O_RDONLY)
    os.replace(temp, target)
    try:
        _fsync(target.parent, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:  # a folder that cannot be opened or synced (some network file systems)
        pass


def _fsync(path: Path, flags: int) -> None:
    fd = os.open(path, flags)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def analysis_overrides(sets: tuple[str, ...] | list[str],
                       mass_per_length: float | None) -> tuple[str, ...]:
    """What an analysis is computed with beyond the run's own settings, as ``/analysis``
    attribute ``overrides`` stores it: the ``--set`` texts, and ``--mass-per-length=VALUE``
    (kg/m)."""
    return tuple(sets) + ((f"--mass-per-length={mass_per_length:g}",)
                          if mass_per_length is not None else ())


def read_analysis_overrides(path: str | Path) -> list[str]:
    """The ``--set`` overrides (and ``--mass-per-length``) the stored analysis was computed
    with beyond the run's own (``/analysis`` attribute ``overrides``); empty when none were
    given, or the analysis is the run's own."""
    def read(path: Path) -> list[str]:
        with _open_checked(path, "r") as handle:
            group = handle.get("analysis")
            value = decode_attr(group.attrs.get("overrides", "[]")) \
                if isinstance(group, h5py.Group) else []
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise RunFileReader(path).refuse("/analysis attribute 'overrides'",
                                             "is not a list of texts",
                                             "the JSON list of texts fsi-lab analyze writes")
        return value

    return _read_safely(Path(path), read)


def read_analysis_summary(path: str | Path) -> dict[str, Any] | None:
    """The summary stored by the last analysis, or None if the run was never analysed.

    Raises
    ------
    InputFileError
        ``/analysis`` or its ``summary`` attribute is not as fsi-lab writes it.
    """
    return _read_safely(Path(path), _read_summary)


def _read_summary(path: Path) -> dict[str, Any] | None:
    with _open_checked(path, "r") as handle:
        reader = RunFileReader(path)
        group = reader.child(handle, "analysis", h5py.Group)
        text = reader.attrs(group).get("summary") if group is not None else None
        if group is not None:
            reader.walk(group)  # analyze replaces it all: every member must open
    if text is None or text == "":
        return None
    if not isinstance(text, dict):  # decode_attr parses what is JSON
        raise reader.refuse("/analysis attribute 'summary'",
                            f"is not a JSON object ({_kind(text)})",
                            "the JSON object fsi-lab analyze writes")
    return text


def _kind(value: Any) -> str:
    return f"a {type(value).__name__} starting {str(value)[:30]!r}"
