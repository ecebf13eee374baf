"""A train of impulses whose amplitudes span a range, spaced so each response decays before
the next: one record then covers the backbone from large to small amplitude."""

from __future__ import annotations

import dataclasses

import numpy as np

from fsi_lab.contract import ExcitationPlugin
from fsi_lab.errors import ParameterError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.excitation._timebase import DELAY, DURATION, time_axis

SHAPES = ("half-sine", "rectangular")
ORDERS = ("descending", "ascending", "interleaved")


def impulse_amplitudes(max_amplitude: float, min_amplitude: float, count: int,
                       order: str = "descending", alternate_sign: bool = False) -> np.ndarray:
    """Peak of each impulse, V: ``count`` values spaced geometrically (equal steps of ln A, the
    scale on which damping and backbones are read) between ``max_amplitude`` and
    ``min_amplitude``.

    ``order`` is ``descending`` (largest first), ``ascending`` or ``interleaved`` (largest,
    smallest, second largest, ...); with ``alternate_sign`` every other impulse is negative, so
    the armature is pushed both ways.
    """
    if not 0 < min_amplitude <= max_amplitude:
        raise ParameterError(
            f"impulse-train: min_amplitude {min_amplitude:g} V and max_amplitude "
            f"{max_amplitude:g} V: expected 0 < min_amplitude <= max_amplitude")
    if order not in ORDERS:
        raise ParameterError(f"impulse-train: order {order!r}; expected one of {', '.join(ORDERS)}")
    amplitudes = np.geomspace(max_amplitude, min_amplitude, count)
    if order == "ascending":
        amplitudes = amplitudes[::-1]
    elif order == "interleaved":
        index = np.empty(count, dtype=int)
        index[0::2] = np.arange((count + 1) // 2)
        index[1::2] = count - 1 - np.arange(count // 2)
        amplitudes = amplitudes[index]
    if alternate_sign:
        amplitudes = amplitudes * np.where(np.arange(count) % 2, -1.0, 1.0)
    return amplitudes


def impulse_train(max_amplitude: float, min_amplitude: float, count: int, spacing: float,
                  width: float, shape: str, order: str, alternate_sign: bool, delay: float,
                  duration: float | None, sample_rate: float) -> np.ndarray:
    """The source voltage, V, sampled at ``sample_rate`` Hz.

    Impulse i (of :func:`impulse_amplitudes`) starts at ``delay + i * spacing`` s and lasts
    ``width`` s: a half period of a sine (smooth, little content above 1.5 / width Hz) or a
    rectangle. ``duration`` (s) defaults to ``delay + count * spacing``: the last response has a
    full spacing to decay.

    Raises
    ------
    ParameterError
        Impulses that overlap, are not resolved by the sample rate, or do not fit the duration.
    """
    if shape not in SHAPES:
        raise ParameterError(f"impulse-train: shape {shape!r}; expected one of {', '.join(SHAPES)}")
    if width >= spacing:
        raise ParameterError(
            f"impulse-train: width {width:g} s must be shorter than spacing {spacing:g} s "
            "(each response must decay before the next impulse)")
    if width * sample_rate < 4:
        raise ParameterError(
            f"impulse-train: width {width:g} s is {width * sample_rate:.3g} samples at "
            f"{sample_rate:g} Hz; expected at least 4 (raise the width or the sample rate)")
    amplitudes = impulse_amplitudes(max_amplitude, min_amplitude, count, order, alternate_sign)
    needed = delay + (count - 1) * spacing + width
    if duration is None:
        duration = delay + count * spacing
    elif duration < needed:
        raise ParameterError(
            f"impulse-train: {count} impulses spaced {spacing:g} s after a delay of {delay:g} s "
            f"need a duration of at least {needed:g} s; duration is {duration:g} s (raise it, "
            "or lower count or spacing)")
    t = time_axis(duration, sample_rate)
    wave = np.zeros(t.size)
    for i, amplitude in enumerate(amplitudes):
        start = delay + i * spacing
        inside = (t >= start) & (t < start + width)
        if shape == "half-sine":
            wave[inside] = amplitude * np.sin(np.pi * (t[inside] - start) / width)
        else:
            wave[inside] = amplitude
    return wave


PLUGIN = ExcitationPlugin(
    name="impulse-train",
    params=(
        Param("max_amplitude", "float", "V", 1.0, minimum=0.0, exclusive_minimum=True,
              maximum=10.0, help="Peak source voltage of the largest impulse."),
        Param("min_amplitude", "float", "V", 0.1, minimum=0.0, exclusive_minimum=True,
              maximum=10.0, help="Peak source voltage of the smallest impulse."),
        Param("count", "int", "", 6, minimum=1, maximum=1000,
              help="Number of impulses; their peaks are spaced geometrically."),
        Param("spacing", "float", "s", 2.0, minimum=0.0, exclusive_minimum=True,
              maximum=600.0, help="Time from one impulse to the next: several decay times of the "
                                  "slowest mode of interest (2 s for the wet beam's second mode)."),
        Param("width", "float", "s", 0.02, minimum=0.0, exclusive_minimum=True, maximum=10.0,
              help="Duration of each impulse (excites up to about 1.5 / width Hz)."),
        Param("shape", "str", "", "half-sine", choices=SHAPES, help="Shape of each impulse."),
        Param("order", "str", "", "descending", choices=ORDERS,
              help="Order of the amplitudes: descending, ascending or interleaved."),
        Param("alternate_sign", "bool", "", False,
              help="Make every other impulse negative."),
        DELAY,
        dataclasses.replace(DURATION, default=None,
                            help="Length of the waveform; unset: delay + count * spacing."),
    ),
    generate=lambda p, rate: impulse_train(
        p["max_amplitude"], p["min_amplitude"], p["count"], p["spacing"], p["width"], p["shape"],
        p["order"], p["alternate_sign"], p["delay"], p["duration"], rate),
    help="Impulses of designed, geometrically spaced amplitudes, each decaying before the next; "
         "one record covers the backbone from large to small amplitude.",
    duration=lambda p: p["duration"] or p["delay"] + p["count"] * p["spacing"],
)


@hookimpl
def fsi_lab_excitations():
    return [PLUGIN]
