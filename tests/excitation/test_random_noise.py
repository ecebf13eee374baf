"""The random excitation: band-limited, flat, reproducible noise that starts and ends at 0 V."""

import numpy as np
import pytest

from fsi_lab.errors import ParameterError
from fsi_lab.params import validate
from fsi_lab.plugins.excitation.random_noise import PLUGIN

RATE = 2000.0


def generate(**values):
    values.setdefault("duration", 4.0)
    return PLUGIN.generate(validate(PLUGIN.params, values, "excitation"), RATE)


def test_spectrum_is_flat_inside_the_band_and_empty_outside():
    wave = generate(rms=0.2, f_low=5.0, f_high=100.0, taper=0.0, delay=0.0)
    spectrum = np.abs(np.fft.rfft(wave))
    f = np.fft.rfftfreq(wave.size, 1 / RATE)
    inside = (f >= 5.0) & (f <= 100.0)
    assert np.std(spectrum[inside]) < 1e-9 * np.mean(spectrum[inside])  # every bin the same
    assert spectrum[~inside].max() < 1e-9 * spectrum[inside].mean()
    assert np.sqrt(np.mean(wave ** 2)) == pytest.approx(0.2)
    assert 2.5 < np.max(np.abs(wave)) / 0.2 < 6.0  # near-Gaussian crest factor


def test_noise_waits_for_the_delay_and_fades_in_and_out():
    wave = generate(rms=0.1, delay=0.5, taper=0.1)
    assert wave.size == int(4.0 * RATE)
    assert np.all(wave[:int(0.5 * RATE)] == 0.0)
    assert wave[int(0.5 * RATE)] == 0.0 and abs(wave[-1]) < 1e-3 * 0.1
    assert np.abs(wave[int(0.5 * RATE):int(0.52 * RATE)]).max() < 0.1  # still fading in


def test_the_seed_makes_it_reproducible():
    np.testing.assert_array_equal(generate(seed=3), generate(seed=3))
    assert not np.array_equal(generate(seed=3), generate(seed=4))


@pytest.mark.parametrize("values, fragment", [
    (dict(f_low=50.0, f_high=20.0), "expected 0 <= f_low < f_high"),
    (dict(f_high=1000.0), "f_high 1000 Hz is not below the Nyquist frequency 1000 Hz"),
    (dict(f_low=10.1, f_high=10.2, delay=0.0),
     "no frequency of resolution 0.25 Hz lies between 10.1 and"),
    (dict(taper=2.0), "cannot hold two tapers of 2 s"),
])
def test_impossible_bands_are_refused_with_the_reason(values, fragment):
    with pytest.raises(ParameterError, match="random: .*" + fragment):
        generate(**values)
