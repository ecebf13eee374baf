"""Events a run emits; the CLI renders them and the GUI subscribes to them."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

log = logging.getLogger("fsi_lab")

STATES = ("configuring", "armed", "running", "finalizing", "analyzing",
          "completed", "aborted", "failed")


@dataclass(frozen=True)
class StateChanged:
    """The run entered ``state`` (one of :data:`STATES`)."""

    state: str
    detail: str = ""


@dataclass(frozen=True)
class Progress:
    """``fraction`` (0..1) of the current stage is done."""

    stage: str
    fraction: float
    message: str = ""


@dataclass(frozen=True)
class DataBlock:
    """Calibrated samples just acquired, per channel; ``t0`` is the time of the first, s."""

    t0: float
    sample_rate: float
    data: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass(frozen=True)
class LogRecord:
    """A message for the experimenter; ``level`` is a logging level name."""

    level: str
    message: str


Event = StateChanged | Progress | DataBlock | LogRecord
Subscriber = Callable[[Event], None]


class EventBus:
    """Delivers events to subscribers in order; a failing subscriber never stops a run."""

    def __init__(self) -> None:
        self._subscribers: list[Subscriber] = []

    def subscribe(self, subscriber: Subscriber) -> Callable[[], None]:
        """Add ``subscriber``; returns a function that removes it again."""
        self._subscribers.append(subscriber)
        return lambda: self._subscribers.remove(subscriber)

    def emit(self, event: Event) -> None:
        for subscriber in list(self._subscribers):
            try:
                subscriber(event)
            except Exception:
                log.exception("event subscriber %r failed", subscriber)

    def log(self, level: str, message: str) -> None:
        """Emit a :class:`LogRecord`."""
        self.emit(LogRecord(level, message))
