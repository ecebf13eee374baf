"""The impulse-train excitation: designed amplitudes, spacing, shapes and their checks."""

import numpy as np
import pytest

from fsi_lab.errors import ParameterError
from fsi_lab.params import validate
from fsi_lab.plugins.excitation.impulse_train import PLUGIN, impulse_amplitudes, impulse_train

RATE = 1000.0


def generate(**values):
    return PLUGIN.generate(validate(PLUGIN.params, values, "excitation"), RATE)


def peaks(wave, spacing, delay, count):
    return [wave[int(round((delay + i * spacing) * RATE)):
                 int(round((delay + (i + 1) * spacing) * RATE))] for i in range(count)]


def test_amplitudes_are_geometric_from_the_largest_to_the_smallest():
    amplitudes = impulse_amplitudes(1.0, 0.01, 5)
    np.testing.assert_allclose(amplitudes, [1.0, 0.316227766, 0.1, 0.0316227766, 0.01])
    np.testing.assert_allclose(impulse_amplitudes(1.0, 0.01, 5, "ascending"), amplitudes[::-1])
    np.testing.assert_allclose(impulse_amplitudes(1.0, 0.01, 5, "interleaved"),
                               amplitudes[[0, 4, 1, 3, 2]])
    np.testing.assert_allclose(impulse_amplitudes(1.0, 0.01, 4, alternate_sign=True),
                               np.geomspace(1.0, 0.01, 4) * [1, -1, 1, -1])


def test_each_impulse_has_its_amplitude_width_and_place():
    wave = generate(max_amplitude=0.8, min_amplitude=0.1, count=4, spacing=0.5, width=0.02,
                    delay=0.1)
    assert wave.size == int((0.1 + 4 * 0.5) * RATE)  # the last response has a full spacing
    segments = peaks(wave, 0.5, 0.1, 4)
    np.testing.assert_allclose([s.max() for s in segments], np.geomspace(0.8, 0.1, 4), rtol=2e-3)
    for segment in segments:
        nonzero = np.flatnonzero(segment)
        assert nonzero[0] <= 1 and nonzero[-1] <= 0.02 * RATE  # a pulse at the start, 20 ms long
    assert np.all(wave[:int(0.1 * RATE)] == 0.0)
    assert np.max(np.abs(wave)) == pytest.approx(0.8, rel=2e-3)  # the peak drive checked


def test_rectangular_impulses_hold_their_level():
    wave = impulse_train(0.5, 0.5, 2, 0.1, 0.01, "rectangular", "descending", False, 0.0, None,
                         RATE)
    assert np.count_nonzero(wave == 0.5) == 20


@pytest.mark.parametrize("values, fragment", [
    (dict(min_amplitude=2.0, max_amplitude=1.0), "expected 0 < min_amplitude <= max_amplitude"),
    (dict(width=2.0, spacing=1.0), "width 2 s must be shorter than spacing 1 s"),
    (dict(width=0.002), "width 0.002 s is 2 samples at 1000 Hz; expected at least 4"),
    (dict(count=6, spacing=2.0, duration=5.0),
     "6 impulses spaced 2 s after a delay of 0.1 s need a duration of at least 10.12 s"),
])
def test_impossible_trains_are_refused_with_the_reason(values, fragment):
    with pytest.raises(ParameterError, match="impulse-train: .*" + fragment.replace("(", r"\(")):
        generate(**values)
