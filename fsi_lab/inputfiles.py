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
    path = Path(path)
    fd = _open_regular(path, expected, error)
    with os.fdopen(fd, "rb") as handle:
        try:
            data = handle.read() if max_bytes is None else handle.read(max_bytes + 1)
        except OSError as exc:
            raise error(f"{path}: cannot be read ({exc.strerror}); expected {expected}") from None
    if max_bytes is not None and len(data) > max_bytes:
        raise error(f"{path}: larger than {max_bytes:,} bytes; expected {expected}")
    utf16_bom = data.startswith((b"\xff\xfe", b"\xfe\xff"))
    try:
        text = data.decode("utf-16" if utf16 and utf16_bom else "utf-8")
    except UnicodeDecodeError as exc:
        if utf16_bom:
            found = (f"damaged UTF-16 text (at offset {exc.start})" if utf16 else
                     "UTF-16 text (a spreadsheet's 'Unicode text' export?)")
        else:
            found = f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}"
            if data[exc.start] >= 0x80:
                found += (": a Latin-1 or Windows-1252 character such as µ or ², written in "
                          "one byte?")
            found += ")"
        raise error(f"{path}: {found}; expected {expected} saved as UTF-8") from None
    return text.removeprefix("\ufeff")
