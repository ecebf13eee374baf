"""Import of data recorded elsewhere: a CSV file becomes a run file.

The header row names each column ``name [unit]`` (or ``name (unit)``, or its names on one row
and their units on the next); the unit (m, m/s, m/s^2, g or V, with a prefix mm, um, mV...)
gives the quantity. An optional column in s (or ms), the time whatever its name, replaces the
sample rate given on the command line. Values are converted to SI
(g to m/s^2, mm/s to m/s). Files exported where the decimal mark is a comma separate their
columns with semicolons (or tabs): their ``1,5`` reads as 1.5. Lines starting with ``#`` before
or among the rows are comments (a row whose first cell is a spreadsheet's error value, ``#NV``,
is a missing sample); blank lines only above the first row or after the last (one
among the rows is a missing sample, refused). What a run file gets from its profile and
instruments and a CSV cannot say is given on import: the base acceleration column
(``reference``), the sensors' signal delays, and the sensitivity of a sensor whose column is in
volts, so that the analysis of exported data gives the run's results.
"""

from __future__ import annotations

import csv
import itertools
import math
import re
import unicodedata
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Collection, Mapping, NoReturn

import numpy as np

from fsi_lab.errors import InputFileError
from fsi_lab.inputfiles import read_text_and_encoding
from fsi_lab.profile import CHANNEL_NAME
from fsi_lab.runcheck import CHANNEL_RATES_HZ, MAX_T0_S
from fsi_lab.runfile import RunFileWriter, new_run_path, software_version, utc_now
from fsi_lab.units import (
    QUANTITY_OF_UNIT,
    SENSITIVITY_FORM,
    TIME_UNITS,
    parse_sensitivity,
    parse_unit,
    to_si,
    voltage_hint,
)

_HEADER = re.compile(r"^\s*(?P<name>[^\[\]()]+?)\s*(?:\[(?P<unit>[^\[\]]*)\]"
                     r"|\((?P<paren>[^()]*)\))\s*$")
TIME_TOLERANCE = 1e-3  # relative spread of the time steps accepted as uniform sampling
#: Half the spacing of single-precision numbers relative to their value (2^-24).
FLOAT32_EPS = 2.0 ** -24
#: The way out of a time column refused, for its messages.
_WITHOUT_TIME = ("; if the samples were taken at a steady rate, give the rate with --rate HZ "
                 "--ignore-time (the time column is then left out)")
EXPECTED = ("a CSV file (UTF-8, or Windows-1252) with a header row of 'name [unit]' cells and "
            "rows of numbers, separated by commas (or by semicolons or tabs, with a decimal "
            "comma or point)")
#: The units accepted, in words, for the messages.
ACCEPTED_UNITS = ("m, m/s, m/s^2, g or V, with a prefix m, u (µ) or n on m, m/s, m/s^2 and V "
                  "(mm/s, um, mV), or s or ms for the time column")
#: The encoding of a CSV file that is not UTF-8: Windows-1252, the code page of Excel and
#: analysers on Western European Windows (it reads Latin-1's µ and ² as well).
SINGLE_BYTE = "cp1252"
#: The second line of a universal file: its first dataset's number, in 6 characters.
_UFF_DATASET = re.compile(r"(?=[ \d]{6}(?:b|\s|$)) *\d+(?:b?\s.*|b)?")
#: A value grouped in thousands (25.300, -1,234): one mark, three digits after it, and 1 to 3
#: before it not starting with 0 (a decimal value below 1, 0.125, is never grouped).
_GROUPED = re.compile(r"[-+]?[1-9]\d{0,2}[.,]\d{3}")
#: The mark that is not the decimal mark given.
_OTHER_MARK = {".": ",", ",": "."}
#: Column separators recognised in the header row, most telling first.
SEPARATORS = (";", "\t", ",")
#: A blank line: empty, spaces or tabs, or separators alone (a sheet's empty row).
_BLANK = re.compile(r"[\s,;]*")
_SEPARATOR_NAMES = {";": "semicolons", "\t": "tabs", ",": "commas"}


@dataclass(frozen=True)
class Column:
    """A column of the file: its channel ``name``, the ``unit`` it is written in, the unit of
    :data:`~fsi_lab.units.QUANTITY_OF_UNIT` (or ``s``) it is one of and the factor to it, the
    name the header wrote (spaces become ``_`` in the channel name) and its column number in
    the file (from 1, counting the columns ``--skip`` leaves out)."""

    name: str
    unit: str
    base: str
    factor: float
    written: str
    number: int = 0

    @property
    def is_time(self) -> bool:
        return self.name.lower() == "time"


#: Units of quantities fsi-lab does not read (force, pressure, temperature, current, ...).
_OTHER_UNIT = re.compile(r"(?i)(m|k)?(n|lbf|pa|bar|a|ohm)|mpa|°c|degc|°f|k|%|hz|rpm")
#: Header cells that name a sample number or a table's index (no unit).
_INDEX_NAME = re.compile(r"(?i)(index|idx|sample|samples|no\.?|nr\.?|n|#|unnamed: ?\d+)")


