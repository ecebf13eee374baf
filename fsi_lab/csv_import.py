"""Import of data recorded elsewhere: a CSV file becomes a run file.

The header row names each column ``name [unit]`` (or ``name (unit)``); the unit (m, m/s,
m/s^2, g or V, with a prefix mm, um, mV...) gives the quantity. An optional ``time [s]`` (or
``[ms]``) column replaces the sample rate given on the command line. Values are converted to SI
(g to m/s^2, mm/s to m/s). Files exported where the decimal mark is a comma separate their
columns with semicolons (or tabs): their ``1,5`` reads as 1.5. Lines starting with ``#`` before
or among the rows are comments. What a run file gets from its profile and instruments and a CSV
cannot say is given on import: the base acceleration column (``reference``) and the sensors'
signal delays, so that the analysis of exported data gives the run's results.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np

from fsi_lab.errors import InputFileError
from fsi_lab.inputfiles import read_text
from fsi_lab.profile import CHANNEL_NAME
from fsi_lab.runcheck import CHANNEL_RATES_HZ, MAX_T0_S
from fsi_lab.runfile import RunFileWriter, new_run_path, software_version, utc_now
from fsi_lab.units import QUANTITY_OF_UNIT, TIME_UNITS, parse_unit, to_si

_HEADER = re.compile(r"^\s*(?P<name>[^\[\]()]+?)\s*(?:\[(?P<unit>[^\[\]]*)\]"
                     r"|\((?P<paren>[^()]*)\))\s*$")
TIME_TOLERANCE = 1e-3  # relative spread of the time steps accepted as uniform sampling
EXPECTED = ("a UTF-8 CSV file with a header row of 'name [unit]' cells and rows of numbers, "
            "separated by commas (or by semicolons or tabs, with a decimal comma or point)")
#: The units accepted, in words, for the messages.
ACCEPTED_UNITS = ("m, m/s, m/s^2, g or V, with a prefix m, u (µ) or n on m, m/s, m/s^2 and V "
                  "(mm/s, um, mV), or s or ms for the time column")
#: Column separators recognised in the header row, most telling first.
SEPARATORS = (";", "\t", ",")
_SEPARATOR_NAMES = {";": "semicolons", "\t": "tabs", ",": "commas"}


@dataclass(frozen=True)
class Column:
    """A column of the file: its channel ``name``, the ``unit`` it is written in, the unit of
    :data:`~fsi_lab.units.QUANTITY_OF_UNIT` (or ``s``) it is one of and the factor to it, and
    the name the header wrote (spaces become ``_`` in the channel name)."""

    name: str
    unit: str
    base: str
    factor: float
    written: str

    @property
    def is_time(self) -> bool:
        return self.name.lower() == "time"


def _parse_header(path: Path, cells: list[str]) -> list[Column]:
    columns = []
    for number, cell in enumerate(cells, start=1):
        match = _HEADER.match(cell)
        if not match:
            raise InputFileError(
                f"{path}: header column {number} is {cell!r}; expected 'name [unit]' (or "
                f"'name (unit)') with unit {ACCEPTED_UNITS}"
            )
        written = match["name"].strip()
        unit = (match["unit"] if match["unit"] is not None else match["paren"]).strip()
        name = re.sub(r"\s+", "_", written)
        if not CHANNEL_NAME.fullmatch(name):  # the names a profile accepts
            raise InputFileError(
                f"{path}: header column {number}: name {written!r} is not accepted; expected a "
                "letter followed by letters, digits, '_', '-' or spaces (e.g. tip_velocity)"
            )
        if name.lower() == "time":
            parsed = ("s", TIME_UNITS[unit]) if unit in TIME_UNITS else None
        else:
            parsed = parse_unit(unit)
        if parsed is None:
            raise InputFileError(
                f"{path}: header column {number} ({written}): unit {unit!r} is not accepted; "
                f"expected {ACCEPTED_UNITS}"
            )
        columns.append(Column(name, unit, parsed[0], parsed[1], written))
    names = [c.name for c in columns]
    duplicate = next((n for n in names if names.count(n) > 1), None)
    if duplicate:
        raise InputFileError(f"{path}: column name {duplicate!r} appears twice in the header")
    return columns


def _separator(header: str) -> str:
    """The column separator of a file whose header line is ``header``: a semicolon or a tab
    when the line holds one (files written with a decimal comma), else a comma."""
    return next((sep for sep in SEPARATORS if sep in header), ",")


def read_csv(path: str | Path) -> tuple[list[Column], np.ndarray, np.ndarray]:
    """Columns, the values (rows x columns, in each column's written unit) and each row's line
    number in the file, of a CSV file.

    The separator is found on the header row (:func:`_separator`); with semicolons or tabs, a
    comma in a value is its decimal mark.
    """
    path = Path(path)
    text = read_text(path, EXPECTED)
    lines = [(number, line) for number, line in enumerate(text.splitlines(), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise InputFileError(f"{path}: empty; expected a header row 'name [unit],...' and data")
    separator = _separator(lines[0][1])
    reader = csv.reader(io.StringIO("\n".join(line for _, line in lines), newline=""),
                        delimiter=separator)
    try:
        rows = list(reader)
    except csv.Error as exc:
        raise InputFileError(f"{path}: line {lines[reader.line_num - 1][0]}: {exc}; expected "
                             f"{EXPECTED}") from None
    if len(rows) != len(lines):  # a quoted cell spanning lines: not a table of numbers
        raise InputFileError(f"{path}: a quoted value spans several lines; expected {EXPECTED}")
    # An export's rows often end with the separator: an empty last cell on every line.
    if len(rows[0]) > 1 and not rows[0][-1].strip():
        rows = [row[:-1] if row and not row[-1].strip() else row for row in rows]
    columns = _parse_header(path, rows[0])
    decimal_comma = separator != ","
    data = np.empty((len(rows) - 1, len(columns)))
    for index, ((line, _), row) in enumerate(zip(lines[1:], rows[1:])):
        if len(row) != len(columns):
            raise InputFileError(
                f"{path}: line {line} has {len(row)} values; the header has {len(columns)} "
                f"columns (separated by {_SEPARATOR_NAMES[separator]})"
            )
        for col, cell in enumerate(row):
            number = cell.strip().replace(",", ".") if decimal_comma else cell
            try:
                value = float(number)
            except ValueError:
                raise InputFileError(
                    f"{path}: line {line}, column {col + 1} ({columns[col].written}): {cell!r} is "
                    "not a number"
                ) from None
            if not np.isfinite(value):
                raise InputFileError(
                    f"{path}: line {line}, column {col + 1} ({columns[col].written}): {cell!r}; "
                    "expected a finite number"
                )
            data[index, col] = value
    if data.shape[0] < 2:
        raise InputFileError(f"{path}: fewer than two data rows")
    return columns, data, np.array([line for line, _ in lines[1:]])


def _check_rate(rate: float, where: str) -> float:
    """``rate`` (Hz) if it lies within :data:`~fsi_lab.runcheck.CHANNEL_RATES_HZ`."""
    low, high = CHANNEL_RATES_HZ
    if not (np.isfinite(rate) and low <= rate <= high):
        raise InputFileError(f"{where}: a sample rate of {rate:g} Hz; expected {low:g} to "
                             f"{high:g} Hz")
    return rate


def _rate_from_time(path: Path, time: np.ndarray, lines: np.ndarray) -> float:
    """The sample rate (Hz) of the time column's values ``time`` (s) on file lines ``lines``."""
    steps = np.diff(time)
    step = float(np.median(steps))
    if step <= 0:
        raise InputFileError(f"{path}: the time column does not increase")
    with np.errstate(over="ignore", invalid="ignore"):
        spread = float(np.max(np.abs(steps - step))) / step
    if spread > TIME_TOLERANCE:
        worst = int(np.argmax(np.abs(steps - step)))
        raise InputFileError(
            f"{path}: the time column is not uniformly sampled (step {steps[worst]:.6g} s at "
            f"line {lines[worst + 1]} against a median of {step:.6g} s); expected uniform sampling "
            f"within {TIME_TOLERANCE:.1%}"
        )
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        rate = (time.size - 1) / float(time[-1] - time[0])
    # A time column printed in decimal misses the sample clock by its rounding (10 kHz read
    # back as 10000.0000000011 Hz); no clock is stable to 10 significant digits.
    if np.isfinite(rate):
        rate = float(f"{rate:.10g}")
    return _check_rate(rate, f"{path}: the time column (steps of {step:.6g} s) gives")


#: Largest sensor delay accepted on import, s (a vibrometer's is about a millisecond).
MAX_DELAY_S = 1.0


def _check_analysis_inputs(path: Path, columns: list[Column], reference: str | None,
                           delays: Mapping[str, float]) -> None:
    """The reference must be an acceleration column and each delay name a data column."""
    quantities = {c.name: QUANTITY_OF_UNIT[c.base] for c in columns if not c.is_time}
    listing = ", ".join(quantities)
    if reference is not None and quantities.get(reference) != "acceleration":
        found = (f"a {quantities[reference]} column" if reference in quantities
                 else f"not a data column of {path}")
        raise InputFileError(f"--reference {reference}: {found}; expected the base "
                             f"acceleration column (columns: {listing})")
    for name, delay in delays.items():
        if name not in quantities:
            raise InputFileError(f"--delay {name}={delay:g}: {name!r} is not a data column of "
                                 f"{path}; expected one of {listing}")
        if not (np.isfinite(delay) and 0.0 <= delay <= MAX_DELAY_S):
            raise InputFileError(f"--delay {name}={delay:g}: expected a sensor delay from 0 to "
                                 f"{MAX_DELAY_S:g} s")


def import_csv(path: str | Path, out: str | Path, rate: float | None,
               reference: str | None = None, delays: Mapping[str, float] | None = None) -> Path:
    """Write the CSV file ``path`` as the run file ``out``; returns ``out``.

    Parameters
    ----------
    path
        CSV file with header ``name [unit]`` (:func:`read_csv`).
    out
        Run file to create; must not exist (nothing is ever overwritten).
    rate
        Sample rate, Hz; ignored (and may be None) when the file has a ``time [s]`` column.
    reference
        The base acceleration column, stored as the root attribute ``reference``:
        ``fsi-lab analyze`` uses it as the profile's ``[analysis] reference`` (base motion
        removed by HVD, transfer functions, the modal model).
    delays
        Signal delay of a column's sensor, s, by column name (a vibrometer's); the column's
        time origin ``t0`` is moved back by it, as a run does with the vibrometer's delay.
    """
    path, out = Path(path), Path(out)
    delays = dict(delays or {})
    columns, data, lines = read_csv(path)
    _check_analysis_inputs(path, columns, reference, delays)
    times = [i for i, column in enumerate(columns) if column.is_time]
    if len(times) > 1:
        raise InputFileError(f"{path}: header columns {times[0] + 1} and {times[1] + 1} are both "
                             "time columns; expected at most one 'time [s]' column")
    if len(times) == len(columns):
        raise InputFileError(f"{path}: only a time column; expected data columns 'name [unit]' "
                             "beside it")
    t0 = 0.0
    if times:
        time = data[:, times[0]] * columns[times[0]].factor
        rate = _rate_from_time(path, time, lines)
        t0 = float(time[0])
        if abs(t0) > MAX_T0_S:
            raise InputFileError(f"{path}: line {lines[0]}: the time column starts at {t0:g} s; "
                                 f"expected a start within {MAX_T0_S:g} s of 0")
    elif rate is None:
        raise InputFileError(f"{path}: no 'time [s]' column; give the sample rate with --rate HZ")
    else:
        _check_rate(rate, f"--rate {rate:g}")
    values = {}
    for col, column in enumerate(columns):
        if col in times:
            continue
        si_unit, factor = to_si(column.base)
        with np.errstate(over="ignore"):
            values[column.name] = data[:, col] * (column.factor * factor)
        if not np.all(np.isfinite(values[column.name])):
            line = lines[int(np.argmax(~np.isfinite(values[column.name])))]
            raise InputFileError(f"{path}: line {line}, column {col + 1} ({column.written}): too "
                                 f"large to convert from {column.unit} to {si_unit}; expected a "
                                 "finite value")
    if out.exists():
        raise InputFileError(f"{out}: already exists; choose another output file")
    _, run_uuid, started = new_run_path(out.parent)
    writer = RunFileWriter(out, {
        "uuid": run_uuid, "start_time": started, "kind": "imported",
        "source_file": str(path), "profile": "", "software_version": software_version(),
        **({"reference": reference} if reference else {}),
    })
    try:
        for column in columns:
            name = column.name
            if name not in values:
                continue
            writer.create_channel(name, {
                "units": to_si(column.base)[0], "quantity": QUANTITY_OF_UNIT[column.base],
                "sample_rate": rate, "t0": t0 - delays.get(name, 0.0), "sensitivity": 1.0,
                "source_instrument": f"imported from {path.name}",
                "original_units": column.unit, "sensor_delay_s": delays.get(name, 0.0),
                **({"original_name": column.written} if column.written != name else {}),
            })
            writer.append(name, values[name])
        writer.set_attrs({"exit_status": "completed", "stop_time": utc_now()})
        writer.close()
    except BaseException:  # interrupted or failed: no half-written file is left behind
        writer.abandon()
        out.unlink(missing_ok=True)
        raise
    return out
