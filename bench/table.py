"""The benchmark table: one row per measured figure, with its reference and target."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable


@dataclass
class Row:
    """One benchmark line.

    ``ours`` and ``reference`` are measured in the same run; ``target`` states the goal in
    words (e.g. "<= 0.5 s", ">= 5x"); ``met`` says whether our figure meets it.
    """

    name: str
    ours: str
    reference: str
    target: str
    met: bool


def best_time(func: Callable[[], object], repeat: int = 5) -> float:
    """Best wall time of ``repeat`` calls of ``func``, s."""
    best = float("inf")
    for _ in range(repeat):
        started = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - started)
    return best


def render(rows: list[Row]) -> str:
    header = ("benchmark", "fsi-lab", "reference", "target", "met")
    cells = [header] + [(r.name, r.ours, r.reference, r.target, "yes" if r.met else "NO") for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(header))]
    lines = ["  ".join(c[i].ljust(widths[i]) for i in range(len(header))) for c in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
