"""The shaker model and the safety check that runs before anything is sent."""

import numpy as np
import pytest

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
    report = assess(np.full(1000, 0.5), 10000.0, 2.0, LIMITS, SHAKER)
    assert report.ok and report.peak_drive_v == 0.5 and report.gain == 2.0
    require_safe(report, "p.toml")


@pytest.mark.parametrize("wave, gain, fragment", [
    (np.full(100, -2.5), 1.0, "peak drive 2.5 V exceeds safety.max_drive_v = 2 V"),
    (np.full(100, 0.1), 12.0, "amplifier gain 12 exceeds safety.max_gain = 10"),
    (np.full(5000, 1.9), 9.0, "predicted stroke"),
    (np.array([0.0, np.nan]), 1.0, "NaN or infinite"),
])
def test_each_limit_refuses(wave, gain, fragment):
    report = assess(wave, 10000.0, gain, LIMITS, SHAKER)
    assert not report.ok
    with pytest.raises(SafetyError) as info:
        require_safe(report, "p.toml")
    assert str(info.value).startswith("p.toml: refused before anything was sent")
    assert fragment in str(info.value)
