"""Fixtures of the GUI tests: the real main window on the in-process simulated bench.

Every wait has a timeout; every window is closed and every thread it started is finished at the
end of its test (a run still going is aborted first).
"""

from __future__ import annotations

import gc
from pathlib import Path

import h5py
import numpy as np
import pytest
from PySide6.QtCore import QCoreApplication, QEvent  # the gui extra: make test installs it

from fsi_lab.gui.app import MainWindow, _configure_pyqtgraph, settle
from fsi_lab.runfile import RunFileWriter, write_analysis

ROOT = Path(__file__).resolve().parents[2]
# Generous limits for waits on conditions: they only matter when something is broken, and the
# suite must pass on a slow shared machine busy with other work.
#: the safety check of a profile (a worker thread; the first one imports the beam model)
CHECK_TIMEOUT_MS = 60000
#: reading a run file on a worker thread and drawing it
LOAD_TIMEOUT_MS = 60000
#: a widget's state following a signal (a button enabled, a label updated)
UI_TIMEOUT_MS = 30000

#: The paper's wet experiment on the in-process simulated bench paced in real time; the
#: excitation and the analysis chain are those of profiles/wet-beam-sim.toml.
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


def wet_inprocess_profile(folder: Path, duration: float = 3.0, sample_rate: float = 10000.0,
                          extra_channels: str = "") -> Path:
    """WET_INPROCESS followed by the [excitation] and [analysis] of the wet profile."""
    wet = (ROOT / "profiles" / "wet-beam-sim.toml").read_text()
    tail = wet[wet.index("[excitation]"):]
    path = folder / "wet-inprocess.toml"
    path.write_text(WET_INPROCESS.format(duration=duration, sample_rate=sample_rate,
                                         extra_channels=extra_channels) + "\n" + tail)
    return path
#: a run in a child process (spawned: it imports fsi-lab afresh), or its analysis
RUN_TIMEOUT_MS = 180000


@pytest.fixture
def make_window(qtbot, tmp_path):
    """Build main windows; each is closed, its threads finished, and deleted afterwards."""
    _configure_pyqtgraph()
    windows: list[MainWindow] = []

    def make(registry=None, **kwargs) -> MainWindow:
        window = MainWindow(registry=registry, out_dir=kwargs.pop("out_dir", tmp_path / "runs"))
        window.resize(1366, 768)  # a common laptop screen
        window.show()
        qtbot.waitExposed(window)
        windows.append(window)
        return window

    yield make
    for window in windows:
        if window.run_control.running:
            window.run_control.abort()
            qtbot.waitUntil(lambda w=window: not w.run_control.running, timeout=RUN_TIMEOUT_MS)
        qtbot.waitUntil(lambda w=window: not w.busy(), timeout=RUN_TIMEOUT_MS)
        window.close()
        assert not window.isVisible()
        window.pool.wait_all()
        window.dispose()
    QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
    gc.collect()  # wrappers of deleted Qt objects go before the next test builds plots


#: The smallest plot area (the view box inside the axes) a person can read, in pixels.
MIN_PLOT_AREA = (100, 80)


def plot_areas(root):
    """(where, width, height) of the data area of every plot shown under ``root``."""
    import pyqtgraph as pg

    areas = []
    for figure in root.findChildren(pg.GraphicsView):
        if not figure.isVisible():
            continue
        for item in figure.scene().items():
            if isinstance(item, pg.PlotItem) and item.isVisible():
                box = item.getViewBox().sceneBoundingRect()
                where = f"{type(figure.parent()).__name__}/{figure.objectName() or 'figure'}"
                areas.append((where, round(box.width()), round(box.height())))
    return areas


def assert_readable(window, what):
    """Once the layouts have settled, every plot shown has at least MIN_PLOT_AREA."""
    assert settle(window), f"{what}: the layout did not settle"
    areas = plot_areas(window)
    assert areas, f"{what}: no plot shown"
    small = [a for a in areas if a[1] < MIN_PLOT_AREA[0] or a[2] < MIN_PLOT_AREA[1]]
    assert not small, f"{what}: plots below {MIN_PLOT_AREA} px: {small}"
    return areas