def _parse_header(path: Path, cells: list[str], line: int,
                  numbers: list[int] | None = None) -> list[Column]:
    """The columns of the header row ``cells`` (file line ``line``), whose column numbers in
    the file are ``numbers`` (default 1, 2, ...)."""
    columns = []
    for number, cell in zip(numbers or itertools.count(1), cells):
        match = _HEADER.match(cell)
        if not match:
            found = f"{cell!r}" if cell.strip() else (
                "empty (a table's index column? export without it, e.g. pandas' "
                "to_csv(index=False))")
            if _INDEX_NAME.fullmatch(cell.strip()):
                found += (" (a sample number or index column? leave it out with --skip "
                          f"{number}, or export without it)")
            raise InputFileError(
                f"{path}: line {line}, header column {number} is {found}; expected 'name "
                f"[unit]' (or 'name (unit)') with unit {ACCEPTED_UNITS}. The first line that "
                "is not a '#' comment is the header row: begin any lines above it with '#'"
            )
        written = match["name"].strip()
        unit = (match["unit"] if match["unit"] is not None else match["paren"]).strip()
        name = _channel_name(written)
        if not CHANNEL_NAME.fullmatch(name):  # the names a profile accepts
            raise InputFileError(
                f"{path}: header column {number}: name {written!r} is not accepted; expected a "
                "letter followed by letters, digits, '_', '-' or spaces (e.g. tip_velocity)"
            )
        # (no channel is in s or ms: a column in them is the time, whatever its name, Zeit,
        # t or X_Value; in a time column 'S' and 'MS' can only mean s and ms)
        is_time = name.lower() == "time" or unit.lower() in TIME_UNITS
        if is_time:
            name = "time"
            scale = TIME_UNITS.get(unit.lower())
            parsed = ("s", scale) if scale is not None else None
        else:
            parsed = parse_unit(unit)
        if parsed is None:
            other = (" (a column of another quantity, such as a hammer's force, is not read: "
                     f"leave it out with --skip {number})") if _OTHER_UNIT.fullmatch(unit) else ""
            raise InputFileError(
                f"{path}: header column {number} ({written}): unit {unit!r} is not accepted; "
                f"expected {ACCEPTED_UNITS}{other}"
            )
        columns.append(Column(name, unit, parsed[0], parsed[1], written, number))
    names = [c.name for c in columns if not c.is_time]   # (two time columns: import_csv)
    duplicate = next((n for n in names if names.count(n) > 1), None)
    if duplicate:
        written = " and ".join(repr(c.written) for c in columns if c.name == duplicate)
        raise InputFileError(f"{path}: column name {duplicate!r} appears twice in the header "
                             f"(written {written}); expected a name to each column")
    return columns


#: Lines below a refused header row searched for the export's own header (its first lines
#: about the export itself: the instrument, the date, the rate).
HEADER_SEARCH = 50


def _later_header(path: Path, lines: list[str], refused: int) -> str:
    """``; line N ('...') is one: begin lines R to N-1 with '#'`` when a line within
    :data:`HEADER_SEARCH` below the refused header row ``refused`` (a line number from 1)
    reads as a header row, else nothing."""
    for number in range(refused + 1, min(len(lines), refused + HEADER_SEARCH) + 1):
        text = lines[number - 1]
        if _BLANK.fullmatch(text) or text.lstrip().startswith("#"):
            continue
        separator = _separator(text)
        cells = _cells(text, separator)
        try:
            _parse_header(path, cells, number)
        except InputFileError:
            # or its names on this row and their units on the next (a blank line between)
            below = next((line for line in lines[number:number + HEADER_SEARCH]
                          if not _BLANK.fullmatch(line) and not line.lstrip().startswith("#")),
                         None)
            following = iter([_cells(below, separator)] if below is not None else [])
            if _names_and_units(path, cells, following, number) is None:
                continue
        above = f"line {refused}" if number == refused + 1 else f"lines {refused} to {number - 1}"
        return (f"; line {number} ({text.strip()!r}) is one: begin {above} with '#', or give "
                f"--header-line {number}")
    return ""


#: Letters spelled out in ASCII in a channel's name (the rest lose their accents).
_SPELLED = str.maketrans({"ß": "ss", "ä": "ae", "ö": "oe", "ü": "ue", "Ä": "Ae", "Ö": "Oe",
                          "Ü": "Ue", "æ": "ae", "ø": "o", "å": "a", "Æ": "Ae", "Ø": "O",
                          "Å": "A"})


def _channel_name(written: str) -> str:
    """The channel name of a header's ``written`` name: letters in ASCII (Fußpunkt:
    Fusspunkt, Vélocité: Velocite), and each run of spaces or other signs (``Point1:+Z``) as
    one ``_``."""
    ascii_text = unicodedata.normalize("NFKD", written.strip().translate(_SPELLED))
    ascii_text = "".join(c for c in ascii_text if not unicodedata.combining(c))
    return re.sub(r"[^A-Za-z0-9_-]+", "_", ascii_text).strip("_")


def _names_and_units(path: Path, names: list[str], reader, line: int,
                     skipped: tuple[list[int], int] | None = None) -> list[Column] | None:
    """The columns of a header written as a row of names (``names``, on file line ``line``)
    and, on the next row ``reader`` gives, a row of their units (``s;mm/s`` or ``[s];[mm/s]``,
    as LMS, DIAdem, dSPACE and oscilloscopes write them); None when the next row is not one
    unit per name. ``skipped``: when ``--skip`` left columns out of ``names``, the indices of
    those it holds and the number of columns in the file's row."""
    try:
        units = next(reader)
    except (StopIteration, csv.Error):
        return None
    units = _trimmed(units)
    kept = None
    if skipped is not None:
        kept, width = skipped
        if len(units) != width:
            return None
        units = [units[i] for i in kept]
    if not names or not units:
        return None
    written = [unit.strip().removeprefix("[").removesuffix("]").removeprefix("(")
               .removesuffix(")").strip() for unit in units]
    read = [parse_unit(unit) is not None or unit.lower() in TIME_UNITS for unit in written]
    # (a unit of another quantity, a hammer's N, beside units read: a row of units whose
    # column is refused by name and number, with --skip)
    other = [not ok and bool(_OTHER_UNIT.fullmatch(unit)) for ok, unit in zip(read, written)]
    if len(written) != len(names) or not any(read) or not all(
            ok or oth for ok, oth in zip(read, other)):
        return None
    cells = [f"{name.strip()} [{unit}]" for name, unit in zip(names, written)]
    numbers = [i + 1 for i in kept] if kept is not None else None
    try:
        return _parse_header(path, cells, line, numbers)
    except InputFileError:
        if any(other):
            raise                                  # that column's refusal
        return None


