"""The desktop GUI, measured offscreen (QT_QPA_PLATFORM=offscreen).

Every figure is measured :data:`~bench.table.REPEAT` times, ours and its reference's alike, and
given as median (min-max, n).

- Frames per second of the live plots with 4 channels holding 10 s at 10 kS/s each (the ring
  buffers full, a new 0.1 s block before every frame), each frame drawn and painted in full
  (decimation, spectra on every third frame, a synchronous repaint of the 1400 x 900 plot
  area); the reference is the same plots fed the raw 100,000 samples per channel (no
  decimation). Warm: each figure the frames drawn in :data:`MEASURE_S`, after one untimed
  frame. Cold: the first frame in a fresh process (the plots shown empty, then filled), the
  imports of the live plots timed apart.
- The longest stall of the UI thread during a real run: the paper's wet experiment on the
  in-process simulated bench, paced in real time, 4 channels at 10 kS/s for 10 s (the run runs
  in a child process, the live plots in the window); then, separately, the longest stall while
  its analysis chain runs (``fsi-lab analyze`` in a child process) and the analysis views are
  drawn. A 5 ms heartbeat timer on the UI thread records the longest gap between its ticks
  beyond its interval. Each repetition is a fresh process (an empty numba cache of its own,
  which its run and analysis processes share) whose window makes two runs: the first is the
  cold figure, the second the warm one. The floor is the same heartbeat's longest gap in the
  same window, idle for as long as a run lasts, before the first run: what the machine's
  scheduling alone costs the UI thread.
"""

from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import numpy as np

from bench.table import REPEAT, Row, cold_times, figure, median

ROOT = Path(__file__).resolve().parents[1]
CHANNELS = 4
RATE = 10_000.0
WINDOW_S = 10.0
BLOCK_S = 0.1
MEASURE_S = 2.0
HEARTBEAT_MS = 5


def _app():
    from PySide6.QtWidgets import QApplication

    import fsi_lab.gui  # noqa: F401 - applies the binding work-arounds

    app = QApplication.instance() or QApplication(sys.argv[:1])
    from fsi_lab.gui.app import _configure_pyqtgraph

    _configure_pyqtgraph()
    return app


def live_plots(max_points: int) -> tuple:
    """The live plots of :data:`CHANNELS` channels shown at 1400 x 900 and their 10 s window
    filled at :data:`RATE`, with their own frame timer stopped (frames are drawn by
    :func:`frame`); returns the application, the plots and the next block's feed."""
    from fsi_lab.events import DataBlock
    from fsi_lab.gui.live_plots import LivePlots

    app = _app()
    plots = LivePlots(window_s=WINDOW_S, max_points=max_points)
    plots.timer.stop()  # frames are driven here, as fast as they can be drawn
    plots.resize(1400, 900)
    plots.show()
    app.processEvents()  # shown empty
    names = [f"ch{i}" for i in range(CHANNELS)]
    plots.configure({name: "V" for name in names}, RATE)
    rng = np.random.default_rng(0)
    block_n = int(BLOCK_S * RATE)
    t0 = [0.0]

    def feed() -> None:
        plots.on_block(DataBlock(t0[0], RATE, {n: rng.normal(size=block_n) for n in names}))
        t0[0] += BLOCK_S

    for _ in range(int(WINDOW_S / BLOCK_S)):  # fill the 10 s window
        feed()
    return app, plots, feed


def frame(app, plots, feed) -> float:
    """One frame of the live plots: a new block, drawn and painted in full; its wall time, s."""
    begin = time.perf_counter()
    feed()
    paints = plots.paints
    plots.refresh()
    app.processEvents()  # the frame is painted here, as the event loop would
    if plots.paints == paints:
        plots.graphics.viewport().repaint()
    return time.perf_counter() - begin


def close_plots(app, plots) -> None:
    plots.close()
    plots.deleteLater()
    app.processEvents()


def frame_rates(max_points: int, repeat: int = REPEAT,
                seconds: float = MEASURE_S) -> tuple[list[float], float]:
    """Frames per second of the live plots in each of ``repeat`` spans of ``seconds`` (after
    one untimed frame), and the slowest frame of them all, s."""
    app, plots, feed = live_plots(max_points)
    frame(app, plots, feed)
    rates, slowest = [], 0.0
    for _ in range(repeat):
        frames = 0
        started = time.perf_counter()
        while time.perf_counter() - started < seconds:
            slowest = max(slowest, frame(app, plots, feed))
            frames += 1
        rates.append(frames / (time.perf_counter() - started))
    close_plots(app, plots)
    return rates, slowest


