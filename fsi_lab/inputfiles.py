"""Files named on the command line, opened so that no input can hang or exhaust fsi-lab.

A profile, CSV or run file must be a regular file: a FIFO would block the reader forever and a
device such as ``/dev/zero`` never ends. Text must be UTF-8 and, for profiles, of a size a
profile can have. Every refusal is an :class:`~fsi_lab.errors.InputFileError` (exit code 2)
naming the file, the problem and what is accepted.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

from fsi_lab.errors import FsiLabError, InputFileError

#: Largest profile accepted, bytes (the example profiles are about 4 kB).
MAX_PROFILE_BYTES = 1 << 20

_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def nesting(value: Any) -> tuple[int, list[str]]:
    """How deeply the dictionaries and lists of parsed input ``value`` nest, and the keys
    (``[i]`` for list items) down to the deepest; 0 for a plain value."""
    deepest: tuple[int, list[str]] = (0, [])
    stack = [(value, 0, [])]
    while stack:
        node, depth, keys = stack.pop()
        if isinstance(node, dict):
            items = [(str(k), v) for k, v in node.items()]
        elif isinstance(node, list):
            items = [(f"[{i}]", v) for i, v in enumerate(node)]
        else:
            continue
        if depth + 1 > deepest[0]:
            deepest = (depth + 1, keys)
        stack.extend((item, depth + 1, keys + [key]) for key, item in items)
    return deepest


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _open_regular(path: Path, expected: str, error: type[FsiLabError]) -> int:
    """A file descriptor of ``path`` opened for reading, refused unless a regular file.

    Opened without blocking (a FIFO would otherwise wait for a writer) and checked on the
    descriptor itself, so that what is checked is what is read.
    """
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except FileNotFoundError:
        raise error(f"{path}: no such file; expected {expected}") from None
    except OSError as exc:
        raise error(f"{path}: cannot be opened ({exc.strerror}); expected {expected}") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise error(f"{path}: is {_kind(mode)}, not a regular file; expected {expected}")
    os.set_blocking(fd, True)
    return fd


def require_regular_file(path: str | Path, expected: str,
                         error: type[FsiLabError] = InputFileError) -> Path:
    """``path`` as a Path, once it is known to be an existing regular file.

    Parameters
    ----------
    path
        The file named by the user.
    expected
        What would be accepted, in words (``"a run file (.h5)"``), for the message.
    error
        The exception class raised (exit code 2 for the input errors).
    """
    path = Path(path)
    os.close(_open_regular(path, expected, error))
    return path


#: Binary formats a user may hand over for text, by their first bytes: what the file is.
_BINARY_FORMATS = (
    (b"PK\x03\x04", "a zip archive (a spreadsheet workbook such as .xlsx or .ods?)"),
    (b"\xd0\xcf\x11\xe0", "an OLE compound file (an Excel 97-2003 .xls workbook?)"),
    (b"MATLAB 5.0 MAT-file", "a MATLAB MAT-file"),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file (a MATLAB v7.3 MAT-file, or a run file?)"),
    (b"TDSm", "a TDMS file (LabVIEW, DIAdem)"),
)


#: Encodings by the names users know them by.
_ENCODING_NAMES = {"cp1252": "Windows-1252", "latin-1": "Latin-1"}


def binary_format(data: bytes) -> str | None:
    """What the binary file that starts with ``data`` is, in words, when its first bytes
    name a format users export (``"a MATLAB MAT-file"``); None otherwise."""
    return next((name for magic, name in _BINARY_FORMATS if data.startswith(magic)), None)


def read_text(path: str | Path, expected: str, max_bytes: int | None = None,
              error: type[FsiLabError] = InputFileError, utf16: bool = False) -> str:
    """The UTF-8 text of a regular file (a leading byte-order mark is dropped).

    Parameters
    ----------
    path
        The file named by the user.
    expected
        What would be accepted, in words, for the message.
    max_bytes
        Largest size accepted, bytes; None for no limit.
    error
        The exception class raised.
    utf16
        Also read UTF-16 text that starts with its byte-order mark (a spreadsheet's "Unicode
        text" export).

    Raises
    ------
    FsiLabError
        Of class ``error``: missing, not a regular file, too large or not UTF-8.
    """
    return read_text_and_encoding(path, expected, max_bytes, error, utf16)[0]


def read_text_and_encoding(path: str | Path, expected: str, max_bytes: int | None = None,
                           error: type[FsiLabError] = InputFileError, utf16: bool = False,
                           fallback: str | None = None) -> tuple[str, str]:
    """The text of a regular file and the encoding it was read in (:func:`read_text`).

    Parameters
    ----------
    fallback
        The encoding of a file that is not UTF-8 (``"cp1252"``: a Windows program's text in
        a Western European language, where µ is the byte 0xb5 and ² 0xb2); None: refused.
        A file of a known binary format (:func:`binary_format`) is refused all the same.
    (others as :func:`read_text`)

    Raises
    ------
    FsiLabError
        Of class ``error``: missing, not a regular file, too large, binary, or in neither
        encoding.
    """
    path = Path(path)
    fd = _open_regular(path, expected, error)
    with os.fdopen(fd, "rb") as handle:
        try:
            data = handle.read() if max_bytes is None else handle.read(max_bytes + 1)
        except OSError as exc:
            raise error(f"{path}: cannot be read ({exc.strerror}); expected {expected}") from None
    if max_bytes is not None and len(data) > max_bytes:
        raise error(f"{path}: larger than {max_bytes:,} bytes; expected {expected}")
    binary = binary_format(data)
    if binary is not None:
        raise error(f"{path}: is {binary}, not text; expected {expected}")
    utf16_bom = data.startswith((b"\xff\xfe", b"\xfe\xff"))
    encoding = "utf-16" if utf16 and utf16_bom else "utf-8"
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as exc:
        # (UTF-8 characters before the bad byte: UTF-8 text damaged, not another encoding)
        if fallback is not None and not utf16_bom and data[:exc.start].isascii():
            try:
                return data.decode(fallback).removeprefix("\ufeff"), fallback
            except UnicodeDecodeError:
                pass
        if utf16_bom:
            found = (f"damaged UTF-16 text (at offset {exc.start})" if utf16 else
                     "UTF-16 text (a spreadsheet's 'Unicode text' export?)")
        else:
            found = f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}"
            if data[exc.start] >= 0x80 and fallback is None:
                found += (": a Latin-1 or Windows-1252 character such as µ or ², written in "
                          "one byte?")
            elif fallback is not None:
                found += (" after UTF-8 characters: damaged UTF-8?" if not
                          data[:exc.start].isascii() else
                          f", nor {_ENCODING_NAMES.get(fallback, fallback)} text")
            found += ")"
        raise error(f"{path}: {found}; expected {expected} saved as UTF-8") from None
    return text.removeprefix("\ufeff"), encoding
