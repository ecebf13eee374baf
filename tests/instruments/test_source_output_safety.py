"""The safety check against what the simulated source really puts out, through the real drivers.

The source plays the arb at its own rate and reconstructs the output through its filter
(sample and hold with ``arb_filter = "off"``, band-limited with ``"normal"`` and ``"step"``); the
digitiser records that output on input 1 at 10 kHz. The check must bound the recorded peak and
predict the stroke the recorded output produces, and a drive below the source's smallest
amplitude must come out at the requested level.
"""

import numpy as np
import pytest
from benchkit import bench_profile, lab_registry, run_profile

from fsi_lab.errors import SafetyError
from fsi_lab.runfile import read_run
from fsi_lab.safety import assess
from fsi_lab.shaker import predicted_stroke_mm

SHAKER = {"suspension_hz": 30.0, "damping_ratio": 0.08, "mm_per_volt": 0.5}
LIMITS = {"max_drive_v": 2.0, "max_gain": 10.0, "max_stroke_mm": 20.0}
#: The simulated amplifier's over-travel interlock trips at this stroke (BenchOptions).
SIM_STROKE_MM = 8.8


def _step(amplitude: float, duration: float = 1.0) -> str:
    return (f'plugin = "step"\namplitude = {amplitude}\nrise_time = 0.0\ndelay = 0.1\n'
            f"duration = {duration}")


def _profile(tmp_path, source="", gain=2.0, max_drive_v=2.0, max_stroke_mm=20.0,
             amplitude=1.0, duration=1.5):
    """A bench profile with a step of ``amplitude`` V, ``source`` settings added to
    ``[bench.source]`` and the given gain and limits."""
    path = bench_profile(tmp_path / "p.toml", duration=duration, excitation=_step(amplitude))
    text = path.read_text()
    for old, new in (('plugin = "keysight33500"\n', f'plugin = "keysight33500"\n{source}\n'),
                     ("gain = 2.0", f"gain = {gain}"),
                     ("max_drive_v = 2.0", f"max_drive_v = {max_drive_v}"),
                     ("max_stroke_mm = 5.0", f"max_stroke_mm = {max_stroke_mm}")):
        assert old in text, old
        text = text.replace(old, new, 1)
    path.write_text(text)
    return path


def _recorded_drive(outcome) -> tuple[np.ndarray, float]:
    assert outcome.exit_status == "completed", outcome.error
    drive = read_run(outcome.path).channels["drive"]
    return drive.data, drive.sample_rate


def test_a_step_at_10_sa_s_that_trips_over_travel_is_refused(tmp_path):
    # a model at the 10 Sa/s arb rate predicted 5.47 mm: the 30 Hz ringing fell between samples
    registry = lab_registry()
    source = 'sample_rate = 10.0\narb_filter = "off"'
    refused = _profile(tmp_path, source, gain=10.0, max_stroke_mm=8.5)
    with pytest.raises(SafetyError, match=r"predicted stroke 8.8\d mm exceeds "
                                          r"safety.max_stroke_mm = 8.5 mm"):
        run_profile(refused, registry, tmp_path / "refused")
    assert not (tmp_path / "refused").exists()

    # and the bench agrees: allowed to go, the same drive trips the over-travel interlock
    allowed = _profile(tmp_path, source, gain=10.0, max_stroke_mm=20.0)
    outcome = run_profile(allowed, registry, tmp_path / "runs")
    assert outcome.safety.predicted_stroke_mm > SIM_STROKE_MM
    assert outcome.exit_status == "failed" and "over_travel" in outcome.error