def _cells(text: str, separator: str) -> list[str]:
    """The cells of one line (a trailing separator's empty cell left out); none for a line
    the CSV reader refuses."""
    try:
        cells = next(csv.reader([text], delimiter=separator, strict=True))
    except csv.Error:
        return []
    return _trimmed(cells)


def _trimmed(cells: list[str]) -> list[str]:
    """A row's cells without the empty last one of a row that ends with the separator (as
    an export's rows often do)."""
    return cells[:-1] if len(cells) > 1 and not cells[-1].strip() else cells


#: Error values spreadsheets write in a cell (English, German, French), upper case.
SHEET_ERRORS = ("#N/A", "#NV", "#NA", "#DIV/0!", "#VALUE!", "#WERT!", "#VALEUR!", "#REF!",
                "#BEZUG!", "#NAME?", "#NOM?", "#NUM!", "#ZAHL!", "#NOMBRE!", "#NULL!", "#NUL!",
                "#LEER!", "#SPILL!", "#ÜBERLAUF!", "#CALC!", "#GETTING_DATA")


def _error_row(text: str, separator: str) -> bool:
    """Whether a line is a row of samples whose first cell holds a spreadsheet's error value
    (:data:`SHEET_ERRORS`), which starts with ``#`` as a comment does."""
    cells = _cells(text.strip(), separator)
    return bool(cells) and cells[0].strip().upper() in SHEET_ERRORS


def _numbers_only(text: str, separator: str) -> bool:
    """Whether every cell of the line ``text`` is a number (a decimal comma allowed beside
    semicolons or tabs)."""
    cells = _cells(text, separator)
    try:
        for cell in cells:
            float(cell.strip().replace(",", ".") if separator != "," else cell)
    except ValueError:
        return False
    return bool(cells)


def _commented_header(path: Path, lines: list[str], first: int) -> int | None:
    """The line (from 1) of a header row written as a comment just above the first row
    ``first``: the nearest line above that is not blank, when it starts with ``#`` and reads
    as a header row without it; else None."""
    for number in range(first - 1, 0, -1):
        text = lines[number - 1]
        if _BLANK.fullmatch(text):
            continue
        body = text.lstrip()
        if not body.startswith("#"):
            return None
        if _error_row(body, _separator(body)):
            continue                    # (a row of samples, refused as such below)
        body = body[1:]
        cells = _cells(body, _separator(body))
        try:
            _parse_header(path, cells, number)
        except InputFileError:
            return None
        return number if cells else None
    return None


def _example_header(count: int, separator: str) -> str:
    """A header row for ``count`` columns separated by ``separator``, for the messages."""
    names = ["time [s]", "tip velocity [m/s]", "base acceleration [m/s^2]"]
    names += [f"channel {k} [V]" for k in range(4, count + 1)]
    return separator.join(names[:count] if count > 1 else ["tip velocity [m/s]"])


def _separator(header: str) -> str:
    """The column separator of a file whose header line is ``header``: a semicolon or a tab
    when the line holds one (files written with a decimal comma), else a comma; a header of
    one column separates nothing, and its values may carry a decimal comma."""
    return next((sep for sep in SEPARATORS if sep in header),
                "," if _HEADER.match(header) is None else ";")


def _plural(count: int, noun: str) -> str:
    return f"{count} {noun}{'' if count == 1 else 's'}"


@dataclass
class Table:
    """A CSV file read: its columns, the values (rows x columns, in each column's written
    unit), each row's line number in the file, and how far each time value may lie from the
    time it stands for (half a unit of its last printed digit, in its written unit; zeros
    without a time column)."""

    columns: list[Column]
    data: np.ndarray
    lines: np.ndarray
    time_rounding: np.ndarray
    #: whether the time column holds single-precision numbers (:func:`_single_precision`)
    time_single: bool = False
    #: the column separator found
    separator: str = ","
    #: the encoding the file was read in (``"utf-8"``, ``"utf-16"`` or :data:`SINGLE_BYTE`)
    encoding: str = "utf-8"


class _Printing:
    """How a time column was printed, learnt from its cells: to a fixed number of decimals
    (``%.6f``: every cell may be off by 5e-7) or of significant digits (``%g``: ``3.99961``
    by 5e-6, ``0.000390625`` far less), trailing zeros dropped or not. A value's rounding is
    the larger of the two the column's longest cells show."""

    def __init__(self, rows: int) -> None:
        self.magnitude = np.full(rows, np.nan)      # floor(log10 |t|) of each cell
        self.decimals = 0
        self.digits = 1

    def add(self, row: int, text: str) -> None:
        try:
            value = Decimal(text)
        except InvalidOperation:
            return
        _, digits, exponent = value.as_tuple()
        if not isinstance(exponent, int):
            return
        self.decimals = max(self.decimals, -exponent)
        if value:
            self.magnitude[row] = value.adjusted()
            self.digits = max(self.digits, len(digits))

    def rounding(self, rows: int) -> np.ndarray:
        """Half a unit of the last digit each of the first ``rows`` cells stands for."""
        fixed = 0.5 * 10.0 ** -self.decimals
        significant = 0.5 * 10.0 ** (self.magnitude[:rows] - self.digits + 1)
        return np.fmax(fixed, significant)


