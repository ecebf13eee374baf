"""The shaker model and the safety check that runs before anything is sent."""

import numpy as np
import pytest
from scipy import signal

from fsi_lab import safety
from fsi_lab.errors import SafetyError
from fsi_lab.safety import assess, require_safe
from fsi_lab.shaker import ShakerModel, predicted_stroke_mm

SHAKER = {"suspension_hz": 30.0, "damping_ratio": 0.08, "mm_per_volt": 0.5}
LIMITS = {"max_drive_v": 2.0, "max_gain": 10.0, "max_stroke_mm": 5.0}


def test_step_overshoot_matches_the_second_order_closed_form():
    zeta = SHAKER["damping_ratio"]
    overshoot = 1 + np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
    stroke = predicted_stroke_mm(np.ones(20000), 20000.0, 2.0, SHAKER)
    assert stroke == pytest.approx(2.0 * 0.5 * overshoot, rel=1e-3)


def test_blocks_equal_one_pass_and_acceleration_is_the_second_derivative():
    rate = 20000.0
    u = np.sin(2 * np.pi * 7 * np.arange(8000) / rate) + (np.arange(8000) > 3000)
    whole_x, whole_a = ShakerModel.from_profile(rate, SHAKER).advance(u)
    model = ShakerModel.from_profile(rate, SHAKER)
    parts = [model.advance(block) for block in np.array_split(u, 7)]
    np.testing.assert_allclose(np.concatenate([p[0] for p in parts]), whole_x, rtol=1e-12,
                               atol=1e-15)
    numeric = np.gradient(np.gradient(whole_x, 1 / rate), 1 / rate)
    inner = slice(100, 2900)  # away from the jump, where finite differences hold
    np.testing.assert_allclose(whole_a[inner], numeric[inner], rtol=0, atol=2e-3 * np.ptp(whole_a))


def test_assess_passes_and_reports_figures():
    report = assess(np.full(1000, 0.5), 10000.0, 2.0, LIMITS, SHAKER, arb_filter="off")
    assert report.ok and report.peak_drive_v == 0.5 and report.gain == 2.0
    require_safe(report, "p.toml")


@pytest.mark.parametrize("wave, gain, fragment", [
    (np.full(100, -2.5), 1.0, "peak drive 2.5 V exceeds safety.max_drive_v = 2 V"),
    (np.full(100, 0.1), 12.0, "amplifier gain 12 exceeds safety.max_gain = 10"),
    (np.full(5000, 1.9), 9.0, "predicted stroke"),
    (np.array([0.0, np.nan]), 1.0, "NaN or infinite"),
])
def test_each_limit_refuses(wave, gain, fragment):
    report = assess(wave, 10000.0, gain, LIMITS, SHAKER, arb_filter="off")
    assert not report.ok
    with pytest.raises(SafetyError) as info:
        require_safe(report, "p.toml")
    assert str(info.value).startswith("p.toml: refused before anything was sent")
    assert fragment in str(info.value)


# --------------------------------------------------------------------------- the source output
def _step(rate, level=1.0, delay=0.1, duration=1.0):
    """A step of ``level`` V after ``delay`` s, held to the end of ``duration`` s."""
    t = np.arange(int(round(duration * rate))) / rate
    return np.where(t >= delay, level, 0.0)


def _second_order_step_peak_mm(volts):
    """Peak base displacement of the continuous model after a step of ``volts`` at the
    amplifier output."""
    zeta = SHAKER["damping_ratio"]
    return volts * SHAKER["mm_per_volt"] * (1 + np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2)))


@pytest.mark.parametrize("rate", [10.0, 40.0, 200.0, 10000.0])
def test_a_held_step_rings_the_suspension_whatever_the_source_rate(rate):
    # a sample-and-hold source steps at once: at 10 Sa/s the 30 Hz ringing falls between the
    # samples, and a model at the source rate predicted 5.47 mm instead of 8.89 mm
    report = assess(_step(rate), rate, 10.0, LIMITS, SHAKER, arb_filter="off")
    assert report.predicted_stroke_mm == pytest.approx(_second_order_step_peak_mm(10.0),
                                                       rel=1e-3)
    (problem,) = report.problems
    assert problem.endswith("mm exceeds safety.max_stroke_mm = 5 mm (shaker model: 0.5 mm/V, "
                            "30 Hz; source output modelled as sample-and-hold); lower the "
                            "amplitude or the gain")