@pytest.mark.parametrize("arb_filter", ["off", "step"])
def test_the_predicted_stroke_is_the_stroke_of_the_recorded_output(tmp_path, arb_filter):
    gain, rate = 5.0, 10.0
    path = _profile(tmp_path, f'sample_rate = {rate}\narb_filter = "{arb_filter}"', gain=gain)
    outcome = run_profile(path, lab_registry(), tmp_path / "runs")
    drive, record_rate = _recorded_drive(outcome)
    measured = predicted_stroke_mm(drive, record_rate, gain, SHAKER)
    waveform = read_run(outcome.path).excitation["waveform"]
    predicted = assess(waveform, rate, gain, LIMITS, SHAKER, arb_filter).predicted_stroke_mm
    assert predicted == pytest.approx(measured, rel=5e-3)
    # the runner does not say which filter the source uses: it keeps the worse model
    assert outcome.safety.predicted_stroke_mm >= predicted


@pytest.mark.parametrize("arb_filter", ["normal", "step"])
def test_the_peak_drive_bounds_the_filters_overshoot(tmp_path, arb_filter):
    rate = 1000.0
    path = _profile(tmp_path, f'sample_rate = {rate}\narb_filter = "{arb_filter}"')
    outcome = run_profile(path, lab_registry(), tmp_path / "runs")
    drive, _ = _recorded_drive(outcome)
    peak = float(np.max(np.abs(drive)))
    assert peak > 1.1  # a 1 V step comes out with the band-limited reconstruction's overshoot
    waveform = read_run(outcome.path).excitation["waveform"]
    report = assess(waveform, rate, 2.0, dict(LIMITS, max_drive_v=1.0), SHAKER, arb_filter)
    assert peak <= report.peak_drive_v <= 1.05 * peak
    assert outcome.safety.peak_drive_v >= report.peak_drive_v
    assert "peak drive" in report.problems[0]

    with pytest.raises(SafetyError, match="exceeds safety.max_drive_v = 1 V \\(the samples "
                                          "peak at 1 V;"):
        run_profile(_profile(tmp_path, f'sample_rate = {rate}\narb_filter = "{arb_filter}"',
                             max_drive_v=1.0), lab_registry(), tmp_path / "refused")


@pytest.mark.parametrize("amplitude", [0.0005, 0.0002])
def test_a_drive_below_the_smallest_amplitude_comes_out_as_requested(tmp_path, amplitude):
    path = _profile(tmp_path, 'arb_filter = "off"', amplitude=amplitude, duration=0.5)
    outcome = run_profile(path, lab_registry(), tmp_path / "runs")
    drive, rate = _recorded_drive(outcome)
    plateau = drive[int(0.2 * rate):int(0.45 * rate)]
    assert np.median(plateau) == pytest.approx(amplitude, abs=2e-5)
    source = read_run(outcome.path).instruments["source"]
    assert source["settings"]["amplitude_vpp"] == pytest.approx(0.002)


def test_a_waveform_starting_high_leaves_no_voltage_after_the_burst(tmp_path):
    # a pulse at t = 0: a 33500 in triggered burst mode rests at the arb's first point, so the
    # driver puts a 0 V point first; the output is back at 0 V once the burst is over, and the
    # safety check (which assumes the worse, a rest at the first sample) still bounds it
    gain, rate = 5.0, 10000.0
    pulse = ('plugin = "ramp-derivative"\nheight = 0.01\nramp_duration = 0.01\ndelay = 0.0\n'
             'duration = 0.03')
    path = _profile(tmp_path, f'sample_rate = {rate}\narb_filter = "off"', gain=gain,
                    duration=1.5)
    path.write_text(path.read_text().replace(_step(1.0), pulse))
    outcome = run_profile(path, lab_registry(), tmp_path / "runs")
    drive, record_rate = _recorded_drive(outcome)
    assert np.abs(drive[int(0.5 * record_rate):]).max() < 1e-3
    assert np.abs(drive).max() == pytest.approx(1.0, rel=1e-3)  # the pulse itself was played
    measured = predicted_stroke_mm(drive, record_rate, gain, SHAKER)
    waveform = read_run(outcome.path).excitation["waveform"]
    predicted = assess(waveform, rate, gain, LIMITS, SHAKER, "off").predicted_stroke_mm
    assert predicted >= 0.995 * measured
    assert outcome.safety.predicted_stroke_mm >= predicted
