"""What a run file must hold for fsi-lab to read it.

Each node and attribute is checked as it is read, so that a damaged or foreign file gets one
:class:`~fsi_lab.errors.InputFileError` naming the file, the node or attribute, the problem and
what is expected (docs/run-format.md), never a traceback.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from fsi_lab.errors import InputFileError
from fsi_lab.inputfiles import nesting

EXPECTED = "a run file written by fsi-lab (layout in docs/run-format.md)"
#: Sample rates a channel may have, Hz (a run file's or an imported CSV's).
CHANNEL_RATES_HZ = (1e-3, 1e9)
#: Largest time origin a channel may have, s (in magnitude).
MAX_T0_S = 1e9
#: What reading an HDF5 node or attribute of a damaged file may raise.
H5_ERRORS = (KeyError, OSError, RuntimeError, TypeError, ValueError)


#: JSON attributes nested deeper than this are left as text (fsi-lab writes 6 levels at most).
MAX_JSON_DEPTH = 32


def decode_attr(value: Any) -> Any:
    """An attribute value as plain Python: text decoded, JSON text parsed (structured values
    are stored as JSON; text that is not JSON, or nests deeper than :data:`MAX_JSON_DEPTH`,
    stays text), numpy scalars and arrays as Python numbers and lists."""
    if isinstance(value, bytes):
        value = value.decode("utf-8", errors="replace")
    if isinstance(value, str) and (value[:1] in "{[" and value or value == "null"):
        try:
            parsed = json.loads(value)
        except (ValueError, RecursionError):
            parsed = value
        value = parsed if nesting(parsed)[0] <= MAX_JSON_DEPTH else value
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    return value


class RunFileReader:
    """Reads the nodes of one open run file, refusing what is not as fsi-lab writes it.

    Parameters
    ----------
    path
        The file, named in every message.
    """

    def __init__(self, path: Path) -> None:
        self.path = path

    def refuse(self, where: str, problem: str, expected: str = EXPECTED) -> InputFileError:
        """The error for ``where`` (a node path, or a node and attribute)."""
        return InputFileError(f"{self.path}: {where}: {problem}; expected {expected}")

    def child(self, group: h5py.Group, name: str, kind: type, required: bool = False):
        """The member ``name`` of ``group``, which must be a ``kind`` (h5py.Group or
        h5py.Dataset) stored in the file itself; None when absent and not ``required``."""
        where = f"{group.name.rstrip('/')}/{name}"
        what = "a group" if kind is h5py.Group else "a dataset"
        node = self._open(group, name, what, required)
        if node is not None and not isinstance(node, kind):
            found = "a group" if isinstance(node, h5py.Group) else "a dataset"
            raise self.refuse(where, f"is {found}", what)
        return node

    def walk(self, group: h5py.Group) -> None:
        """Open every member of ``group`` and below (refused if one does not open)."""
        for name in self.names(group):
            node = self._open(group, name, "a group or a dataset", True)
            if isinstance(node, h5py.Group):
                self.walk(node)

    def _open(self, group: h5py.Group, name: str, what: str, required: bool):
        """The member ``name`` of ``group`` through a hard link; None if absent."""
        where = f"{group.name.rstrip('/')}/{name}"
        try:
            link = group.get(name, getlink=True)
        except H5_ERRORS as exc:
            raise self.refuse(where, f"cannot be read ({exc})") from None
        if link is None:
            if required:
                raise self.refuse(where, "is missing", f"{what} there (see docs/run-format.md)")
            return None
        if not isinstance(link, h5py.HardLink):
            kind_of_link = "a soft" if isinstance(link, h5py.SoftLink) else "an external"
            raise self.refuse(where, f"is {kind_of_link} link", f"{what} stored in the file")
        try:
            return group[name]
        except H5_ERRORS as exc:
            raise self.refuse(where, f"cannot be read ({exc})") from None

    def names(self, group: h5py.Group) -> list[str]:
        """The members of ``group`` (refused if a name is not UTF-8 text)."""
        try:
            names = list(group.keys())
        except H5_ERRORS as exc:
            raise self.refuse(group.name, f"its members cannot be listed ({exc})") from None
        for name in names:
            if not isinstance(name, str):
                raise self.refuse(f"{group.name}/{decode_attr(name)}", "has a name that is not "
                                  "UTF-8 text", "members named in UTF-8")
        return names

    def attrs(self, node: h5py.HLObject) -> dict[str, Any]:
        """Every attribute of ``node``, decoded (:func:`decode_attr`)."""
        try:
            keys = list(node.attrs.keys())
        except H5_ERRORS as exc:
            raise self.refuse(node.name, f"its attributes cannot be read ({exc})") from None
        values = {}
        for key in keys:
            name = decode_attr(key)  # a damaged name may not be UTF-8
            try:
                values[name] = decode_attr(node.attrs[key])
            except H5_ERRORS as exc:
                raise self.refuse(f"{node.name} attribute {name!r}",
                                  f"cannot be read ({exc})") from None
        return values

    def text(self, values: dict[str, Any], key: str, where: str, default: str | None = None,
             choices: tuple[str, ...] | None = None) -> str:
        """Attribute ``key`` of ``values`` (read at node ``where``), which must be text (one of
        ``choices`` when given); ``default`` when absent, or refused if that is None."""
        value = values.get(key, default)
        accepted = "text" if choices is None else "one of " + ", ".join(map(repr, choices))
        if value is None:
            raise self.refuse(f"{where} attribute {key!r}", "is missing", accepted)
        if not isinstance(value, str) or (choices is not None and value not in choices):
            raise self.refuse(f"{where} attribute {key!r}", f"is {_short(value)}", accepted)
        return value

    def number(self, values: dict[str, Any], key: str, where: str,
               default: float | None = None,
               bounds: tuple[float, float] = (-math.inf, math.inf)) -> float:
        """Attribute ``key`` (read at node ``where``), which must be a finite number within
        ``bounds``; ``default`` when absent, or refused if that is None."""
        value = values.get(key, default)
        low, high = bounds
        accepted = "a finite number" + (f" from {low:g} to {high:g}"
                                        if math.isfinite(low) else "")
        if value is None:
            raise self.refuse(f"{where} attribute {key!r}", "is missing", accepted)
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) or not low <= value <= high:
            raise self.refuse(f"{where} attribute {key!r}", f"is {_short(value)}", accepted)
        return float(value)

    def samples(self, dataset: h5py.Dataset, load: bool) -> tuple[int, np.ndarray]:
        """The length of a 1-D dataset of real numbers and, when ``load``, its values."""
        where = dataset.name
        accepted = "a 1-D dataset of real numbers"
        try:
            shape, dtype = dataset.shape, dataset.dtype
        except H5_ERRORS as exc:
            raise self.refuse(where, f"cannot be read ({exc})", accepted) from None
        if shape is None or len(shape) != 1:
            raise self.refuse(where, f"has shape {shape}", accepted)
        if dtype.kind not in "fiu":
            raise self.refuse(where, f"holds {dtype} values", accepted)
        if not load:
            return shape[0], np.empty(0)
        try:
            return shape[0], np.asarray(dataset[()], dtype=float)
        except H5_ERRORS as exc:
            raise self.refuse(where, f"its samples cannot be read ({exc})", accepted) from None


def _short(value: Any, limit: int = 40) -> str:
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({type(value).__name__})"
