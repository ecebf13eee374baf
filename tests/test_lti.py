"""fsi_lab.lti (the filters of the safety check and the shaker model, in numpy alone) against
the scipy.signal functions they stand in for."""

import numpy as np
import pytest
from scipy import signal

from fsi_lab import lti


def shaker_filters(suspension_hz, damping_ratio, samples_per_period):
    """Displacement and acceleration filters of the shaker model (num, den, rate)."""
    w = 2 * np.pi * suspension_hz
    gain = w * w * 0.5e-3
    den = [1.0, 2 * damping_ratio * w, w * w]
    rate = suspension_hz * samples_per_period
    return [([gain], den, rate), ([gain, 0.0, 0.0], den, rate)]


@pytest.mark.parametrize("num, den, rate", [
    *shaker_filters(30.0, 0.08, 333),
    *shaker_filters(0.1, 0.001, 10_000),
    *shaker_filters(2000.0, 2.0, 100),
    ([1.0, 3.0], [2.0, 5.0], 1000.0),
    ([4.0], [1.0, 0.5], 50.0),
])
def test_bilinear_is_scipys(num, den, rate):
    b, a = lti.bilinear(num, den, rate)
    b_ref, a_ref = signal.bilinear(num, den, fs=rate)
    assert a[0] == 1.0
    np.testing.assert_allclose(a, a_ref / a_ref[0], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(b, b_ref / a_ref[0], rtol=1e-12, atol=1e-13 * np.max(np.abs(b)))


@pytest.mark.parametrize("suspension_hz, damping_ratio, samples_per_period, tolerance", [
    (30.0, 0.08, 333, 1e-11),      # the simulated bench's world rate
    (30.0, 0.08, 100, 1e-11),      # the safety check's least
    (30.0, 1.0, 1000, 1e-11),      # critically damped: a double pole
    (2000.0, 2.0, 100, 1e-11),     # overdamped
    (30.0, 0.001, 10_000, 1e-7),   # the safety check's most, lightly damped: ill-conditioned
])
def test_lfilter_is_scipys_with_its_state(suspension_hz, damping_ratio, samples_per_period,
                                          tolerance):
    rng = np.random.default_rng(3)
    steps = np.repeat(rng.standard_normal(400), 97)  # a staircase, as a held source plays
    for num, den, rate in shaker_filters(suspension_hz, damping_ratio, samples_per_period):
        b, a = lti.bilinear(num, den, rate)
        zi = rng.standard_normal(2) * 1e-4
        expected, expected_zf = signal.lfilter(b, a, steps, zi=zi)
        got, zf = lti.lfilter(b, a, steps, zi)
        scale = np.max(np.abs(expected))
        assert np.max(np.abs(got - expected)) <= tolerance * scale
        assert np.max(np.abs(zf - expected_zf)) <= tolerance * np.max(np.abs(expected_zf))
        # in blocks of any length, the state carried, as the simulated bench feeds it
        state, pieces = zi, []
        for piece in np.array_split(steps, [1, 2, 50, 1000, 1001, 20000]):
            out, state = lti.lfilter(b, a, piece, state)
            pieces.append(out)
        assert np.max(np.abs(np.concatenate(pieces) - expected)) <= tolerance * scale


def test_lfilter_of_order_one_and_of_nothing():
    x = np.random.default_rng(4).standard_normal(1234)
    b, a = [0.2, 0.1], [1.0, -0.7]
    expected, zf_expected = signal.lfilter(b, a, x, zi=[0.3])
    got, zf = lti.lfilter(b, a, x, [0.3, 0.0])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)
    assert zf[0] == pytest.approx(zf_expected[0], rel=1e-12) and zf[1] == 0.0
    empty, state = lti.lfilter(b, a, np.zeros(0), [0.3, 0.0])
    assert empty.size == 0 and list(state) == [0.3, 0.0]
    with pytest.raises(ValueError, match="order 2"):
        lti.lfilter([1.0, 2.0, 3.0, 4.0], [1.0], x, [0.0, 0.0])


@pytest.mark.parametrize("numtaps, cutoff, beta", [(161, 1 / 8, 5.0), (33, 0.9 / 16, 8.0),
                                                   (8193, 1 / 4096, 5.0)])
def test_kaiser_lowpass_is_firwin(numtaps, cutoff, beta):
    np.testing.assert_allclose(lti.kaiser_lowpass(numtaps, cutoff, beta),
                               signal.firwin(numtaps, cutoff, window=("kaiser", beta)),
                               rtol=1e-12, atol=1e-16)


@pytest.mark.parametrize("factor", [1, 2, 3, 8, 100, 4096])
def test_interpolate_is_resample_poly(factor):
    x = np.random.default_rng(factor).standard_normal(257)
    expected = signal.resample_poly(x, factor, 1)
    got = lti.interpolate(x, factor)
    assert got.shape == expected.shape
    assert np.max(np.abs(got - expected)) <= 1e-13 * np.max(np.abs(expected))