def first_frames(max_points: int, repeat: int = REPEAT) -> tuple[list[float], list[float]]:
    """The imports of the live plots and their first frame (:func:`live_plots`, then
    :func:`frame`) in each of ``repeat`` fresh processes with an empty numba cache, s."""
    return cold_times("import bench.bench_gui as g\nimport fsi_lab.gui.live_plots",
                      "g.frame(app, plots, feed)",
                      prepare=f"app, plots, feed = g.live_plots({max_points})", repeat=repeat)


#: The wet experiment on the in-process simulated bench (as in tests/gui/conftest.py).
WET_INPROCESS = """
[run]
name = "wet beam on the in-process bench"
duration = {duration}
sample_rate = {sample_rate}
block_duration = 0.1

[safety]
max_drive_v = 2.0
max_gain = 10.0
max_stroke_mm = 5.0

[shaker]
suspension_hz = 30.0
damping_ratio = 0.08
mm_per_volt = 0.5

[specimen]
length = 0.08
width = 0.01275
thickness = 0.00008
youngs_modulus = 240e9
density = 7200.0
fluid = "water"
drag_coefficient = 1.8
measurement_point = 0.08

[model]
modes = 4
c_i = 0.65
c_f = 33.0

[bench.source]
plugin = "inprocess-source"

[bench.amplifier]
plugin = "inprocess-amplifier"
gain = 2.0

[bench.vibrometer]
plugin = "inprocess-vibrometer"
range = "125mm/s/V"

[bench.acquisition]
plugin = "inprocess-acquisition"
realtime = true

[channels.drive]
quantity = "voltage"
unit = "V"
sensitivity = 1.0
input = 1

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
{extra_channels}
"""


def _profile(folder: Path, duration: float = WINDOW_S) -> Path:
    """``duration`` s at 10 kS/s in real time, 4 channels (drive, base acceleration, tip
    velocity, spare), the wet profile's excitation and analysis chain."""
    wet = (ROOT / "profiles" / "wet-beam-sim.toml").read_text()
    spare = '\n[channels.spare]\nquantity = "voltage"\nunit = "V"\nsensitivity = 1.0\ninput = 4\n'
    path = folder / "wet-gui-bench.toml"
    path.write_text(WET_INPROCESS.format(duration=duration, sample_rate=RATE,
                                         extra_channels=spare)
                    + "\n" + wet[wet.index("[excitation]"):])
    return path


def _spin(app, seconds: float, until=None, what: str = "") -> None:
    """Process the window's events for ``seconds``, or until ``until()`` holds (then
    ``seconds`` is a time limit, and reaching it is an error naming ``what``)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if until is not None and until():
            return
        app.processEvents()
        time.sleep(0.001)
    if until is not None and not until():
        raise RuntimeError(f"GUI bench: {what} not within {seconds:g} s")


def stall_session(runs: int = 2, duration: float = WINDOW_S, idle_s: float = WINDOW_S) -> dict:
    """The main window's UI-thread stalls in this process, ms: the longest gap of a
    :data:`HEARTBEAT_MS` heartbeat beyond its interval while the window is idle for ``idle_s``
    (the floor), then for each of ``runs`` runs of ``duration`` s in a row, while the run goes
    (start to safe state and file closed: ``acquire``) and afterwards while its analysis runs
    and the views are drawn (``end``), with the run's exit status."""
    from PySide6.QtCore import QTimer

    from fsi_lab.gui.app import MainWindow, freeze_startup_objects

    app = _app()
    with tempfile.TemporaryDirectory() as folder:
        window = MainWindow(out_dir=Path(folder) / "runs")
        window.resize(1680, 1050)
        window.show()
        app.processEvents()
        freeze_startup_objects()  # as fsi-lab gui does
        window.open_profile(_profile(Path(folder), duration))
        _spin(app, 60, window.run_control.can_start, "the profile checked")
        result = {"idle": 0.0, "runs": []}
        phase: list = [None]  # "idle" or the run's entry
        last = [time.perf_counter()]

        def beat() -> None:
            now = time.perf_counter()
            gap = (now - last[0] - HEARTBEAT_MS / 1e3) * 1e3
            last[0] = now
            if os.environ.get("FSI_LAB_BENCH_TRACE") and gap > 30:
                print(f"stall {gap:.0f} ms in state {window.run_control.state} "
                      f"blocks={window.live.blocks} frames={window.live.frames} "
                      f"paints={window.live.paints} "
                      f"last frame {window.live.last_frame_s * 1e3:.0f} ms", file=sys.stderr)
            if phase[0] == "idle":
                result["idle"] = max(result["idle"], gap)
            elif phase[0] is not None:
                key = "acquire" if window.run_control.running else "end"
                phase[0][key] = max(phase[0][key], gap)

        heartbeat = QTimer()
        heartbeat.setInterval(HEARTBEAT_MS)
        heartbeat.timeout.connect(beat)

        def measure(what, start=None, until=None) -> None:
            phase[0] = what
            last[0] = time.perf_counter()
            heartbeat.start()
            if start is not None:
                start()
            if until is None:
                _spin(app, idle_s)
            else:
                _spin(app, 120 + 3 * duration, until, "the run and its analysis")
                _spin(app, 1.0)  # the analysis views are drawn and painted
            heartbeat.stop()
            phase[0] = None

        _spin(app, 1.0)  # the experimenter looks at the window
        measure("idle")
        for _ in range(runs):
            _spin(app, 60, window.run_control.can_start, "Start enabled")
            _spin(app, 1.0)  # before Start
            before = window.last_run
            entry = {"acquire": 0.0, "end": 0.0}

            def analysed(before=before) -> bool:
                shown = window.analysis.results
                return (not window.run_control.running and not window.busy()
                        and window.last_run is not None and window.last_run != before
                        and shown is not None and shown.path.resolve() == window.last_run
                        and bool(shown.analysis))

            measure(entry, window.run_control.start, analysed)
            outcome = window.run_control.outcome
            entry["status"] = outcome.exit_status if outcome else "none"
            result["runs"].append(entry)
        window.close()
        window.pool.wait_all()
        window.dispose()
        app.processEvents()
        gc.unfreeze()
    return result