def read_csv(path: str | Path, decimal_mark: str | None = None,
             skip: Collection[int] = (), header_line: int | None = None) -> Table:
    """The columns and values of a CSV file (:class:`Table`), without the columns numbered
    ``skip`` (from 1: a hammer's force, a sample index); with ``header_line`` (from 1), the
    header row is that line and the lines above it are left out (an export's notes on itself).

    The separator is found on the header row (:func:`_separator`); with semicolons or tabs, a
    comma in a value is its decimal mark, and a file that holds both a decimal comma and a
    point (a thousands separator?) is refused rather than read a thousand times off, as is one
    whose every value with a mark reads as a number grouped in thousands (``25.300``, never
    ``0.125`` or ``2.5``) unless ``decimal_mark`` (``"."`` or ``","``) says which the file
    uses.
    """
    path = Path(path)
    # (a Windows program in a Western European language writes µ and ² in one byte each)
    text, encoding = read_text_and_encoding(path, EXPECTED, utf16=True, fallback=SINGLE_BYTE)
    if "\x00" in text:
        raise InputFileError(f"{path}: holds NUL characters (UTF-16 text without its byte-order "
                             f"mark?); expected {EXPECTED}")
    # (a CSV written on Windows by a writer that adds its own \r to each \r\n ends every
    # line with \r\r\n: one line end, not a blank line after each row)
    lines = text.replace("\r\r\n", "\n").splitlines()
    numbers: list[int] = []          # the file's line number of each line the reader took

    first = header_line or 1
    if first > len(lines):
        raise InputFileError(f"--header-line {first}: {path} has {_plural(len(lines), 'line')}; "
                             "expected the number of the line that holds its header row")
    if header_line is not None and (_BLANK.fullmatch(lines[first - 1])
                                    or lines[first - 1].lstrip().startswith("#")):
        raise InputFileError(f"--header-line {first}: line {first} of {path} is "
                             f"{'blank' if _BLANK.fullmatch(lines[first - 1]) else 'a comment'}; "
                             "expected the line that holds its header row 'name [unit],...'")

    def table():
        for number, line in enumerate(lines[first - 1:], start=first):
            if not _BLANK.fullmatch(line) and not line.lstrip().startswith("#"):
                numbers.append(number)
                yield line

    rows = table()
    header = next(rows, None)
    if header is None:
        found = "only comments" if any(not _BLANK.fullmatch(line) for line in lines) else "empty"
        raise InputFileError(f"{path}: {found}; expected a header row 'name [unit],...' and "
                             "data")
    # a universal file's datasets open with '    -1' and the dataset's number, each printed
    # in 6 characters ('    58' for a function such as a time record)
    if header.rstrip() == "    -1":
        following = next(rows, "")
        if _UFF_DATASET.fullmatch(following.rstrip()):
            raise InputFileError(
                f"{path}: is a universal file (UFF, dataset {following.split()[0]}), not a CSV "
                f"file; expected {EXPECTED}: export the channels as CSV from the program that "
                "wrote it")
        rows = itertools.chain([following], rows) if following else rows
    separator = _separator(header)
    if _numbers_only(header, separator):
        # numpy's savetxt writes its header row as a comment ("# time [s],v [m/s]")
        above = _commented_header(path, lines, numbers[0]) if header_line is None else None
        if above is None and header_line is not None:
            raise InputFileError(f"--header-line {header_line}: line {numbers[0]} of {path} "
                                 "holds numbers, not a header row; expected the line that holds "
                                 "its header row 'name [unit],...'")
        if above is None:
            cells = len(_cells(header, separator))
            raise InputFileError(
                f"{path}: line {numbers[0]} holds numbers, not a header row: the file has "
                f"none; expected a first row naming its {_plural(cells, 'column')} "
                f"'name [unit]', e.g. '{_example_header(cells, separator)}'")
        numbers.insert(0, above)
        rows = itertools.chain([header], rows)
        header = lines[above - 1].lstrip()[1:]
        separator = _separator(header)
    # Blank lines are accepted above the first row and after the last; between, one is a
    # missing sample: skipped, it would move every later sample by a sample period. (Line
    # numbers from 1; the file's lines are scanned in place, nothing per line is kept.)
    def holds_row(number: int) -> bool:
        text = lines[number - 1]
        return not _BLANK.fullmatch(text) and not text.lstrip().startswith("#")

    reader = csv.reader(itertools.chain([header], rows), delimiter=separator, strict=True)
    try:
        cells = _trimmed(next(reader))
        width = len(cells)
        kept = _kept_columns(path, skip, width, numbers[0])
        cells = [cells[i] for i in kept]
        header_rows = 1
        try:
            columns = _parse_header(path, cells, numbers[0], [i + 1 for i in kept])
        except InputFileError as exc:
            # an analyser's names on one row and their units on the next
            columns = _names_and_units(path, cells, reader, numbers[0],
                                       (kept, width) if len(kept) != width else None)
            if columns is None:
                raise InputFileError(f"{exc}{_later_header(path, lines, numbers[0])}") from None
            header_rows = 2
        # (after the header: the lines above the first row of an export that holds a few
        # lines about itself are refused as a header, not as samples missing)
        top = numbers[header_rows - 1]               # the header's last row
        first = next((n for n in range(top + 1, len(lines) + 1) if holds_row(n)), None)
        last = next((n for n in range(len(lines), top, -1) if holds_row(n)), 0)
        if first is not None:
            blank = next((n for n in range(first + 1, last) if _BLANK.fullmatch(lines[n - 1])),
                         None)
            if blank is not None:
                text = lines[blank - 1]
                _missing_sample(path, blank, separator in text or bool(text.strip()))
            for number in range(top + 1, last):
                text = lines[number - 1]
                if "#" in text and _error_row(text, separator):
                    raise InputFileError(
                        f"{path}: line {number} begins with {text.split(separator)[0].strip()!r}"
                        " (a spreadsheet's error value in a row of samples, not a comment): a "
                        "sample is missing there (skipped, every later sample would move one "
                        "sample period early); expected a number in every cell, and '#' only "
                        "before a comment")
        time = next((i for i, c in enumerate(columns) if c.is_time), None)
        data = np.empty((len(lines), len(columns)))
        printing = _Printing(len(lines))
        row_lines = np.empty(len(lines), dtype=np.int64)
        count, read = 0, header_rows             # rows kept; rows read, the header first
        marks: dict[str, tuple[int, str]] = {}   # the first value with each decimal mark
        grouped = True          # every value with a mark so far reads as thousands (25.300)
        for row in reader:
            read += 1
            line = numbers[-1]
            if reader.line_num != read:              # one line a row
                raise InputFileError(f"{path}: line {numbers[read - 1]}: a quoted value spans "
                                     f"several lines; expected {EXPECTED}")
            if not any(cell.strip() for cell in row):   # empty cells alone ('"";""')
                if line < last:
                    _missing_sample(path, line, True)
                continue                                 # a sheet's blank rows at its end
            if len(row) == width + 1 and not row[-1].strip():
                row = row[:-1]
            if len(row) != width:
                raise InputFileError(
                    f"{path}: line {line} has {_plural(len(row), 'value')}; the header has "
                    f"{_plural(width, 'column')} (separated by "
                    f"{_SEPARATOR_NAMES[separator]})"
                )
            if len(kept) != width:
                row = [row[i] for i in kept]
            for col, cell in enumerate(row):
                value_text = cell.strip()
                if separator != ",":
                    for mark in ",.":
                        if mark in value_text and mark not in marks:
                            marks[mark] = (line, cell)
                    if decimal_mark is not None and _OTHER_MARK[decimal_mark] in value_text:
                        raise InputFileError(
                            f"{path}: line {line}, column {columns[col].number} "
                            f"({columns[col].written}): "
                            f"{cell!r} holds {_OTHER_MARK[decimal_mark]!r}, and the decimal "
                            f"mark given is {decimal_mark!r}; expected no thousands separators")
                    if grouped and ("," in value_text or "." in value_text):
                        grouped = bool(_GROUPED.fullmatch(value_text))
                    value_text = value_text.replace(",", ".")
                data[count, col] = _number(path, line, columns[col], cell, value_text,
                                           separator == ",")
                if col == time:
                    printing.add(count, value_text)
            row_lines[count] = line
            count += 1
    except csv.Error as exc:
        raise InputFileError(f"{path}: line {numbers[reader.line_num - 1]}: {exc}; expected "
                             f"{EXPECTED}") from None
    if len(marks) == 2:
        (comma_line, comma), (point_line, point) = marks[","], marks["."]
        raise InputFileError(
            f"{path}: line {comma_line} has {comma!r} (a decimal comma) and line {point_line} "
            f"{point!r} (a point: a thousands separator?); expected one decimal mark in the "
            "whole file and no thousands separators"
        )
    if grouped and marks and decimal_mark is None:
        mark, (line, cell) = next(iter(marks.items()))
        raise InputFileError(
            f"{path}: every value with a {mark!r} has one {mark!r} and three digits after it, "
            f"and none lies between -1 and 1 (line {line}: {cell!r}): a thousands separator "
            f"({cell.strip()} read as {cell.strip().replace(mark, '')}) cannot be told from a "
            "decimal mark; expected "
            f"--decimal-mark '{mark}' if it is the decimal mark, or the file exported without "
            "thousands separators")
    if count < 2:
        raise InputFileError(f"{path}: fewer than two data rows")
    rounding = printing.rounding(count) if time is not None else np.zeros(count)
    single = time is not None and _single_precision(data[:count, time], printing)
    return Table(columns, data[:count], row_lines[:count], rounding, single, separator,
                 encoding)


