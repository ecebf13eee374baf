"""A high-pass in the measuring chain read off a release (fsi_lab.dsp.coupling), and the
warning the equivalent-damping plugin gives with it: against simulated releases with known
damping, seen through first-order high-passes of known corners, and pulses from rest."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.signal
from support import run_main

from fsi_lab.dsp.coupling import release_shift
from fsi_lab.dsp.laws import simulate_decay
from fsi_lab.errors import AnalysisError

FS = 2000.0
MASS = 0.1346          # kg/m
X0 = 1e-3              # m, the release


def _release(frequency: float, duration: float, pre: float = 0.0, zeta: float = 0.01,
             beta: float = 60.0) -> np.ndarray:
    """The velocity (m/s) of a linear + quadratic decay released from X0 after ``pre`` s of
    stillness: ``x'' + 2 zeta w x' + beta |x'| x' + w^2 x = 0``."""
    t = np.arange(int((pre + duration) * FS)) / FS
    w0 = 2.0 * math.pi * frequency
    v = simulate_decay("quadratic", [zeta * w0, beta], w0, X0, pre, t, quantity="displacement",
                       output="velocity")
    v[t < pre] = 0.0
    return v


def _highpassed(v: np.ndarray, corner: float) -> np.ndarray:
    b, a = scipy.signal.butter(1, corner, "highpass", fs=FS)
    return scipy.signal.lfilter(b, a, v)


def _noisy(v: np.ndarray, share: float, offset: float = 0.0, seed: int = 0) -> np.ndarray:
    peak = float(np.max(np.abs(v)))
    return v + peak * (offset + share * np.random.default_rng(seed).standard_normal(v.size))


@pytest.mark.parametrize("frequency, corner", [(5.0, 0.5), (8.0, 1.0), (5.0, 1.0), (3.0, 1.0)])
def test_a_release_behind_a_high_pass_gives_back_its_corner(frequency, corner):
    """A release after a second of stillness, 0.5 % noise and an offset of 3 % of the peak:
    DC-coupled, the mean displacement keeps the release's (ratio 1 to 1.15: the first swing,
    its measure, has lost a little to the damping within it); behind a
    first-order high-pass it returns, and the corner is read within 20 % (from the shift, or
    from the first period's mean where the shift has all but gone)."""
    v = _release(frequency, 20.0, pre=1.0)
    noise = 0.005 * float(np.max(np.abs(v)))
    dc = release_shift(_noisy(v, 0.005, 0.03), FS, frequency, noise)
    assert dc is not None and 1.0 <= dc.ratio < 1.15
    assert dc.start == pytest.approx(FS, abs=5)
    ac = release_shift(_noisy(_highpassed(v, corner), 0.005, 0.03), FS, frequency, noise)
    assert ac is not None and ac.ratio < 0.5 and ac.first_share < dc.first_share
    assert ac.corner_hz == pytest.approx(corner, rel=0.2)
    gain = 1.0 / math.sqrt(1.0 + (corner / frequency) ** 2)
    assert ac.gain(frequency) == pytest.approx(gain, rel=0.02)


def test_a_release_at_the_record_s_start_takes_its_offset_from_the_quiet_tail():
    """Recorded from the release on (no still part): the offset comes from the record's end,
    where the decay has fallen under a tenth of its first extremum; a record that ends before
    that gives no measure."""
    v = _highpassed(_release(5.0, 30.0), 1.0)
    noise = 0.003 * float(np.max(np.abs(v)))
    found = release_shift(_noisy(v, 0.003, 0.02), FS, 5.0, noise)
    assert found is not None and found.start < 5 and found.ratio < 0.05
    assert release_shift(_noisy(v[:int(3 * FS)], 0.003, 0.02), FS, 5.0, noise) is None


