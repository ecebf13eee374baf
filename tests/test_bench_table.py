"""The benchmark table's conventions (bench/table.py) and the rows built on them: every figure
is a median with its range and count, measured as many times for us and the reference, cold
(an empty numba cache in a fresh process) and warm. These tests check what is measured and how
it is shown, never how fast anything is."""

import re
import sys

import pytest

from bench import bench_analysis, bench_startup
from bench.table import cache_times, cold_times, figure

#: median (min-max, n=N) with a unit
FIGURE = re.compile(r"^-?\d+(\.\d+)? \S+ \(-?\d+(\.\d+)?--?\d+(\.\d+)?, n=(\d+)\)")


def test_a_figure_is_the_median_its_range_and_the_count():
    assert figure([0.3, 0.1, 0.2]) == "0.200 s (0.100-0.300, n=3)"
    assert figure([0.0123, 0.0101], "ms", 1e3, 1) == "11.2 ms (10.1-12.3, n=2)"
    assert FIGURE.match(figure([1.0, 2.0, 4.0], digits=2)).group(4) == "3"


#: One run of a command that notes how many entries its numba cache holds, then adds one.
NOTE_CACHE = ("import os, sys; d = os.environ['NUMBA_CACHE_DIR']; os.makedirs(d, exist_ok=True); "
              "open(sys.argv[1], 'a').write(f'{len(os.listdir(d))}\\n'); "
              "open(os.path.join(d, f'entry{os.getpid()}'), 'w').close()")


def test_cold_runs_start_with_an_empty_numba_cache_and_warm_runs_with_a_filled_one(tmp_path):
    log = tmp_path / "entries.txt"
    cold, warm = cache_times([sys.executable, "-c", NOTE_CACHE, str(log)], tmp_path, repeat=3)
    assert len(cold) == len(warm) == 3 and min(cold + warm) > 0
    entries = [int(line) for line in log.read_text().split()]
    # 3 cold runs, each on an emptied cache; 1 untimed run filling the warm cache; 3 warm runs
    assert entries == [0, 0, 0, 0, 1, 2, 3]


def test_a_cold_call_runs_in_a_fresh_process_with_an_empty_numba_cache():
    imported, called = cold_times(
        "import math", "assert math.sqrt(4) == 2 and not os.listdir(os.environ['NUMBA_CACHE_DIR'])"
        " and __import__('sys').modules.get('bench.table') is None", prepare="import os",
        repeat=2)
    assert len(imported) == len(called) == 2 and min(imported + called) >= 0
    with pytest.raises(RuntimeError, match="cold start of 'boom' failed"):
        cold_times("import os", "boom", repeat=1)


def test_start_up_rows_are_cold_and_warm_with_the_floor_measured_as_many_times(tmp_path):
    rows = bench_startup.startup_rows((("--help", ["--help"]),), tmp_path, repeat=2)
    assert [r.name for r in rows] == [
        "start-up: fsi-lab --help, whole process, cold (empty numba cache)",
        "start-up: fsi-lab --help, whole process, warm (numba cache filled)"]
    for row in rows:
        assert FIGURE.match(row.ours).group(4) == "2"
        assert row.reference.startswith('python -c "import numpy" ')
        assert FIGURE.match(row.reference.split('" ', 1)[1]).group(4) == "2"
    assert (rows[0].target, rows[0].met) == ("-", None)
    assert rows[1].target == "<= 0.5 s" and isinstance(rows[1].met, bool)


def test_the_whole_chain_row_runs_the_default_chain_on_its_record():
    from fsi_lab.chain import default_chain, run_chain
    from fsi_lab.registry import load_registry

    inputs = bench_analysis.chain_inputs(seconds=2.0)
    assert inputs["channels"]["tip"].data.size == 2 * bench_analysis.CHAIN_FS
    assert list(inputs["params"]) == default_chain(load_registry())
    _, summary = run_chain(**inputs)
    assert "errors" not in summary["tip"], summary["tip"].get("errors")
