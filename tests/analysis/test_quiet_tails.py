"""Records that end in a long quiet tail (the acquisition stopped late): the padding predictor
on silent stretches."""

from __future__ import annotations

import numpy as np
import pytest

from fsi_lab.dsp._signal import ar_extend, predict_pad


@pytest.fixture
def numpy_strict():
    """numpy's warnings of a division by zero, an invalid value or an overflow raise."""
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        yield


@pytest.mark.parametrize("name, stretch, level", [
    ("all zero", np.zeros(4000), 0.0),
    ("a constant offset (a simulated velocity after its decay)", np.full(4000, 6.4e-15), 6.4e-15),
    ("subnormal numbers (a decay gone below 1e-308)",
     1e-310 * np.cos(0.1 * np.arange(4000)), None),
])
def test_the_predictor_holds_a_silent_stretch_without_dividing_by_zero(numpy_strict, name,
                                                                      stretch, level):
    """Kumaresan-Tufts prediction (rank given) and the ridge form both: the normal matrix of
    a silent stretch has zero eigenvalues, which must not be divided by."""
    for rank in (6, None):
        ext = ar_extend(stretch, 500, 12, 10, 2000, rank=rank)
        assert ext.shape == (500,) and np.all(np.isfinite(ext)), name
        expected = float(np.mean(stretch)) if level is None else level
        np.testing.assert_allclose(ext, expected, rtol=1e-12, atol=1e-300)


def test_a_decay_that_dies_into_silence_is_padded_without_numpy_warnings(numpy_strict):
    """Two decaying tones that stop dead after 12 s of a 20 s record: the end stretch the
    predictor is fitted on is all zero; the start is padded from the decay as before."""
    fs = 2000.0
    t = np.arange(int(20 * fs)) / fs
    x = np.exp(-3 * t) * np.cos(2 * np.pi * 8 * t) + 0.3 * np.exp(-3 * t) \
        * np.cos(2 * np.pi * 27 * t + 1)
    x[t > 12] = 0.0
    padded = predict_pad(x, fs, np.array([8.0, 27.0]), 1000, 1000, rank=6)
    assert np.all(np.isfinite(padded))
    np.testing.assert_array_equal(padded[-1000:], 0.0)
    np.testing.assert_array_equal(padded[1000:-1000], x)
    # The head continues the decay backwards: larger than the first samples, and smooth.
    assert np.max(np.abs(padded[500:1000])) > np.max(np.abs(x[:200]))

