"""Helpers shared by the test modules (fixtures live in conftest.py).

Kept out of conftest.py so that test modules in sub-folders with a conftest of their own can
import them unambiguously: ``from support import cli``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PROFILES = ROOT / "profiles"
EXAMPLE_PLUGIN = Path(__file__).resolve().parent / "example_plugin"
GOOD_PROFILE = PROFILES / "wet-beam-sim.toml"


def cli(*args: str, env: dict | None = None, timeout: float = 120, cwd: Path | None = None,
        input_text: str | None = None) -> subprocess.CompletedProcess:
    """Run ``fsi-lab ARGS`` in a subprocess and return the completed process."""
    full_env = {**os.environ, **(env or {})}
    return subprocess.run([sys.executable, "-m", "fsi_lab.cli", *args], capture_output=True,
                          text=True, timeout=timeout, env=full_env, cwd=cwd, input=input_text)


def cli_json(*args: str, **kwargs) -> tuple[dict, subprocess.CompletedProcess]:
    """Run with ``--json`` and parse stdout, which must be exactly one JSON object."""
    proc = cli(*args, "--json", **kwargs)
    return json.loads(proc.stdout), proc


SIM_PROFILE = """
[run]
duration = {duration}
sample_rate = 2000.0
block_duration = 0.05

[safety]
max_drive_v = 2.0
max_gain = 10.0
max_stroke_mm = 5.0

[shaker]
suspension_hz = 30.0
damping_ratio = 0.08
mm_per_volt = 0.5

[specimen]
fluid = "water"

[model]
c_i = 0.65
c_f = 33.0

[bench.source]
plugin = "inprocess-source"

[bench.amplifier]
plugin = "inprocess-amplifier"
gain = 2.0
{amplifier_extra}

[bench.vibrometer]
plugin = "inprocess-vibrometer"
range = "125mm/s/V"

[bench.acquisition]
plugin = "inprocess-acquisition"
realtime = {realtime}
{acquisition_extra}

[channels.base_acceleration]
quantity = "acceleration"
unit = "m/s^2"
sensitivity = 0.0102
input = 2

[channels.tip_velocity]
quantity = "velocity"
unit = "m/s"
input = 3
sensor = "vibrometer"

[excitation]
plugin = "step"
amplitude = {amplitude}
duration = 0.5
{analysis}
"""


class LineReader:
    """Reads a subprocess's stream on a thread so tests can wait for a line with a timeout."""

    def __init__(self, stream) -> None:
        import queue
        import threading

        self.lines: list[str] = []
        self._queue: queue.Queue = queue.Queue()
        self._thread = threading.Thread(target=self._pump, args=(stream,), daemon=True)
        self._thread.start()

    def _pump(self, stream) -> None:
        for line in iter(stream.readline, ""):
            self._queue.put(line)
        self._queue.put(None)

    def wait_for(self, predicate, timeout: float) -> str:
        """The first line (from now on) for which ``predicate`` is true; AssertionError on
        timeout."""
        import queue
        import time

        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(f"no matching line within {timeout} s; got {self.lines[-20:]}")
            try:
                line = self._queue.get(timeout=remaining)
            except queue.Empty:
                continue
            if line is None:
                raise AssertionError("stream ended without a matching line; "
                                     f"got {self.lines[-20:]}")
            self.lines.append(line)
            if predicate(line):
                return line


def start_cli(*args: str, env: dict | None = None) -> subprocess.Popen:
    """Start ``fsi-lab ARGS`` without waiting; stderr is a text pipe."""
    return subprocess.Popen([sys.executable, "-m", "fsi_lab.cli", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, **(env or {})})


def run_main(*args: str) -> tuple[int, str, str]:
    """``fsi-lab ARGS`` in this process: the exit code, stdout and stderr.

    Much faster than :func:`cli` for the many refusals the input tests try; a usage error's
    SystemExit becomes its exit code.
    """
    import contextlib
    import io

    from fsi_lab.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(args))
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
    return code, out.getvalue(), err.getvalue()


