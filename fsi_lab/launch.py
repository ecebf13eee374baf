"""The ``fsi-lab`` console script's entry point: Ctrl+C and SIGTERM honoured while it starts.

Importing the command (numpy among its modules) takes a tenth of a second or more on a busy
machine; a SIGTERM in that time used to kill the process (exit 143, nothing said) and a Ctrl+C
printed a traceback of the import. This module, which imports nothing but the standard
library's ``signal``, notes either signal from its first line; :func:`main` then hands the
note to :func:`fsi_lab.cli.main`, which ends the command at once as it ends any interrupted
command (one message, exit 130). Only the interpreter's own start, before this module is
imported, is left to the default handlers.
"""

from __future__ import annotations

import signal

#: Ctrl+C and SIGTERM received while the command was being imported, in order.
noted: list[int] = []


def _note(signum: int, frame: object) -> None:
    noted.append(signum)


_previous = {signum: signal.signal(signum, _note) for signum in (signal.SIGINT, signal.SIGTERM)}


def main() -> int:
    """``fsi-lab``: import the command with signals noted, run it, return its exit code."""
    try:
        from fsi_lab.cli import main as command

        return command(started_with=noted)
    finally:  # the handlers found at start-up are the caller's again
        for signum, handler in _previous.items():
            signal.signal(signum, handler)
