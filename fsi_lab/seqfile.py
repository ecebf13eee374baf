"""The sequence record: one HDF5 file per sequence, beside its run files (docs/sequence-format.md).

The record is small (the plan, the base profile and one group of attributes per run), so it is
rewritten whole at every change, into a temporary file that is synced and then renamed over the
old one: whenever the process is killed (even with ``kill -9``), ``sequence.h5`` is the last
complete version, never a half-written one, and ``fsi-lab sequence --resume DIR`` can trust it.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import uuid as _uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import h5py
import numpy as np

from fsi_lab.errors import InputFileError
from fsi_lab.inputfiles import require_regular_file
from fsi_lab.isolation import crash_or_hang
from fsi_lab.plan import Plan, PlannedRun
from fsi_lab.runcheck import RunFileReader
from fsi_lab.runfile import SEQUENCE_FORMAT, decode_attr, software_version, utc_now, write_attrs

SEQUENCE_FILE = "sequence.h5"
LOCK_FILE = ".sequence.lock"
FORMAT = SEQUENCE_FORMAT
FORMAT_VERSION = 1
EXPECTED = "a sequence file written by fsi-lab sequence (layout in docs/sequence-format.md)"
#: ``running`` while the sequence goes (or if its process was killed), then how it ended.
STATUSES = ("running", "completed", "failed", "interrupted")
#: A run is ``pending`` until started; ``running`` while it goes (or if the process was
#: killed during it); then its run file's exit status; ``skipped`` when the plan's stop_when
#: target was reached before it.
RUN_STATUSES = ("pending", "running", "completed", "failed", "aborted", "skipped")


def compact_results(summary: dict[str, Any] | None) -> dict[str, list[dict[str, Any]]]:
    """Per analysed channel, each component's frequency (Hz), C_i (kg/(m s)) and C_f (kg/m^2)
    with their 95 % intervals and R^2, and its warnings, from an analysis summary (empty
    without one).

    A component's ``warnings`` are its own and those of each analysis that keeps them under
    its key (:func:`fsi_lab.summary.warnings_of`), the latter prefixed ``key: `` as
    ``fsi-lab analyze --strict`` names them; an empty list when none warned it.
    """
    from fsi_lab.summary import warnings_of

    results: dict[str, list[dict[str, Any]]] = {}
    for channel, info in ((summary or {}).get("channels") or {}).items():
        components = []
        for component in info.get("components") or []:
            eq = component.get("equivalent_damping") or {}
            components.append({
                "index": component.get("index"), "frequency_hz": component.get("frequency_hz"),
                **{key: eq.get(key) for key in ("c_i", "c_i_ci95", "c_f", "c_f_ci95", "r2")},
                "warnings": [f"{key}: {text}" if key else text
                             for key, text in warnings_of(component)]})
        results[channel] = components
    return results


def new_run_entry(run: PlannedRun, safety: dict[str, Any] | None) -> dict[str, Any]:
    """The record's entry of a planned run, pending."""
    return {"index": run.index, "step": run.step, "step_name": run.step_name,
            "point": dict(run.point), "repeat": run.repeat, "repeats": run.repeats,
            "overrides": list(run.overrides), "settle_s": run.settle_s, "status": "pending",
            "run_file": "", "start_time": "", "stop_time": "", "error": "",
            "interrupted": False, "attempts": [], "safety": safety or {}, "results": {},
            "analysed": False}