def _single_precision(values: np.ndarray, printing: "_Printing") -> bool:
    """Whether a time column holds single-precision numbers (LabVIEW's SGL, a float32
    array): printed to 9 significant digits or fewer, the most a float32 needs, or printed in
    full and each exactly a float32."""
    with np.errstate(over="ignore"):
        exact = bool(np.all(values.astype(np.float32).astype(np.float64) == values))
    return printing.digits <= 9 or exact


def _missing_sample(path: Path, line: int, cells: bool) -> NoReturn:
    """Refuse the blank line ``line`` (empty ``cells``, or nothing but spaces) among the rows."""
    found = "has no values (separators alone)" if cells else "is blank"
    raise InputFileError(
        f"{path}: line {line} {found}: a sample is missing there (skipped, every later sample "
        "would move one sample period early); expected a row of values on every line from the "
        "first row to the last: blank lines only above the first row or after the last, and "
        "'#' comment lines anywhere"
    )


def _number(path: Path, line: int, column: Column, cell: str, text: str,
            commas: bool) -> float:
    """The finite value of ``cell`` (read as ``text``) on file line ``line`` of a file whose
    columns are separated by commas (``commas``) or not."""
    where = f"{path}: line {line}, column {column.number} ({column.written})"
    try:
        value = float(text)
    except ValueError:
        if not text or text.upper() in _MISSING_MARKS:
            _missing_value(where, cell)
        hint = (" (a decimal comma in a comma-separated file? separate the columns with "
                "semicolons)" if commas and "," in cell else _grouping_hint(cell))
        raise InputFileError(f"{where}: {cell!r} is not a number{hint}") from None
    if math.isnan(value):
        _missing_value(where, cell)
    if not math.isfinite(value):
        raise InputFileError(f"{where}: {cell!r} (an overflow of the recorder?); expected a "
                             "finite number")
    return value


#: A number whose digits are grouped by thousands (1.234,5 or 1,234.5, 1 234,5, 1'234.5).
_DIGIT_GROUPS = re.compile(r"[+-]?\d{1,3}(?P<group>[.,' \u00a0])\d{3}(?:(?P=group)\d{3})*"
                           r"(?P<decimal>[.,]\d*)?")


def _grouping_hint(cell: str) -> str:
    """A hint naming the thousands separator when ``cell`` is a number grouped by thousands
    (a spreadsheet's display format exported as is), else ''."""
    found = _DIGIT_GROUPS.fullmatch(cell.strip())
    if found is None:
        return ""
    group, decimal = found["group"], found["decimal"]
    if decimal and decimal[0] == group:     # one mark for both: not a grouped number
        return ""
    return (f" (its digits are grouped by thousands with {group!r}: export the numbers "
            f"without thousands separators, e.g. {cell.strip().replace(group, '')!r})")