def wait_checked(qtbot, window, ok: bool | None = True):
    """Wait for the safety check of the values now in the forms."""
    qtbot.waitUntil(lambda: window.session.current is not None, timeout=CHECK_TIMEOUT_MS)
    checked = window.session.current
    if ok is not None:
        assert checked.ok is ok, checked.error or checked.report
    return checked


def wait_finished(qtbot, window):
    qtbot.waitUntil(lambda: not window.run_control.running, timeout=RUN_TIMEOUT_MS)
    outcome = window.run_control.outcome
    assert outcome is not None
    return outcome


def write_run(path: Path, rate: float = 1000.0, seconds: float = 4.0, analysis: bool = True,
              failed: str | None = None, c_i: float = 0.65, c_f: float = 33.0,
              name: str = "synthetic", hvd_components: int = 2,
              hvd_bands: np.ndarray | None = None) -> Path:
    """A run file with a decaying two-mode velocity and analysis groups laid out as the
    analysis plugins store them (``/analysis/<channel>/<plugin>/``); HVD finds
    ``hvd_components`` components (beyond two, weak ones at higher frequencies)."""
    n = int(rate * seconds)
    t = np.arange(n) / rate
    env = np.vstack([0.05 * np.exp(-0.8 * t), 0.01 * np.exp(-2.0 * t)]
                    + [0.002 / k * np.exp(-3.0 * t) for k in range(1, hvd_components - 1)])
    freq = np.vstack([17.0 - 0.3 * np.exp(-0.8 * t), 2.0 + 0 * t]
                     + [40.0 * k + 0 * t for k in range(1, hvd_components - 1)])
    comps = env * np.cos(2 * np.pi * np.cumsum(freq, axis=1) / rate)
    velocity = comps.sum(axis=0)
    profile = '[analysis]\nchain = []\nchannels = ["tip_velocity"]\n'
    writer = RunFileWriter(path, {"uuid": "0" * 32, "start_time": "2026-01-01T00:00:00",
                                  "kind": "measured", "run_name": name, "profile": profile,
                                  "software_version": "test", "plugin_versions": {},
                                  "profile_path": "", "overrides": []})
    writer.create_channel("tip_velocity", {"units": "m/s", "quantity": "velocity",
                                           "sample_rate": rate, "t0": 0.0, "sensitivity": 8.0})
    writer.create_channel("base_acceleration", {"units": "m/s^2", "quantity": "acceleration",
                                                "sample_rate": rate, "t0": 0.0,
                                                "sensitivity": 0.0102})
    writer.append("tip_velocity", velocity)
    writer.append("base_acceleration", 0.1 * np.sin(2 * np.pi * 30 * t))
    writer.set_attrs({"exit_status": "completed", "stop_time": "2026-01-01T00:00:05"})
    writer.close()
    if not analysis:
        return path
    amp = np.linspace(0.004, 0.0005, 40)
    vel_amp = amp * 2 * np.pi * 17
    zeta = 0.01 + 2.0 * amp
    cq = c_i + 8 * c_f * 2 * np.pi * 17 * amp / (3 * np.pi)
    freqs = np.fft.rfftfreq(n, 1 / rate)
    spectrum = np.abs(np.fft.rfft(velocity)) * 2 / n
    pad = np.full(10, np.nan)  # rows of unequal length are padded with NaN

    def two_rows(a, b):
        return np.vstack([a, np.concatenate([b[:-10], pad])])

    zc_t = np.arange(0.05, seconds - 0.05, 1 / 34.0)
    groups = {
        "tip_velocity/spectrum": {"datasets": {"frequency": freqs, "amplitude": spectrum,
                                               "peak_frequencies": np.array([2.0, 17.0])},
                                  "attrs": {}, "params": {"window": "hann"}},
        "tip_velocity/hvd": {"datasets": {"components": comps, "envelopes": env,
                                          "frequencies": freq, "residual": velocity * 0,
                                          "edge_mask": np.zeros_like(comps, dtype=np.uint8),
                                          "cutoffs": np.array([4.0, 1.0, *range(
                                              30, 30 + 40 * (hvd_components - 2), 40)])},
                             "units": {"components": "m/s", "envelopes": "m/s",
                                       "frequencies": "Hz", "cutoffs": "Hz"},
                             "attrs": {"n_components": hvd_components},
                             "params": {"components": hvd_components}},
        "tip_velocity/instantaneous": {
            "datasets": {"frequency_times": two_rows(zc_t, zc_t),
                         "frequency": two_rows(17 + 0 * zc_t, 2 + 0 * zc_t)}, "params": {}},
        "tip_velocity/backbone": {"datasets": {"amplitude": two_rows(amp, amp),
                                               "frequency": two_rows(17 - 10 * amp, 2 - 5 * amp),
                                               "velocity_amplitude": two_rows(vel_amp, vel_amp),
                                               "velocity_frequency": two_rows(17 - 10 * amp,
                                                                              2 - 5 * amp)},
                                  "attrs": {}, "params": {}},
        "tip_velocity/damping": {"datasets": {"amplitude": amp[None, :],
                                              "velocity_amplitude": vel_amp[None, :],
                                              "zeta": zeta[None, :]},
                                 "attrs": {"method": "envelope-fit"}, "params": {}},
        "tip_velocity/equivalent-damping": {
            "datasets": {"amplitude": amp[None, :], "c_q": cq[None, :]},
            "attrs": {"component_0_c_i": c_i, "component_0_c_f": c_f, "component_0_r2": 0.914},
            "params": {"confidence": 0.95}},
    }
    if hvd_bands is not None:  # the decomposition of the "bands" method: a band per mode
        groups["tip_velocity/hvd"]["datasets"]["bands"] = np.asarray(hvd_bands, dtype=float)
        groups["tip_velocity/hvd"]["units"]["bands"] = "Hz"
        groups["tip_velocity/hvd"]["attrs"]["method"] = "bands"
    for content in groups.values():
        content["attrs"] = {"status": "ok", **content.get("attrs", {})}
    if failed:
        groups[f"tip_velocity/{failed}"] = {"attrs": {"status": "failed",
                                                      "error": f"{failed}: too few peaks"},
                                            "params": {}}
    summary = {"run": str(path), "channels": {"tip_velocity": {
        "spectrum_peaks_hz": [2.0, 17.0],
        "components": [{"index": 0, "frequency_hz": 17.0,
                        "equivalent_damping": {"c_i": c_i, "c_f": c_f, "r2": 0.914,
                                               "c_i_ci95": [c_i - 0.1, c_i + 0.1],
                                               "c_f_ci95": [c_f - 3, c_f + 3]}},
                       {"index": 1, "frequency_hz": 2.0}]}}}
    write_analysis(path, groups, summary)
    return path


def with_specimen_and_convention(path: Path, convention: str, point: float = 0.08) -> Path:
    """The run's profile (of :func:`write_run`) gains a specimen measured at ``point`` (m);
    its equivalent-damping the amplitude convention ``convention``."""
    with h5py.File(path, "r+") as f:
        f.attrs["profile"] = (f.attrs["profile"] + "\n[specimen]\nlength = 0.08\n"
                              f"measurement_point = {point}\n")
        f["analysis/tip_velocity/equivalent-damping"].attrs["amplitude_convention"] = convention
    return path


def write_foreign(path: Path) -> Path:
    """A valid HDF5 file that is not an fsi-lab run file."""
    with h5py.File(path, "w") as handle:
        handle.create_dataset("data", data=np.arange(10))
    return path


def write_corrupt(path: Path) -> Path:
    """Not an HDF5 file at all, though it is called .h5."""
    path.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\x00garbage" * 100)
    return path
