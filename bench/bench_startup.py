"""Start-up of the everyday commands, whole process, next to the interpreter's own floor.

Each row starts the ``fsi-lab`` command (the console script beside this interpreter) in a
process of its own, :data:`REPEAT` times after one untimed warm-up run, and gives the median
wall time and its range, from process start to exit. The reference is ``python -c "import
numpy"``, timed the same way in the same run: the least any command can take, since every one
of them needs numpy. The target (issue 14) is 0.5 s, set for ``profile check`` and ``safe``,
the commands run before every experiment, and held by the others too.

``safe`` runs on the wet profile, whose bench is the embedded simulated one: it starts the
simulated instruments and talks to them over their real wires. ``show`` reads a run file made
before the timing by ``fsi-lab simulate`` (h5py is its business).
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.table import Row

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "profiles" / "wet-beam-sim.toml"
REPEAT = 7
TARGET_S = 0.5


def _command() -> list[str]:
    """The ``fsi-lab`` console script of this environment, or the module if there is none."""
    script = Path(sys.executable).with_name("fsi-lab")
    return [str(script)] if script.exists() else [sys.executable, "-m", "fsi_lab.cli"]


def _times(argv: list[str]) -> list[float]:
    """Wall times of :data:`REPEAT` runs of ``argv`` (after one untimed), s; each must exit 0."""
    times = []
    for attempt in range(REPEAT + 1):
        started = time.perf_counter()
        proc = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              text=True, cwd=ROOT, timeout=300)
        elapsed = time.perf_counter() - started
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(argv)} exited {proc.returncode}: {proc.stderr[-300:]}")
        if attempt:
            times.append(elapsed)
    return times


def _figure(times: list[float]) -> str:
    return f"{statistics.median(times):.2f} s ({min(times):.2f}-{max(times):.2f})"


def rows() -> list[Row]:
    fsi_lab = _command()
    with tempfile.TemporaryDirectory() as out:
        run_file = Path(out) / "simulated.h5"
        subprocess.run([*fsi_lab, "simulate", str(PROFILE), "--duration", "2", "--rate", "10000",
                        "-o", str(run_file), "-q"], check=True, cwd=ROOT, timeout=300,
                       stdout=subprocess.DEVNULL)
        floor = _times([sys.executable, "-c", "import numpy"])
        reference = f'python -c "import numpy" {_figure(floor)}'
        commands = (
            ("--help", ["--help"]),
            ("profile check (wet profile)", ["profile", "check", str(PROFILE)]),
            ("safe (wet profile, embedded bench)", ["safe", str(PROFILE)]),
            ("show (a 2 s run file)", ["show", str(run_file)]),
            ("plugins", ["plugins"]),
        )
        result = []
        for label, args in commands:
            times = _times([*fsi_lab, *args])
            result.append(Row(
                f"start-up: fsi-lab {label}, median of {REPEAT} (min-max)", _figure(times),
                reference, f"<= {TARGET_S:g} s", statistics.median(times) <= TARGET_S))
    return result
