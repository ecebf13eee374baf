"""Run every ``bench/bench_*.py`` module and print one table.

Each module exposes ``rows()`` returning a list of :class:`bench.Row`; our figure and the
reference it is compared with are measured in the same run, the same number of times
(:data:`bench.table.REPEAT`), and given as median (min-max, n=N): warm (in-process after one
untimed call, or a whole process with the numba cache filled) and cold (the first call in a
fresh process with an empty numba cache, imports apart), with the floor of the work measured in
the same run (one FFT of the length, reading the bytes, an idle window's heartbeat).
Rows without a target show a figure for what it is ("-" under met).
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import time

import bench
from bench.table import Row, render


def main() -> int:
    names = sorted(m.name for m in pkgutil.iter_modules(bench.__path__)
                   if m.name.startswith("bench_"))
    wanted = sys.argv[1:]
    all_rows: list[Row] = []
    for name in names:
        if wanted and not any(w in name for w in wanted):
            continue
        module = importlib.import_module(f"bench.{name}")
        started = time.perf_counter()
        print(f"running {name} ...", file=sys.stderr, flush=True)
        all_rows.extend(module.rows())
        print(f"  {name} took {time.perf_counter() - started:.1f} s", file=sys.stderr, flush=True)
    print(render(all_rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