#: What spreadsheets and analysers write for a value they do not have (besides an empty cell
#: and NaN, which read as missing too).
_MISSING_MARKS = {"#NV", "#N/A", "#NA", "N/A", "NA", "--", "-", "?", "NULL", "NONE"}


def _missing_value(where: str, cell: str) -> NoReturn:
    """Refuse a cell that holds no value (empty, NaN, ``#N/A``: a sample the recorder lost)."""
    written = "is empty" if not cell.strip() else f"holds {cell.strip()!r}"
    raise InputFileError(
        f"{where} {written}: a missing sample (the recorder lost it, or the export left it "
        "out); expected a finite number in every cell: the analyses need every sample at its "
        "place. Export the record again, or cut the file before or after the gap")


def _kept_columns(path: Path, skip: Collection[int], width: int, line: int) -> list[int]:
    """The indices of the columns of a header row of ``width`` cells (file line ``line``)
    left when the columns numbered ``skip`` (from 1) are left out."""
    outside = sorted(number for number in skip if not 1 <= number <= width)
    if outside:
        raise InputFileError(
            f"--skip {outside[0]}: {path} has {_plural(width, 'column')} (header row, line "
            f"{line}); expected a column number from 1 to {width}")
    left_out = set(skip)
    kept = [i for i in range(width) if i + 1 not in left_out]
    if not kept:
        raise InputFileError(f"--skip leaves none of the {_plural(width, 'column')} of {path}; "
                             "expected at least one data column kept")
    return kept


def _check_rate(rate: float, where: str) -> float:
    """``rate`` (Hz) if it lies within :data:`~fsi_lab.runcheck.CHANNEL_RATES_HZ`."""
    low, high = CHANNEL_RATES_HZ
    if not (np.isfinite(rate) and low <= rate <= high):
        raise InputFileError(f"{where}: a sample rate of {rate:g} Hz; expected {low:g} to "
                             f"{high:g} Hz")
    return rate


def _refuse_gaps(path: Path, time: np.ndarray, lines: np.ndarray, steps: np.ndarray,
                 allowed: np.ndarray) -> None:
    """Refuse a time column with samples missing (steps of 1.5 typical steps or more beyond
    their tolerance ``allowed``, s, at no more than one step in a hundred): a DAQ's buffer
    overrun, a dropped block, two exports joined. Reading it at a steady rate
    (``--ignore-time``) would join the two sides of each gap and move every later sample
    early, which shifts the frequency."""
    typical = float(np.median(steps))
    with np.errstate(invalid="ignore"):
        gaps = np.flatnonzero((steps >= 1.5 * typical) & (steps - typical > allowed))
    if gaps.size == 0 or gaps.size > steps.size // 100:    # none, or the stamps' own rounding
        return
    first = int(gaps[0])
    missing = steps[first] / typical - 1.0
    more = f" (and {gaps.size - 1} more gap(s) after it)" if gaps.size > 1 else ""
    places = max(0, 1 - math.floor(math.log10(typical)))    # a tenth of a step
    raise InputFileError(
        f"{path}: the time column jumps from {time[first]:.{places}f} s to "
        f"{time[first + 1]:.{places}f} s at "
        f"line {lines[first + 1]}, where its steps are {typical:.6g} s: about {missing:.0f} "
        f"samples are missing there{more} (a buffer overrun, a dropped block, two exports "
        f"joined); expected samples at a steady rate. --ignore-time would join the two sides "
        f"and put every later sample {steps[first] - typical:.3g} s early, which shifts the "
        f"frequency: import the part before line {lines[first + 1]} and the part from it on "
        f"as two files (the header row on each), or export the record again"
    )


def _rate_from_time(path: Path, time: np.ndarray, lines: np.ndarray, rounding: np.ndarray,
                    given: float | None, single: bool = False) -> float:
    """The sample rate (Hz) of the time column's values ``time`` (s) on file lines ``lines``,
    each within ``rounding`` (s) of the time it stands for (and, ``single``, within the
    single-precision error of it): ``given`` (``--rate``) when the column agrees with it."""
    steps = np.diff(time)
    with np.errstate(over="ignore", invalid="ignore"):
        span = float(time[-1] - time[0])
    step = span / steps.size
    if np.any(steps < 0):
        # A column printed with too few digits repeats a time; only rows out of order (or
        # records joined) make it go back, and read at a steady rate they would stay so.
        back = int(np.argmax(steps < 0))
        raise InputFileError(
            f"{path}: the time column goes back from {time[back]:.9g} s to "
            f"{time[back + 1]:.9g} s at line {lines[back + 1]}: its rows are out of order "
            "(or records were joined); expected times that increase row by row. Sort the rows "
            "by time, or import each record as a file of its own (--ignore-time would keep "
            "the rows in the file's order)")
    if not np.all(steps > 0):
        raise InputFileError(f"{path}: the time column does not increase (line "
                             f"{lines[int(np.argmin(steps > 0)) + 1]}: printed with too few "
                             f"digits for its step?){_WITHOUT_TIME}")
    # A column printed to a few digits moves each step by up to a unit of the last one
    # (2560 Hz to 6 decimals: steps of 0.000390 and 0.000391 s).
    # Never half a step or more: a column printed to a step's resolution (whole ms at 1 kHz)
    # would otherwise pass a missing sample.
    # A column kept in single precision (LabVIEW's SGL, float32 arrays) errs by its unit in
    # the last place, 6e-8 of the time, at each end of a step.
    last_place = FLOAT32_EPS * np.maximum(np.abs(time[:-1]), np.abs(time[1:])) if single \
        else np.zeros(steps.size)
    with np.errstate(over="ignore", invalid="ignore"):
        allowed = np.minimum(np.maximum.reduce([np.full(steps.size, TIME_TOLERANCE * step),
                                                (rounding[:-1] + rounding[1:]) * (1 + 1e-9),
                                                2.0 * last_place]), 0.49 * step)
        excess = np.abs(steps - step) - allowed
    if not float(np.max(excess)) <= 0.0:
        worst = int(np.nanargmax(np.where(np.isnan(excess), np.inf, excess)))
        _refuse_gaps(path, time, lines, steps, allowed)
        raise InputFileError(
            f"{path}: the time column is not uniformly sampled (step {steps[worst]:.6g} s at "
            f"line {lines[worst + 1]} against a mean of {step:.6g} s); expected uniform "
            f"sampling, within {TIME_TOLERANCE:.1%} of a step or the rounding of the digits "
            f"printed{_WITHOUT_TIME}"
        )
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        rate = (time.size - 1) / span
        # the rate's uncertainty from the rounding of the two ends
        spread = rate * float(rounding[0] + rounding[-1]) / span
    where = f"{path}: the time column (steps of {step:.6g} s) gives"
    measured = rate
    if np.isfinite(rate) and abs(rate - round(rate)) <= spread:
        rate = float(round(rate))        # a whole number of Hz within the rounding
    elif np.isfinite(rate):
        # A time column printed in decimal misses the sample clock by its rounding (10 kHz
        # read back as 10000.0000000011 Hz); no clock is stable to 10 significant digits.
        rate = float(f"{rate:.10g}")
    if given is not None:
        if not abs(given - measured) <= max(spread, 1e-9 * given):
            raise InputFileError(
                f"--rate {given:g}: the time column of {path} gives {rate:.10g} Hz; leave out "
                "--rate (the time column sets the rate) or give the rate the column shows"
            )
        return _check_rate(given, f"--rate {given:g}")
    return _check_rate(rate, where)


