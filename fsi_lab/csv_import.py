"""Import of data recorded elsewhere: a CSV file becomes a run file.

The header row names each column ``name [unit]``; the unit (m, m/s, m/s^2, g or V) gives the
quantity. An optional ``time [s]`` column replaces the sample rate given on the command line.
Values in g are converted to m/s^2. What a run file gets from its profile and instruments and a
CSV cannot say is given on import: the base acceleration column (``reference``) and the sensors'
signal delays, so that the analysis of exported data gives the run's results.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path
from typing import Mapping

import numpy as np

from fsi_lab.errors import InputFileError
from fsi_lab.inputfiles import read_text
from fsi_lab.profile import CHANNEL_NAME
from fsi_lab.runcheck import CHANNEL_RATES_HZ, MAX_T0_S
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


def _check_rate(rate: float, where: str) -> float:
    """``rate`` (Hz) if it lies within :data:`~fsi_lab.runcheck.CHANNEL_RATES_HZ`."""
    low, high = CHANNEL_RATES_HZ
    if not (np.isfinite(rate) and low <= rate <= high):
        raise InputFileError(f"{where}: a sample rate of {rate:g} Hz; expected {low:g} to "
                             f"{high:g} Hz")
    return rate


def _rate_from_time(path: Path, time: np.ndarray) -> float:
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
            f"line {worst + 3} against a median of {step:.6g} s); expected uniform sampling "
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


def _check_analysis_inputs(path: Path, columns: list[tuple[str, str]], reference: str | None,
                           delays: Mapping[str, float]) -> None:
    """The reference must be an acceleration column and each delay name a data column."""
    quantities = {name: QUANTITY_OF_UNIT[unit] for name, unit in columns
                  if name.lower() != "time"}
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
        CSV file with header ``name [unit]``.
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
    columns, data = read_csv(path)
    _check_analysis_inputs(path, columns, reference, delays)
    times = [i for i, (name, _) in enumerate(columns) if name.lower() == "time"]
    if len(times) > 1:
        raise InputFileError(f"{path}: header columns {times[0] + 1} and {times[1] + 1} are both "
                             "time columns; expected at most one 'time [s]' column")
    if len(times) == len(columns):
        raise InputFileError(f"{path}: only a time column; expected data columns 'name [unit]' "
                             "beside it")
    t0 = 0.0
    if times:
        rate = _rate_from_time(path, data[:, times[0]])
        t0 = float(data[0, times[0]])
        if abs(t0) > MAX_T0_S:
            raise InputFileError(f"{path}: line 2: the time column starts at {t0:g} s; "
                                 f"expected a start within {MAX_T0_S:g} s of 0")
    elif rate is None:
        raise InputFileError(f"{path}: no 'time [s]' column; give the sample rate with --rate HZ")
    else:
        _check_rate(rate, f"--rate {rate:g}")
    values = {}
    for col, (name, unit) in enumerate(columns):
        if col in times:
            continue
        si_unit, factor = to_si(unit)
        with np.errstate(over="ignore"):
            values[name] = data[:, col] * factor
        if not np.all(np.isfinite(values[name])):
            line = int(np.argmax(~np.isfinite(values[name]))) + 2
            raise InputFileError(f"{path}: line {line}, column {col + 1} ({name}): too large "
                                 f"to convert from {unit} to {si_unit}; expected a finite value")
    if out.exists():
        raise InputFileError(f"{out}: already exists; choose another output file")
    _, run_uuid, started = new_run_path(out.parent)
    writer = RunFileWriter(out, {
        "uuid": run_uuid, "start_time": started, "kind": "imported",
        "source_file": str(path), "profile": "", "software_version": software_version(),
        **({"reference": reference} if reference else {}),
    })
    try:
        for name, unit in columns:
            if name not in values:
                continue
            writer.create_channel(name, {
                "units": to_si(unit)[0], "quantity": QUANTITY_OF_UNIT[unit],
                "sample_rate": rate, "t0": t0 - delays.get(name, 0.0), "sensitivity": 1.0,
                "source_instrument": f"imported from {path.name}", "original_units": unit,
                "sensor_delay_s": delays.get(name, 0.0),
            })
            writer.append(name, values[name])
        writer.set_attrs({"exit_status": "completed", "stop_time": utc_now()})
        writer.close()
    except BaseException:  # interrupted or failed: no half-written file is left behind
        writer.abandon()
        out.unlink(missing_ok=True)
        raise
    return out