def cli_here(*args: str) -> subprocess.CompletedProcess:
    """:func:`cli` in this process (:func:`run_main`): the same exit code, stdout and stderr,
    without a Python start-up per call (half a second of the tests that import many files)."""
    code, out, err = run_main(*args)
    return subprocess.CompletedProcess(["fsi-lab", *args], code, out, err)


def cli_json_here(*args: str) -> tuple[dict, subprocess.CompletedProcess]:
    """:func:`cli_json` in this process."""
    proc = cli_here(*args, "--json")
    return json.loads(proc.stdout), proc


def write_decay_run(path: Path, a: float = 0.5, beta: float = 2.0, frequency: float = 20.0,
                    start: float = 0.3, noise: float = 1e-3, seed: int = 0,
                    duration: float = 4.0, rate: float = 1000.0,
                    others: tuple = ()) -> Path:
    """An imported run file (no profile) of one mode's free decay with known damping: the
    velocity of ``x'' + 2 a x' + beta |x'| x' + w0^2 x = 0`` from an extremum ``start`` (m/s)
    at 0.1 s after a short forced build-up, plus white noise of RMS ``noise`` (m/s). With
    ``--mass-per-length m`` its analysis gives C_i = 2 m a and C_f = m beta. ``others``:
    ``(a, beta, frequency, start)`` of more modes, each built up and released the same way."""
    import math

    from fsi_lab.csv_import import import_csv
    from fsi_lab.dsp.laws import simulate_decay

    t = np.arange(int(duration * rate)) / rate
    early = t < 0.1
    v = np.zeros(t.size)
    for a_k, beta_k, frequency_k, start_k in ((a, beta, frequency, start), *others):
        w0 = 2 * math.pi * frequency_k
        v_k = simulate_decay("quadratic", [a_k, beta_k], w0, start_k, 0.1, t)
        v_k[early] = start_k * np.cos(w0 * (t[early] - 0.1)) * np.sin(np.pi * t[early] / 0.2)
        v += v_k
    v = v + noise * np.random.default_rng(seed).standard_normal(t.size)
    csv = path.with_suffix(".csv")
    csv.write_text("time [s],tip [m/s]\n" + "\n".join(f"{x:.6f},{y:.9g}" for x, y in zip(t, v)))
    import_csv(csv, path, None)
    csv.unlink()
    return path


def ode_path(rhs, y0, times, *, start: float | None = None, rtol: float = 1e-10,
             atol: float = 1e-13, max_step: float = 0.0) -> np.ndarray:
    """States of ``y' = rhs(t, y)`` at ``times`` (s, increasing), one row per time, from
    ``y0`` at ``start`` (s; default: the first time, and at most the first), by ODEPACK's
    LSODA (scipy's ``odeint``).

    Its steps run in compiled code: a record of a forced oscillator is integrated several times
    faster than by ``solve_ivp``, whose steps run in Python. ``max_step`` (s; 0 for none) keeps
    it from stepping over a forcing that changes within a step. A failed integration raises
    RuntimeError.
    """
    from scipy.integrate import odeint

    times = np.asarray(times, dtype=np.float64)
    first = float(times[0]) if start is None else float(start)
    if times[0] - first <= 1e-12 * max(1.0, abs(first)):
        # (a time within rounding of the start is the start: LSODA refuses output times
        # closer together than its resolution)
        grid = np.concatenate(([first], times[1:]))
    else:
        grid = np.concatenate(([first], times))
    out, info = odeint(rhs, np.asarray(y0, dtype=np.float64), grid, tfirst=True, rtol=rtol,
                       atol=atol, hmax=max_step, mxstep=10 ** 7, full_output=True)
    if info["message"] != "Integration successful.":
        raise RuntimeError(f"LSODA failed from {first} s: {info['message']}")
    return out[grid.size - times.size:]