#: Largest sensor delay accepted on import, s (a vibrometer's is about a millisecond).
MAX_DELAY_S = 1.0


def _calibrations(path: Path, columns: list[Column], sensitivities: Mapping[str, str]
                  ) -> dict[str, tuple[float, str]]:
    """Each ``--sensitivity`` read (:func:`~fsi_lab.units.parse_sensitivity`): volts per SI
    unit and that unit, by column name; each must name a column written in volts."""
    units = {c.name: c.unit for c in columns if not c.is_time}
    out = {}
    for name, text in sensitivities.items():
        if name not in units:
            raise InputFileError(f"--sensitivity {name}={text}: {name!r} is not a data column "
                                 f"of {path}; expected one of {', '.join(units)}")
        if QUANTITY_OF_UNIT[next(c.base for c in columns if c.name == name)] != "voltage":
            raise InputFileError(f"--sensitivity {name}={text}: the column is written in "
                                 f"{units[name]}, already calibrated; expected a column in V "
                                 "or mV")
        parsed = parse_sensitivity(text)
        if parsed is None:
            raise InputFileError(f"--sensitivity {name}={text}: not understood; expected "
                                 f"{SENSITIVITY_FORM}")
        out[name] = parsed
    return out


def _check_analysis_inputs(path: Path, columns: list[Column], reference: str | None,
                           delays: Mapping[str, float],
                           calibrations: Mapping[str, tuple[float, str]]) -> None:
    """The reference must be an acceleration column (once calibrated) and each delay name a
    data column."""
    quantities = {c.name: QUANTITY_OF_UNIT[calibrations[c.name][1] if c.name in calibrations
                                           else c.base]
                  for c in columns if not c.is_time}
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


#: A time column left out whose mean rate differs from --rate by more than this share (or its
#: printed digits' share of its span) gets a note.
TIME_RATE_NOTE = 0.005


def _note_time_rate(path: Path, time: np.ndarray, rounding: np.ndarray, rate: float,
                    notes: list[str]) -> None:
    """Note that a time column left out (``--ignore-time``) runs at another mean rate than
    ``rate`` (Hz): every frequency read from the record moves by their ratio. ``time`` in s,
    ``rounding`` how far each value may lie from the time it stands for (s)."""
    span = float(time[-1] - time[0]) if time.size > 1 else 0.0
    if not (math.isfinite(span) and span > 0.0):
        return
    mean_rate = (time.size - 1) / span
    slack = float(rounding[0] + rounding[-1]) / span
    if abs(mean_rate / rate - 1.0) > max(TIME_RATE_NOTE, slack):
        notes.append(f"{path}: the time column left out (--ignore-time) runs at {mean_rate:.6g} "
                     f"Hz on average, not the {rate:g} Hz given with --rate, which is used: "
                     "were the rate wrong, every frequency read from the record would be "
                     f"{rate / mean_rate:.4g} times the true one")