@dataclass
class SequenceRecord:
    """A sequence's record: root attributes and one entry per run (dicts of the attributes
    listed in docs/sequence-format.md)."""

    directory: Path
    attrs: dict[str, Any]
    runs: list[dict[str, Any]] = field(default_factory=list)
    #: the aggregation of the completed runs (:func:`fsi_lab.aggregate.aggregate_extracts`)
    #: with ``sequence_runs``, the indices of the runs it holds; None before any
    aggregate: dict[str, Any] | None = None

    @property
    def path(self) -> Path:
        return self.directory / SEQUENCE_FILE

    @classmethod
    def new(cls, plan: Plan, directory: Path,
            safety: dict[int, dict[str, Any]]) -> SequenceRecord:
        """A record of ``plan`` in ``directory``, every run pending."""
        attrs = {"format": FORMAT, "format_version": FORMAT_VERSION, "uuid": _uuid.uuid4().hex,
                 "name": plan.name, "status": "running", "error": "",
                 "start_time": utc_now(), "stop_time": "", "resumed": [],
                 "plan_path": str(plan.path.resolve()), "plan": plan.text,
                 "plan_sha256": plan.sha256, "profile_path": str(plan.profile_path.resolve()),
                 "profile": plan.profile_text, "profile_sha256": plan.profile_sha256,
                 "on_failure": plan.on_failure, "software_version": software_version()}
        return cls(Path(directory), attrs,
                   [new_run_entry(run, safety.get(run.index)) for run in plan.runs])

    def save(self) -> None:
        """Write the record whole into a temporary file, sync it and rename it over
        ``sequence.h5`` (atomic: a crash leaves the previous version)."""
        temporary = self.directory / (SEQUENCE_FILE + ".tmp")
        with h5py.File(temporary, "w") as handle:
            write_attrs(handle, {**self.attrs, "runs": len(self.runs)})
            group = handle.create_group("runs")
            for entry in self.runs:
                write_attrs(group.create_group(f"{entry['index']:05d}"), entry)
            if self.aggregate is not None:
                _write_aggregate(handle.create_group("aggregate"), self.aggregate)
        _fsync(temporary)
        os.replace(temporary, self.path)
        _fsync(self.directory)

    def counts(self) -> dict[str, int]:
        """How many runs are in each status."""
        found = {status: 0 for status in RUN_STATUSES}
        for entry in self.runs:
            found[entry["status"]] += 1
        return found

    def as_json(self) -> dict[str, Any]:
        """The record as one JSON object (``fsi-lab show DIR --json``)."""
        attrs = {k: v for k, v in self.attrs.items() if k not in ("plan", "profile")}
        return {"sequence": str(self.path), "directory": str(self.directory), **attrs,
                "counts": self.counts(), "runs": self.runs, "plan": self.attrs["plan"],
                "aggregate": self.aggregate}


def _write_aggregate(group: h5py.Group, agg: dict[str, Any]) -> None:
    """The aggregation: its summary as JSON text, each mode's curves as datasets."""
    from fsi_lab.aggregate import CURVES, without_curves

    write_attrs(group, {"summary": without_curves(agg)})
    for k, mode in enumerate(agg["modes"]):
        node = group.create_group(f"mode_{k:02d}")
        for curve, keys in CURVES.items():
            for key in keys:
                data = np.asarray(mode["curves"][curve][key],
                                  dtype=np.int32 if key == "run" else np.float64)
                node.create_dataset(f"{curve}_{key}", data=data)


def _read_aggregate(reader: RunFileReader, group: h5py.Group) -> dict[str, Any]:
    from fsi_lab.aggregate import CURVES

    summary = reader.attrs(group).get("summary")
    if not (isinstance(summary, dict) and isinstance(summary.get("modes"), list)):
        raise reader.refuse(f"{group.name} attribute 'summary'", "is not an aggregation",
                            "JSON with runs and modes (docs/sequence-format.md)")
    for k, mode in enumerate(summary["modes"]):
        node = reader.child(group, f"mode_{k:02d}", h5py.Group, required=True)
        curves: dict[str, dict[str, Any]] = {}
        for curve, keys in CURVES.items():
            curves[curve] = {}
            for key in keys:
                data = reader.child(node, f"{curve}_{key}", h5py.Dataset, required=True)
                if data.ndim != 1:
                    raise reader.refuse(data.name, f"has shape {data.shape}", "a 1-D dataset")
                curves[curve][key] = data[()]
        mode["curves"] = curves
    return summary


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def record_path(directory: str | Path) -> Path:
    """``DIR/sequence.h5``, or ``directory`` itself when it names the file."""
    directory = Path(directory)
    return directory if directory.name == SEQUENCE_FILE and not directory.is_dir() \
        else directory / SEQUENCE_FILE


