"""Start-up of the everyday commands, whole process, next to the interpreter's own floor.

Each command is the ``fsi-lab`` console script beside this interpreter, run in a process of
its own and timed from process start to exit, :data:`~bench.table.REPEAT` times cold (an empty
numba cache for each run) and as many times warm (the cache filled by one untimed run), given
as median (min-max, n). The operating system's file cache is warm in both (the files were read
before). The reference is ``python -c "import numpy"``, timed as many times in the same run: the
least any command can take, since every one of them needs numpy. The target (issue 14) is 0.5 s
warm, set for ``profile check`` and ``safe``, the commands run before every experiment, and held
by the others too; a cold row shows its figure for what it is.

``safe`` runs on the wet profile, whose bench is the embedded simulated one: it starts the
simulated instruments and talks to them over their real wires. ``show`` reads a run file made
before the timing by ``fsi-lab simulate`` (h5py is its business).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

from bench.table import Row, cache_times, figure, median, process_times

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "profiles" / "wet-beam-sim.toml"
TARGET_S = 0.5


def command() -> list[str]:
    """The ``fsi-lab`` console script of this environment, or the module if there is none."""
    script = Path(sys.executable).with_name("fsi-lab")
    return [str(script)] if script.exists() else [sys.executable, "-m", "fsi_lab.cli"]


def commands(run_file: Path) -> tuple[tuple[str, list[str]], ...]:
    """(label, arguments) of each command timed; ``show`` reads ``run_file``."""
    return (("--help", ["--help"]),
            ("profile check (wet profile)", ["profile", "check", str(PROFILE)]),
            ("safe (wet profile, embedded bench)", ["safe", str(PROFILE)]),
            ("show (a 2 s run file)", ["show", str(run_file)]),
            ("plugins", ["plugins"]))


def startup_rows(which: tuple[tuple[str, list[str]], ...], folder: Path,
                 repeat: int | None = None) -> list[Row]:
    """A cold and a warm row for each (label, arguments) of ``which``, next to the floor;
    ``folder`` holds the numba caches; ``repeat`` defaults to :data:`~bench.table.REPEAT`."""
    counts = {} if repeat is None else {"repeat": repeat}
    floor = process_times([sys.executable, "-c", "import numpy"], **counts)
    reference = f'python -c "import numpy" {figure(floor, digits=2)}'
    fsi_lab = command()
    rows = []
    for label, args in which:
        cold, warm = cache_times([*fsi_lab, *args], folder, **counts)
        name = f"start-up: fsi-lab {label}, whole process"
        rows.append(Row(f"{name}, cold (empty numba cache)", figure(cold, digits=2), reference,
                        "-", None))
        rows.append(Row(f"{name}, warm (numba cache filled)", figure(warm, digits=2), reference,
                        f"<= {TARGET_S:g} s", median(warm) <= TARGET_S))
    return rows


def rows() -> list[Row]:
    with tempfile.TemporaryDirectory() as out:
        run_file = Path(out) / "simulated.h5"
        subprocess.run([*command(), "simulate", str(PROFILE), "--duration", "2", "--rate",
                        "10000", "-o", str(run_file), "-q"], check=True, cwd=ROOT, timeout=300,
                       stdout=subprocess.DEVNULL)
        return startup_rows(commands(run_file), Path(out))
