"""Import of data recorded elsewhere: a CSV file becomes a run file.

The header row names each column ``name [unit]``; the unit (m, m/s, m/s^2, g or V) gives the
quantity. An optional ``time [s]`` column replaces the sample rate given on the command line.
Values in g are converted to m/s^2.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from fsi_lab.errors import InputFileError
from fsi_lab.inputfiles import read_text
from fsi_lab.profile import CHANNEL_NAME
from fsi_lab.runfile import RunFileWriter, new_run_path, software_version, utc_now
from fsi_lab.units import QUANTITY_OF_UNIT, to_si

_HEADER = re.compile(r"^\s*(?P<name>[^\[\]]+?)\s*\[(?P<unit>[^\[\]]*)\]\s*$")
TIME_TOLERANCE = 1e-3  # relative spread of the time steps accepted as uniform sampling
EXPECTED = "a UTF-8 CSV file with a header row of 'name [unit]' cells and rows of numbers"


def _parse_header(path: Path, cells: list[str]) -> list[tuple[str, str]]:
    columns = []
    accepted = ", ".join(list(QUANTITY_OF_UNIT) + ["s (time column)"])
    for number, cell in enumerate(cells, start=1):
        match = _HEADER.match(cell)
        if not match:
            raise InputFileError(
                f"{path}: header column {number} is {cell!r}; expected 'name [unit]' with unit "
                f"one of {accepted}"
            )
        name, unit = match["name"].strip(), match["unit"].strip()
        if not CHANNEL_NAME.fullmatch(name):  # the names a profile accepts
            raise InputFileError(
                f"{path}: header column {number}: name {name!r} is not accepted; expected a "
                "letter followed by letters, digits, '_' or '-' (e.g. tip_velocity)"
            )
        is_time = name.lower() == "time"
        if (is_time and unit != "s") or (not is_time and unit not in QUANTITY_OF_UNIT):
            raise InputFileError(
                f"{path}: header column {number} ({name}): unit {unit!r} is not accepted; "
                f"expected one of {accepted}"
            )
        columns.append((name, unit))
    names = [n for n, _ in columns]
    duplicate = next((n for n in names if names.count(n) > 1), None)
    if duplicate:
        raise InputFileError(f"{path}: column name {duplicate!r} appears twice in the header")
    return columns


def read_csv(path: str | Path) -> tuple[list[tuple[str, str]], np.ndarray]:
    """Columns ``(name, unit)`` and the values (rows x columns) of a CSV file."""
    path = Path(path)
    reader = csv.reader(io.StringIO(read_text(path, EXPECTED), newline=""))
    try:
        rows = list(reader)
    except csv.Error as exc:
        raise InputFileError(f"{path}: line {reader.line_num}: {exc}; expected {EXPECTED}") \
            from None
    rows = [r for r in rows if any(cell.strip() for cell in r)]
    if not rows:
        raise InputFileError(f"{path}: empty; expected a header row 'name [unit],...' and data")
    columns = _parse_header(path, rows[0])
    data = np.empty((len(rows) - 1, len(columns)))
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(columns):
            raise InputFileError(
                f"{path}: line {line} has {len(row)} values; the header has {len(columns)} columns"
            )
        for col, cell in enumerate(row):
            try:
                value = float(cell)
            except ValueError:
                raise InputFileError(
                    f"{path}: line {line}, column {col + 1} ({columns[col][0]}): {cell!r} is "
                    "not a number"
                ) from None
            if not np.isfinite(value):
                raise InputFileError(
                    f"{path}: line {line}, column {col + 1} ({columns[col][0]}): {cell!r}; "
                    "expected a finite number"
                )
            data[line - 2, col] = value
    if data.shape[0] < 2:
        raise InputFileError(f"{path}: fewer than two data rows")
    return columns, data


def _rate_from_time(path: Path, time: np.ndarray) -> float:
    steps = np.diff(time)
    step = float(np.median(steps))
    if step <= 0:
        raise InputFileError(f"{path}: the time column does not increase")
    spread = float(np.max(np.abs(steps - step))) / step
    if spread > TIME_TOLERANCE:
        worst = int(np.argmax(np.abs(steps - step)))
        raise InputFileError(
            f"{path}: the time column is not uniformly sampled (step {steps[worst]:.6g} s at "
            f"line {worst + 3} against a median of {step:.6g} s); expected uniform sampling "
            f"within {TIME_TOLERANCE:.1%}"
        )
    return 1.0 / step


def import_csv(path: str | Path, out: str | Path, rate: float | None) -> Path:
    """Write the CSV file ``path`` as the run file ``out``; returns ``out``.

    Parameters
    ----------
    path
        CSV file with header ``name [unit]``.
    out
        Run file to create; must not exist (nothing is ever overwritten).
    rate
        Sample rate, Hz; ignored (and may be None) when the file has a ``time [s]`` column.
    """
    path, out = Path(path), Path(out)
    columns, data = read_csv(path)
    names = [n for n, _ in columns]
    t0 = 0.0
    if "time" in [n.lower() for n in names]:
        index = [n.lower() for n in names].index("time")
        rate = _rate_from_time(path, data[:, index])
        t0 = float(data[0, index])
    elif rate is None:
        raise InputFileError(f"{path}: no 'time [s]' column; give the sample rate with --rate HZ")
    elif not (np.isfinite(rate) and rate > 0):
        raise InputFileError(f"--rate {rate}: expected a positive sample rate in Hz")
    if out.exists():
        raise InputFileError(f"{out}: already exists; choose another output file")
    _, run_uuid, started = new_run_path(out.parent)
    writer = RunFileWriter(out, {
        "uuid": run_uuid, "start_time": started, "kind": "imported",
        "source_file": str(path), "profile": "", "software_version": software_version(),
    })
    try:
        for col, (name, unit) in enumerate(columns):
            if name.lower() == "time":
                continue
            si_unit, factor = to_si(unit)
            writer.create_channel(name, {
                "units": si_unit, "quantity": QUANTITY_OF_UNIT[unit], "sample_rate": rate,
                "t0": t0, "sensitivity": 1.0, "source_instrument": f"imported from {path.name}",
                "original_units": unit,
            })
            writer.append(name, data[:, col] * factor)
        writer.set_attrs({"exit_status": "completed", "stop_time": utc_now()})
    finally:
        writer.close()
    return out
