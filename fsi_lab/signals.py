"""Ctrl+C and SIGTERM: from the first line of ``fsi-lab``'s main an exception (exit code 130),
while the bench is driven an abort, held back while the bench is being made safe and the run
file finalised, and noted so that one whose exception a library swallows is raised at the next
checkpoint."""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Any, Callable

from fsi_lab.errors import RunAborted
from fsi_lab.events import Progress

#: The error recorded for a run (or a command) ended by Ctrl+C.
INTERRUPTED = "interrupted (Ctrl+C)"


def exception_for(signum: int) -> BaseException:
    """What a signal becomes: KeyboardInterrupt for Ctrl+C, :class:`RunAborted` otherwise."""
    if signum == signal.SIGINT:
        return KeyboardInterrupt()
    return RunAborted(f"received {signal.Signals(signum).name}")


class SignalNote:
    """Remembers the first Ctrl+C or SIGTERM, to raise it again at a checkpoint.

    The exception a signal handler raises can land inside a library's cleanup code (a
    destructor, a callback), which swallows it; the note is not lost that way. Give it to
    :class:`RunSignals` as ``on_signal`` and subscribe :meth:`checkpoint` to an event bus:
    every progress event then raises a signal that was received.
    """

    def __init__(self) -> None:
        self.signum: int | None = None

    def __call__(self, signum: int) -> None:
        if self.signum is None:
            self.signum = signum

    def check(self) -> None:
        """Raise what :func:`exception_for` makes of the signal received, if any."""
        if self.signum is not None:
            raise exception_for(self.signum)

    def checkpoint(self, event) -> None:
        """An event-bus subscriber: :meth:`check` at every progress event."""
        if isinstance(event, Progress):
            self.check()


class RunSignals:
    """Turns SIGTERM into RunAborted and can hold signals back while finalizing.

    Use: :meth:`install`, then :meth:`held` around what must not be cut short, then
    :meth:`restore`. Outside the main thread (the GUI's workers) it does nothing: signals are
    the main thread's.

    Parameters
    ----------
    on_signal
        Called with the signal number before the exception is raised, e.g. to set a flag the
        caller checks at its own pace: an exception raised from a handler can land inside a
        library's cleanup code, which may swallow it, and a flag is not lost that way.
    """

    def __init__(self, on_signal: Callable[[int], None] | None = None) -> None:
        self.active = threading.current_thread() is threading.main_thread()
        self._saved: dict[int, Any] = {}
        self.pending: list[int] = []
        self._on_signal = on_signal
        self._silenced = False

    def install(self) -> None:
        """Keep the present handlers and turn SIGTERM into :class:`RunAborted` (and Ctrl+C
        into KeyboardInterrupt after ``on_signal``, when given)."""
        if not self.active:
            return
        for signum in (signal.SIGINT, signal.SIGTERM):
            self._saved[signum] = signal.getsignal(signum)
        self._set_raising()

    def _set_raising(self) -> None:
        signal.signal(signal.SIGTERM, self._raise)
        signal.signal(signal.SIGINT, self._raise if self._on_signal is not None
                      else self._saved[signal.SIGINT])

    def _raise(self, signum, frame):
        if self._on_signal is not None:
            self._on_signal(signum)
        if self._silenced:
            self.pending.append(signum)
            return
        raise exception_for(signum)

    def silence(self) -> None:
        """From now on signals are only noted in ``pending`` (while an interruption is being
        reported, a second Ctrl+C must not cut the report short)."""
        self._silenced = True

    def _defer(self, signum, frame):
        self.pending.append(signum)

    @contextlib.contextmanager
    def held(self):
        """Within this block Ctrl+C and SIGTERM are noted, not raised (safe state, final write)."""
        if self.active:
            signal.signal(signal.SIGINT, self._defer)
            signal.signal(signal.SIGTERM, self._defer)
        try:
            yield
        finally:
            if self.active:
                self._set_raising()

    def raise_pending(self) -> None:
        """Raise what :meth:`held` noted, at a point the caller chose: KeyboardInterrupt for
        Ctrl+C, :class:`RunAborted` for SIGTERM. (Raised from the handler instead, the
        exception could land inside a library's cleanup code, which may swallow it.)"""
        if self.pending:
            raise exception_for(self.pending[0])

    def restore(self) -> None:
        """Put back the handlers :meth:`install` found; ``pending`` keeps what was held."""
        for signum, handler in self._saved.items():
            signal.signal(signum, handler)
