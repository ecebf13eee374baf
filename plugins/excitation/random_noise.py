"""Band-limited random noise for the frequency response function (FRF)."""

from __future__ import annotations

import numpy as np

from fsi_lab.contract import ExcitationPlugin
from fsi_lab.errors import ParameterError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.excitation._timebase import DELAY, DURATION, time_axis


def band_limited_noise(rms: float, f_low: float, f_high: float, taper: float, seed: int,
                       delay: float, duration: float, sample_rate: float) -> np.ndarray:
    """Random noise with a flat spectrum between ``f_low`` and ``f_high`` Hz and none outside.

    Every FFT bin of the band gets the same magnitude and a random phase (a random-phase
    multisine: its spectrum has no statistical scatter, its amplitude distribution is close to
    Gaussian, its peak about 4 times its RMS). The noise fills ``delay`` .. ``duration`` s; its
    RMS before tapering is ``rms`` V; raised-cosine ramps of ``taper`` s at both ends start and
    end it at 0 V, sparing the shaker a step. ``seed`` makes it reproducible.

    Raises
    ------
    ParameterError
        A band that is empty, inverted or beyond the Nyquist frequency; tapers longer than the
        noise.
    """
    t = time_axis(duration, sample_rate)
    first = int(np.searchsorted(t, delay))
    m = t.size - first
    nyquist = sample_rate / 2.0
    if not 0.0 <= f_low < f_high:
        raise ParameterError(f"random: f_low {f_low:g} Hz and f_high {f_high:g} Hz: expected "
                             "0 <= f_low < f_high")
    if f_high >= nyquist:
        raise ParameterError(f"random: f_high {f_high:g} Hz is not below the Nyquist frequency "
                             f"{nyquist:g} Hz of the source sample rate {sample_rate:g} Hz")
    if m < 16 or 2 * taper >= m / sample_rate:
        raise ParameterError(f"random: {m / sample_rate:g} s of noise after the delay cannot "
                             f"hold two tapers of {taper:g} s; lengthen the duration")
    freqs = np.fft.rfftfreq(m, 1.0 / sample_rate)
    band = (freqs >= f_low) & (freqs <= f_high) & (freqs > 0)
    if not band.any():
        raise ParameterError(f"random: no frequency of resolution {sample_rate / m:g} Hz lies "
                             f"between {f_low:g} and {f_high:g} Hz; widen the band or lengthen "
                             "the duration")
    rng = np.random.default_rng(seed)
    spectrum = np.zeros(freqs.size, dtype=complex)
    spectrum[band] = np.exp(2j * np.pi * rng.random(int(band.sum())))
    noise = np.fft.irfft(spectrum, m)
    noise *= rms / np.sqrt(np.mean(noise ** 2))
    ramp = int(round(taper * sample_rate))
    if ramp:
        window = 0.5 - 0.5 * np.cos(np.pi * np.arange(ramp) / ramp)
        noise[:ramp] *= window
        noise[-ramp:] *= window[::-1]
    wave = np.zeros(t.size)
    wave[first:] = noise
    return wave


PLUGIN = ExcitationPlugin(
    name="random",
    params=(
        Param("rms", "float", "V", 0.1, minimum=0.0, exclusive_minimum=True, maximum=10.0,
              help="RMS source voltage of the noise (its peak is about 4 times larger)."),
        Param("f_low", "float", "Hz", 1.0, minimum=0.0, maximum=1e6,
              help="Lowest frequency of the band."),
        Param("f_high", "float", "Hz", 200.0, minimum=0.0, exclusive_minimum=True, maximum=1e6,
              help="Highest frequency of the band (below half the source sample rate)."),
        Param("taper", "float", "s", 0.05, minimum=0.0, maximum=60.0,
              help="Raised-cosine fade in and out, so the drive starts and ends at 0 V."),
        Param("seed", "int", "", 0, minimum=0, maximum=2**32 - 1,
              help="Seed of the random phases."),
        DELAY, DURATION,
    ),
    generate=lambda p, rate: band_limited_noise(p["rms"], p["f_low"], p["f_high"], p["taper"],
                                                p["seed"], p["delay"], p["duration"], rate),
    help="Band-limited random noise (flat spectrum, random phases) for the frequency response.",
    duration=lambda p: p["duration"],
)


@hookimpl
def fsi_lab_excitations():
    return [PLUGIN]
