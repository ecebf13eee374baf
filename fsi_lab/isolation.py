"""Reading first in a child process what may crash or hang the HDF5 library.

HDF5 reads a damaged file's metadata without checksums; some damage (a flipped byte in a
string's heap address) makes the C library crash the whole process, and a cyclic index could
make it loop. :func:`crash_or_hang` runs the read in a forked child first: if the child dies or
does not come back in time, the file is refused; otherwise the caller reads it itself (the same
code, which then fails, if at all, with an ordinary exception).
"""

from __future__ import annotations

import contextlib
import faulthandler
import os
import select
import signal
import time
from typing import Callable, ContextManager

#: A child that does not come back within this long (plus a second per 20 MB of file) is
#: stopped and the file refused.
TIMEOUT_S = 60.0
BYTES_PER_S = 20e6
_POLL_S = 0.005


def crash_or_hang(task: Callable[[], object], size_bytes: int = 0,
                  hold: ContextManager | None = None) -> str | None:
    """Run ``task`` in a forked child; None when it returned or raised, else what went wrong
    (a crash by a signal, or no answer in time), in words.

    Parameters
    ----------
    task
        The reading to try; its result and exceptions stay in the child.
    size_bytes
        Size of the file read, bytes: the time allowed grows with it.
    hold
        A (re-entrant) lock held across the fork, so that no other thread of the caller is
        inside the library at that moment and the child inherits it consistent (h5py's lock).
    """
    return in_child(task, size_bytes, hold)[0]


def in_child(task: Callable[[], object], size_bytes: int = 0,
             hold: ContextManager | None = None) -> tuple[str | None, bool]:
    """Run ``task`` in a forked child, for its effects (e.g. a file it writes).

    Returns
    -------
    problem, returned
        ``problem`` as :func:`crash_or_hang` gives it (None, or a crash or hang in words);
        ``returned`` is True when ``task`` returned without raising. Where processes cannot
        be forked, ``task`` runs in the caller (its exceptions then propagate).
    """
    if not hasattr(os, "fork"):  # pragma: no cover - fsi-lab runs on Linux
        task()
        return None, True
    timeout = TIMEOUT_S + size_bytes / BYTES_PER_S
    with hold if hold is not None else contextlib.nullcontext():
        pid = os.fork()
        if pid == 0:  # the child: never returns into the caller's code
            code = 0
            try:
                faulthandler.disable()
                task()
            except BaseException:  # noqa: BLE001 - an ordinary failure is the parent's to report
                code = 3
            os._exit(code)
    try:
        status = _wait(pid, timeout)
        if status is None:
            return f"reading it did not finish within {timeout:.3g} s", False
        pid = 0
    finally:
        if pid:  # timed out, or the parent was interrupted: the child must not outlive it
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        name = signal.Signals(os.WTERMSIG(status)).name
        return f"the HDF5 library crashed reading it ({name})", False
    return None, os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0


def _wait(pid: int, timeout: float) -> int | None:
    """The wait status of child ``pid``, or None if it is still running after ``timeout`` s.
    Woken by the child's exit where the system offers it (a pidfd), else by polling."""
    deadline = time.monotonic() + timeout
    fd = os.pidfd_open(pid) if hasattr(os, "pidfd_open") else None
    try:
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                return status
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            if fd is not None:
                select.select([fd], [], [], remaining)
            else:  # pragma: no cover - older kernels
                time.sleep(min(_POLL_S, remaining))
    finally:
        if fd is not None:
            os.close(fd)