def load_record(directory: str | Path) -> SequenceRecord:
    """Read the record of the sequence in ``directory`` (or the ``sequence.h5`` named).

    Raises
    ------
    InputFileError
        No record there, or one that is not as fsi-lab writes it (the node named).
    """
    path = record_path(directory)
    if not path.exists():
        raise InputFileError(f"{path.parent}: holds no {SEQUENCE_FILE}; expected the --out "
                             "directory of fsi-lab sequence")
    require_regular_file(path, EXPECTED)
    problem = crash_or_hang(lambda: _read(path), path.stat().st_size, hold=h5py._objects.phil)
    if problem:
        raise InputFileError(f"{path}: damaged: {problem}; expected {EXPECTED}")
    return _read(path)


def is_sequence_record(path: Path) -> bool:
    """Whether ``path`` is a sequence's record (a regular HDF5 file whose root ``format`` is
    :data:`FORMAT`); False for anything else, readable or not (a pipe is not opened)."""
    if not Path(path).is_file():
        return False
    try:
        with h5py.File(path, "r") as handle:
            found = handle.attrs.get("format")
    except (OSError, ValueError):
        return False
    return decode_attr(found) == FORMAT


def _read(path: Path) -> SequenceRecord:
    reader = RunFileReader(path)
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        raise InputFileError(f"{path}: not a readable HDF5 file ({exc}); expected "
                             f"{EXPECTED}") from None
    with handle:
        attrs = reader.attrs(handle)
        if attrs.get("format") != FORMAT:
            raise reader.refuse("/ attribute 'format'", f"is {attrs.get('format')!r}",
                                f"{FORMAT!r}: {EXPECTED}")
        reader.text(attrs, "status", "/", choices=STATUSES)
        for key in ("plan", "plan_sha256", "profile", "profile_sha256", "plan_path",
                    "profile_path", "start_time"):
            reader.text(attrs, key, "/")
        group = reader.child(handle, "runs", h5py.Group, required=True)
        runs = []
        for name in sorted(reader.names(group)):
            node = reader.child(group, name, h5py.Group, required=True)
            entry = reader.attrs(node)
            where = node.name
            reader.text(entry, "status", where, choices=RUN_STATUSES)
            reader.text(entry, "run_file", where)
            index = reader.number(entry, "index", where, bounds=(1, 1e9))
            if index != len(runs) + 1:
                raise reader.refuse(where, f"holds run {index:g} in place {len(runs) + 1}",
                                    "runs numbered 1, 2, ... in order")
            for key in ("overrides", "attempts"):
                if not isinstance(entry.get(key), list):
                    raise reader.refuse(f"{where} attribute {key!r}", "is not a list",
                                        "a JSON list")
            runs.append(entry)
        node = reader.child(handle, "aggregate", h5py.Group, required=False)
        aggregate = _read_aggregate(reader, node) if node is not None else None
    attrs.pop("runs", None)
    return SequenceRecord(path.parent, attrs, runs, aggregate)


@contextlib.contextmanager
def locked(directory: Path) -> Iterator[None]:
    """Hold the sequence directory's lock (one ``fsi-lab sequence`` at a time in it); the
    system releases it when the process ends, however it ends.

    Raises
    ------
    InputFileError
        Another process holds it (its pid is named).
    """
    path = directory / LOCK_FILE
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            raise InputFileError(f"{directory}: another fsi-lab sequence (pid {holder}) is "
                                 "running in it; wait for it or stop it first") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield
    finally:
        os.close(fd)


def holder(directory: Path) -> int | None:
    """The pid of the process running the sequence in ``directory``, or None if none is."""
    path = directory / LOCK_FILE
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            text = os.pread(fd, 32, 0).decode(errors="replace").strip()
            return int(text) if text.isdigit() else -1
        fcntl.flock(fd, fcntl.LOCK_UN)
        return None
    finally:
        os.close(fd)