SESSION = ("import json, sys; from bench.bench_gui import stall_session; "
           "print(json.dumps(stall_session(*json.loads(sys.argv[1]))))")


def stall_sessions(repeat: int = REPEAT, runs: int = 2, duration: float = WINDOW_S,
                   idle_s: float = WINDOW_S) -> list[dict]:
    """:func:`stall_session` in each of ``repeat`` fresh processes, each with an empty numba
    cache of its own (its run and analysis processes share it)."""
    out = []
    for k in range(repeat):
        with tempfile.TemporaryDirectory() as cache:
            proc = subprocess.run(
                [sys.executable, "-c", SESSION, json.dumps([runs, duration, idle_s])],
                capture_output=True, text=True, check=False, cwd=ROOT,
                timeout=300 + runs * (200 + 3 * duration) + idle_s,
                env={**os.environ, "NUMBA_CACHE_DIR": cache, "QT_QPA_PLATFORM": "offscreen"})
        if proc.returncode != 0:
            raise RuntimeError(f"GUI stall session {k + 1} failed: {proc.stderr[-800:]}")
        out.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    return out


def rows() -> list[Row]:
    decimated = 2000
    fps, slowest = frame_rates(decimated)
    raw_fps, raw_slowest = frame_rates(10 ** 9)
    imports, first = first_frames(decimated)
    raw_imports, raw_first = first_frames(10 ** 9)
    sessions = stall_sessions()
    plots = f"GUI live plots, {CHANNELS} ch x {WINDOW_S:g} s at {RATE / 1000:g} kS/s"
    result = [
        Row(f"{plots}: frames per second, warm",
            f"{figure(fps, 'fps', digits=1)}; slowest frame {slowest * 1e3:.0f} ms",
            f"undecimated {figure(raw_fps, 'fps', digits=1)}; slowest {raw_slowest * 1e3:.0f} ms",
            ">= 30 fps", median(fps) >= 30),
        Row(f"{plots}, cold: first frame, fresh process",
            f"{figure(first, 'ms', 1e3, 0)}; imports {figure(imports, digits=2)}",
            f"undecimated {figure(raw_first, 'ms', 1e3, 0)}; imports "
            f"{figure(raw_imports, digits=2)}", "-", None),
    ]
    floor = (f"idle window, {WINDOW_S:g} s: "
             f"{figure([s['idle'] for s in sessions], 'ms', digits=0)}")
    run = f"{WINDOW_S:g} s run ({CHANNELS} ch at {RATE / 1000:g} kS/s, real time)"
    for index, when in ((0, "cold (first run of a fresh window, empty numba cache)"),
                        (1, "warm (second run)")):
        entries = [s["runs"][index] for s in sessions]
        statuses = sorted({e["status"] for e in entries})
        done = statuses == ["completed"]
        acquire = [e["acquire"] for e in entries]
        end = [e["end"] for e in entries]
        result.append(Row(f"GUI longest UI-thread stall during a {run}, {when}",
                          f"{figure(acquire, 'ms', digits=0)} (runs {', '.join(statuses)})",
                          floor, "< 50 ms", median(acquire) < 50 and done))
        result.append(Row(f"GUI longest UI-thread stall after the run (analysis in a child "
                          f"process, views drawn), {when}", figure(end, 'ms', digits=0), floor,
                          "< 50 ms", median(end) < 50 and done))
    return result


if __name__ == "__main__":
    from bench.table import render

    print(render(rows()))