@pytest.mark.parametrize("width", [0.005, 0.01, 0.02, 0.04, 0.06])
def test_a_pulse_from_rest_is_no_release(width):
    """A half-sine force pulse of 5 to 60 ms (0.1 to 1.2 periods of the 20 Hz mode) from rest,
    DC-coupled: its mean displacement stays where it started, as a release's behind a
    high-pass does, but its first swing starts at its middle (the short ones) or its velocity
    peaks later than a release's (the long ones): not taken for a release."""
    fs, f = FS, 20.0
    w0 = 2 * math.pi * f
    t = np.arange(int(6.0 * fs)) / fs
    force = np.where((t >= 0.5) & (t < 0.5 + width), np.sin(np.pi * (t - 0.5) / width), 0.0)
    b, a = scipy.signal.cont2discrete(([1.0, 0.0], [1.0, 2 * 0.01 * w0, w0 * w0]), 1 / fs)[:2]
    v = scipy.signal.lfilter(np.ravel(b), a, force)
    assert release_shift(_noisy(v, 0.003), fs, f, 0.003 * float(np.max(np.abs(v)))) is None


def test_a_wandering_mean_or_a_forced_start_gives_no_measure():
    """A release recorded from its start beside a slow wander of the velocity's offset (0.3
    Hz, 5 % of the peak: its displacement outgrows the release's, and read as a relaxation it
    would be a 0.44 Hz high-pass) gives no measure, nor a release whose first free decay
    (identify's) starts more than three periods after the motion did; without the wander,
    and with the free decay a period in, the same release is measured."""
    frequency = 7.5
    v = _release(frequency, 20.0)
    peak = float(np.max(np.abs(v)))
    t = np.arange(v.size) / FS
    noise = 0.005 * peak
    plain = _noisy(v, 0.005, seed=2)
    found = release_shift(plain, FS, frequency, noise, free=int(FS / frequency))
    assert found is not None and found.ratio > 0.9
    wander = plain + 0.05 * peak * np.sin(2 * np.pi * 0.3 * t)
    assert release_shift(wander, FS, frequency, noise) is None
    assert release_shift(plain, FS, frequency, noise, free=int(4 * FS / frequency)) is None


def test_bad_input_is_refused_naming_what_is_expected():
    v = _release(5.0, 2.0)
    with pytest.raises(AnalysisError, match="release_shift: frequency"):
        release_shift(v, FS, 0.0, 1e-6)
    with pytest.raises(AnalysisError, match="release_shift: noise"):
        release_shift(v, FS, 5.0, float("nan"))


def _analysed(tmp_path, name: str, v: np.ndarray, *sets: str) -> dict:
    t = np.arange(v.size) / FS
    csv = tmp_path / f"{name}.csv"
    csv.write_text("Time (s),Tip velocity (m/s)\n"
                   + "\n".join(f"{a:.6f},{b:.9g}" for a, b in zip(t, v)))
    run = tmp_path / f"{name}.h5"
    code, _, err = run_main("import", str(csv), "-o", str(run))
    assert code == 0, err
    args = ["analyze", str(run), "--mass-per-length", str(MASS), "--json"]
    for item in sets:
        args += ["--set", item]
    code, text, err = run_main(*args)
    assert code == 0, err
    (channel,) = json.loads(text)["channels"].values()
    return channel["components"][0]


def test_an_ac_coupled_release_is_warned_and_corrected_when_its_corner_is_given(tmp_path):
    """A 5 Hz release through a 2 Hz AC coupling (0.3 % noise) reads C_f 6 % high: it is
    warned, naming the high-pass and how to give it; given (highpass_hz = 2), C_f is within
    2 % of the truth and the warning gone. The same release DC-coupled is not warned of a
    high-pass."""
    frequency, beta = 5.0, 60.0
    truth = MASS * beta
    v = _release(frequency, 25.0, pre=0.5)
    coupled = _noisy(_highpassed(v, 2.0), 0.003, seed=1)
    warned = _analysed(tmp_path, "ac", coupled)
    c_f = warned["equivalent_damping"]["c_f"]
    assert c_f / truth - 1.0 > 0.04
    said = [w for w in warned["warnings"] if "high-pass in the measuring chain" in w]
    assert len(said) == 1 and "analysis.equivalent-damping.highpass_hz=HZ" in said[0]
    given = _analysed(tmp_path, "given", coupled, "analysis.equivalent-damping.highpass_hz=2")
    assert given["equivalent_damping"]["c_f"] == pytest.approx(truth, rel=0.02)
    assert not any("high-pass" in w for w in given["warnings"])
    plain = _analysed(tmp_path, "dc", _noisy(v, 0.003, seed=1))
    assert plain["equivalent_damping"]["c_f"] == pytest.approx(truth, rel=0.01)
    assert not any("high-pass" in w for w in plain["warnings"])