def import_csv(path: str | Path, out: str | Path, rate: float | None,
               reference: str | None = None, delays: Mapping[str, float] | None = None,
               sensitivities: Mapping[str, str] | None = None,
               decimal_mark: str | None = None, notes: list[str] | None = None,
               ignore_time: bool = False, skip: Collection[int] = (),
               header_line: int | None = None) -> Path:
    """Write the CSV file ``path`` as the run file ``out``; returns ``out``.

    Parameters
    ----------
    path
        CSV file with header ``name [unit]`` (:func:`read_csv`).
    out
        Run file to create; must not exist (nothing is ever overwritten).
    rate
        Sample rate, Hz; may be None when the file has a ``time [s]`` column, which then sets
        it; given beside one, it must agree with the column (within the column's printed
        digits) and is stored as given (a column printed to 6 decimals at 2560 Hz reads
        2560.0007 Hz; a whole number of Hz within that rounding is taken without it).
    reference
        The base acceleration column, stored as the root attribute ``reference``:
        ``fsi-lab analyze`` uses it as the profile's ``[analysis] reference`` (base motion
        removed by HVD, transfer functions, the modal model).
    delays
        Signal delay of a column's sensor, s, by column name (a vibrometer's); the column's
        time origin ``t0`` is moved back by it, as a run does with the vibrometer's delay.
    sensitivities
        The sensitivity of the sensor behind a column written in volts, by column name, as
        :func:`~fsi_lab.units.parse_sensitivity` reads it (``"200mV/(mm/s)"``): the column is
        stored in the sensor's SI unit (volts over the sensitivity), with the sensitivity in
        its ``sensitivity`` and ``sensitivity_units`` attributes, as a run stores a channel.
    decimal_mark
        ``"."`` or ``","``: the decimal mark of a file separated by semicolons or tabs whose
        values could be grouped in thousands (:func:`read_csv`); None: as found.
    ignore_time
        Leave the time column out (one printed with too few digits, or a scope's time stamps
        with jitter): the samples start at 0 s and follow at ``rate``, which must be given.
    notes
        A list the sentences the user should read about the import are appended to (the
        file read as Windows-1252, not UTF-8); None: not kept.
    skip
        Numbers (from 1) of the file's columns to leave out (a hammer's force, a sample
        index): they are not read; the run file's ``skipped_columns`` names them.
    header_line
        The file's line (from 1) that holds the header row; the lines above it (an export's
        notes on itself) are left out. None: the first line that is not blank or a comment.
    """
    path, out = Path(path), Path(out)
    delays = dict(delays or {})
    table = read_csv(path, decimal_mark, skip, header_line)
    columns, data, lines = table.columns, table.data, table.lines
    if table.encoding == SINGLE_BYTE and notes is not None:
        cells = [f"{c.written} [{c.unit}]" for c in columns]
        read = [cell for cell in cells if not cell.isascii()]
        notes.append(f"{path}: not UTF-8; read as Windows-1252 (the text of Excel and analysers "
                     "on Western European Windows)"
                     + (f", which gives the header {', '.join(map(repr, read))}" if read else "")
                     + "; if that reads wrong, save the file as UTF-8")
    if decimal_mark == "," and table.separator == ",":
        raise InputFileError(f"--decimal-mark ',': {path} separates its columns with commas; "
                             "expected a decimal comma only in a file separated by semicolons "
                             "or tabs")
    # the names as the header wrote them, or as their channels are named
    delays = {_channel_name(k): v for k, v in delays.items()}
    reference = _channel_name(reference) if reference else reference
    calibrations = _calibrations(path, columns, {_channel_name(k): v for k, v
                                                 in (sensitivities or {}).items()})
    _check_analysis_inputs(path, columns, reference, delays, calibrations)
    volts = [c.name for c in columns
             if QUANTITY_OF_UNIT.get(c.base) == "voltage" and c.name not in calibrations]
    if volts and notes is not None:
        notes.append(f"{path}: {', '.join(volts)} {'is' if len(volts) == 1 else 'are'} in volts "
                     "without --sensitivity: kept in volts (a drive signal stays so; a "
                     "sensor's gives frequencies, but not the motion it measures: C_i, C_f, "
                     f"backbones){voltage_hint('voltage')}")
    times = [i for i, column in enumerate(columns) if column.is_time]
    if len(times) > 1:
        raise InputFileError(f"{path}: header columns {columns[times[0]].number} and "
                             f"{columns[times[1]].number} are both time columns; expected at "
                             "most one 'time [s]' column")
    if len(times) == len(columns):
        raise InputFileError(f"{path}: only a time column; expected data columns 'name [unit]' "
                             "beside it")
    t0 = 0.0
    if ignore_time and rate is None:
        raise InputFileError("--ignore-time: the sample rate is then --rate's; expected "
                             "--rate HZ beside it")
    if times and not ignore_time:
        factor = columns[times[0]].factor
        time = data[:, times[0]] * factor
        rate = _rate_from_time(path, time, lines, table.time_rounding * factor, rate,
                               table.time_single)
        t0 = float(time[0])
        if abs(t0) > MAX_T0_S:
            raise InputFileError(f"{path}: line {lines[0]}: the time column starts at {t0:g} s; "
                                 f"expected a start within {MAX_T0_S:g} s of 0 (a time "
                                 f"of day or since 1904?){_WITHOUT_TIME}")
    elif rate is None:
        raise InputFileError(f"{path}: no 'time [s]' column; give the sample rate with --rate HZ")
    else:
        _check_rate(rate, f"--rate {rate:g}")
        if times and notes is not None:
            factor = columns[times[0]].factor
            _note_time_rate(path, data[:, times[0]] * factor, table.time_rounding * factor,
                            rate, notes)
    values = {}
    for col, column in enumerate(columns):
        if column.is_time:
            continue
        si_unit, factor = to_si(column.base)
        if column.name in calibrations:             # volts over volts per SI unit
            factor /= calibrations[column.name][0]
            si_unit = calibrations[column.name][1]
        with np.errstate(over="ignore"):
            values[column.name] = data[:, col] * (column.factor * factor)
        if not np.all(np.isfinite(values[column.name])):
            line = lines[int(np.argmax(~np.isfinite(values[column.name])))]
            raise InputFileError(f"{path}: line {line}, column {column.number} "
                                 f"({column.written}): too large to convert from {column.unit} "
                                 f"to {si_unit}; expected a finite value")
    if out.exists():
        raise InputFileError(f"{out}: already exists; choose another output file")
    _, run_uuid, started = new_run_path(out.parent)
    writer = RunFileWriter(out, {
        "uuid": run_uuid, "start_time": started, "kind": "imported",
        "source_file": str(path), "profile": "", "software_version": software_version(),
        **({"source_encoding": table.encoding} if table.encoding != "utf-8" else {}),
        **({"reference": reference} if reference else {}),
        **({"skipped_columns": sorted(set(skip))} if skip else {}),
    })
    try:
        for column in columns:
            name = column.name
            if name not in values:
                continue
            sensitivity, unit = calibrations.get(name, (1.0, to_si(column.base)[0]))
            writer.create_channel(name, {
                "units": unit, "quantity": QUANTITY_OF_UNIT[unit],
                "sample_rate": rate, "t0": t0 - delays.get(name, 0.0),
                "sensitivity": sensitivity,
                **({"sensitivity_units": f"V/({unit})"} if name in calibrations else {}),
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