def test_a_band_limited_source_overshoots_the_samples_and_the_check_bounds_it():
    limits = dict(LIMITS, max_drive_v=1.0, max_stroke_mm=100.0)
    held = assess(_step(1000.0), 1000.0, 1.0, limits, SHAKER, arb_filter="off")
    assert held.ok and held.peak_drive_v == 1.0
    for arb_filter in ("normal", "step"):
        report = assess(_step(1000.0), 1000.0, 1.0, limits, SHAKER, arb_filter=arb_filter)
        # Gibbs overshoot of the windowed-sinc reconstruction (1.137 V), plus the 3 % margin
        assert report.peak_drive_v == pytest.approx(1.137 * 1.03, rel=2e-3)
        (problem,) = report.problems
        assert problem.startswith("peak drive 1.171 V exceeds safety.max_drive_v = 1 V (the "
                                  "samples peak at 1 V; the source's band-limited "
                                  "reconstruction (arb_filter 'normal' or 'step') overshoots")
        assert "3% margin" in problem


def test_a_band_limited_source_smooths_a_slow_step():
    # at 10 Sa/s the filter spreads the rise over about 0.1 s, far slower than 30 Hz
    report = assess(_step(10.0), 10.0, 10.0, LIMITS, SHAKER, arb_filter="normal")
    assert 5.0 < report.predicted_stroke_mm < 6.0


def test_an_unknown_reconstruction_is_assessed_both_ways_and_the_worse_is_kept():
    wave, rate = _step(10.0), 10.0
    held = assess(wave, rate, 10.0, LIMITS, SHAKER, arb_filter="off")
    smooth = assess(wave, rate, 10.0, LIMITS, SHAKER, arb_filter="normal")
    for arb_filter in (None, "linear"):
        either = assess(wave, rate, 10.0, LIMITS, SHAKER, arb_filter=arb_filter)
        assert either.peak_drive_v == smooth.peak_drive_v > held.peak_drive_v
        assert either.predicted_stroke_mm == held.predicted_stroke_mm > smooth.predicted_stroke_mm


def test_a_long_waveform_is_assessed_in_blocks_exactly_as_in_one(monkeypatch):
    rng = np.random.default_rng(3)
    wave = signal.lfilter([0.05], [1, -0.95], rng.standard_normal(5000))
    whole = {f: assess(wave, 2000.0, 3.0, LIMITS, SHAKER, arb_filter=f)
             for f in ("off", "normal")}
    monkeypatch.setattr(safety, "BLOCK", 333)
    for arb_filter, report in whole.items():
        blocks = assess(wave, 2000.0, 3.0, LIMITS, SHAKER, arb_filter=arb_filter)
        assert blocks.peak_drive_v == pytest.approx(report.peak_drive_v, rel=1e-12)
        assert blocks.predicted_stroke_mm == pytest.approx(report.predicted_stroke_mm,
                                                           rel=1e-9)


def test_a_source_rate_the_shaker_model_cannot_follow_is_refused():
    lowest = safety.lowest_source_rate(SHAKER["suspension_hz"])  # 100 x 30 Hz / 4096
    assert lowest == pytest.approx(0.732, rel=1e-3)
    assert assess(_step(1.0, duration=20.0), 1.0, 1.0, LIMITS, SHAKER).ok
    report = assess(np.array([0.0, 0.1, 0.1, 0.0]), 0.5, 1.0, LIMITS, SHAKER)
    (problem,) = report.problems
    assert problem == ("source sample rate 0.5 Sa/s is too low for the shaker model to follow "
                       "its output; expected at least 0.732 Sa/s: raise bench.source.sample_rate "
                       "(or run.sample_rate when it is unset)")


@pytest.mark.parametrize("rate", [1e5, 1e7, 1.6e8])
def test_the_stroke_is_predicted_alike_at_any_source_rate(rate):
    """Millions of source samples per suspension period made the shaker model's filter lose
    its precision (no stroke predicted at 10 MSa/s, a safety limit not enforced) and its tail
    exhaust memory (160 MSa/s); the output is averaged down for the model instead."""
    from fsi_lab.safety import HOLD, output_stroke_mm

    shaker = {"suspension_hz": 0.1, "damping_ratio": 0.08, "mm_per_volt": 0.5}

    def pulse(sample_rate):  # 1 V for 2 ms after 1 ms, in 5 ms; the source rests at 0 V
        t = np.arange(round(0.005 * sample_rate)) / sample_rate
        return np.where((t >= 0.001) & (t < 0.003), 1.0, 0.0)

    reference = output_stroke_mm(pulse(1e4), 1e4, HOLD, 2.0, shaker)
    assert reference > 0
    assert output_stroke_mm(pulse(rate), rate, HOLD, 2.0, shaker) == \
        pytest.approx(reference, rel=1e-3)
