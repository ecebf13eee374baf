"""The benchmark table: one row per measured figure, with its reference and target."""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable


@dataclass
class Row:
    """One benchmark line.

    ``ours`` and ``reference`` are measured in the same run; ``target`` states the goal in
    words (e.g. "<= 0.5 s", ">= 5x"); ``met`` says whether our figure meets it (None: a figure
    shown for what it is, with no target).
    """

    name: str
    ours: str
    reference: str
    target: str
    met: bool | None


# --------------------------------------------------------------------------- honest timings
#: How many times every figure is measured, ours and each reference's alike.
REPEAT = 5
ROOT = Path(__file__).resolve().parents[1]


def times(func: Callable[[], object], repeat: int = REPEAT) -> list[float]:
    """Wall times of ``repeat`` calls of ``func``, s (warm figures: call it once before)."""
    out = []
    for _ in range(repeat):
        started = time.perf_counter()
        func()
        out.append(time.perf_counter() - started)
    return out


def figure(samples: list[float], unit: str = "s", scale: float = 1.0, digits: int = 3) -> str:
    """``median (min-max, n=N)`` of ``samples`` times ``scale``, in ``unit``."""
    values = [v * scale for v in samples]
    return (f"{statistics.median(values):.{digits}f} {unit} ({min(values):.{digits}f}-"
            f"{max(values):.{digits}f}, n={len(values)})")


def median(samples: list[float]) -> float:
    return statistics.median(samples)


def cold_times(imports: str, call: str, prepare: str = "",
               repeat: int = REPEAT) -> tuple[list[float], list[float]]:
    """The cold start of ``call``: in each of ``repeat`` fresh interpreters, with an empty numba
    cache of its own (``NUMBA_CACHE_DIR``, so that every compiled function compiles), the time
    of ``imports`` and of the first ``call``, s; ``prepare`` (the data) runs between them,
    untimed. All three are Python statements run from the repository's root."""
    script = (f"import json, time\nstarted = time.perf_counter()\n{imports}\n"
              f"imported = time.perf_counter()\n{prepare}\nready = time.perf_counter()\n"
              f"{call}\ndone = time.perf_counter()\n"
              "print(json.dumps([imported - started, done - ready]))\n")
    imported, called = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as cache:
            proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                                  check=False, cwd=ROOT, timeout=900,
                                  env={**os.environ, "NUMBA_CACHE_DIR": cache})
        if proc.returncode != 0:
            raise RuntimeError(f"cold start of {call!r} failed: {proc.stderr[-500:]}")
        first, second = json.loads(proc.stdout.strip().splitlines()[-1])
        imported.append(first)
        called.append(second)
    return imported, called


def process_times(argv: list[str], repeat: int = REPEAT, env: dict | None = None,
                  before: Callable[[], object] | None = None) -> list[float]:
    """Wall times of ``repeat`` runs of the command ``argv``, from process start to exit, s
    (``before`` is called untimed before each run); each run must exit 0."""
    out = []
    for _ in range(repeat):
        if before is not None:
            before()
        started = time.perf_counter()
        proc = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              check=False, cwd=ROOT, timeout=900,
                              env={**os.environ, **(env or {})})
        out.append(time.perf_counter() - started)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(argv)} exited {proc.returncode}: "
                               f"{proc.stderr[-300:]}")
    return out


def cache_times(argv: list[str], folder: Path, repeat: int = REPEAT,
                env: dict | None = None) -> tuple[list[float], list[float]]:
    """Cold and warm wall times of the command ``argv`` (:func:`process_times`), s: cold,
    ``repeat`` runs each with an empty numba cache (``NUMBA_CACHE_DIR`` in ``folder``, emptied
    before each run); warm, ``repeat`` runs with a cache filled by one untimed run. Every run
    is a fresh process."""
    cold_cache, warm_cache = folder / "cold-numba-cache", folder / "warm-numba-cache"

    def empty_cache() -> None:
        shutil.rmtree(cold_cache, ignore_errors=True)

    cold = process_times(argv, repeat, {**(env or {}), "NUMBA_CACHE_DIR": str(cold_cache)},
                         before=empty_cache)
    warm_env = {**(env or {}), "NUMBA_CACHE_DIR": str(warm_cache)}
    process_times(argv, 1, warm_env)  # fills the cache
    return cold, process_times(argv, repeat, warm_env)


def render(rows: list[Row]) -> str:
    header = ("benchmark", "fsi-lab", "reference", "target", "met")
    cells = [header] + [(r.name, r.ours, r.reference, r.target,
                         "-" if r.met is None else "yes" if r.met else "NO") for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(header))]
    lines = ["  ".join(c[i].ljust(widths[i]) for i in range(len(header))) for c in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
