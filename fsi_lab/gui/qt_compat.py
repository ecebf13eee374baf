"""Work-arounds for defects of particular Qt binding releases.

PySide6 6.12.0 returns ``None``, ``True`` and ``False`` to Python without counting the reference
it hands over: every call of a void Qt method (``processEvents()``, ``QTimer.start()``, ...) drops
one reference to ``None``, every ``Signal.emit()`` one to ``True``, some calls one to ``False``.
On Python 3.12 and later these objects are immortal and nothing happens; on Python 3.11 a GUI
that repaints 30 times a second brings the count to zero within minutes and the interpreter
aborts ("none_dealloc" / "bool_dealloc: ... refcount error in a C extension"). PySide6 6.11.x
does not have the defect, and the ``gui`` extra of pyproject.toml excludes 6.12.0
(``PySide6-Essentials>=6.6,!=6.12.0``).

The probe stays for environments that install PySide6 some other way: when the loss is measured
here (not guessed from version numbers), the three singletons are given so many extra
references (2**40) that no session can use them up. With a binding that loses nothing the probe
changes nothing.
"""

from __future__ import annotations

import ctypes
import sys
import warnings

from PySide6.QtCore import QObject, Signal

RESERVE = 1 << 40
PROBE_CALLS = 64
_applied = False


class _Probe(QObject):
    ping = Signal()


def lost_references() -> dict[str, int]:
    """References to None and True lost by ``PROBE_CALLS`` void calls and emits."""
    probe = _Probe()
    none_before = sys.getrefcount(None)
    for _ in range(PROBE_CALLS):
        probe.setObjectName("probe")
    none_lost = none_before - sys.getrefcount(None)
    true_before = sys.getrefcount(True)
    for _ in range(PROBE_CALLS):
        probe.ping.emit()
    true_lost = true_before - sys.getrefcount(True)
    return {"None": none_lost, "True": true_lost}


def guard_singleton_refcounts() -> bool:
    """Apply the work-around once if this PySide6 loses references; returns whether it did."""
    global _applied
    if _applied or sys.version_info >= (3, 12) or sys.implementation.name != "cpython":
        return _applied
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lost = lost_references()
    if max(lost.values()) >= PROBE_CALLS // 2:
        for singleton in (None, True, False):
            ctypes.c_ssize_t.from_address(id(singleton)).value += RESERVE
        _applied = True
    return _applied
