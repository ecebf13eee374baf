"""The few linear filters the safety check and the shaker model need, in numpy alone.

``fsi-lab profile check`` and every run predict the shaker's stroke and the source's output
before anything is driven. Importing :mod:`scipy.signal` for that takes most of a second, longer
than the check itself, so this module computes what the check uses:

- :func:`bilinear`: a continuous transfer function made discrete by the bilinear (Tustin)
  transform, as ``scipy.signal.bilinear`` (and ``cont2discrete(..., method="bilinear")``);
- :func:`lfilter`: a recursive filter of order 2 at most with its state carried from block to
  block, as ``scipy.signal.lfilter(b, a, x, zi=zi)`` (direct form II transposed);
- :func:`kaiser_lowpass` and :func:`interpolate`: the windowed-sinc FIR of
  ``scipy.signal.firwin`` and the polyphase interpolation by an integer factor of
  ``scipy.signal.resample_poly(x, factor, 1)``.

Each agrees with scipy's to rounding, or, for a lightly damped resonance sampled thousands of
times per period, within what such a filter's own rounding allows (1e-7; the tests hold them
to it). None is faster than scipy's once scipy is loaded: the simulated bench and the analysis
(:mod:`fsi_lab.dsp`) keep using scipy.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

#: Input samples on each side of an output of :func:`interpolate` (scipy's ``resample_poly``
#: filter spans 10 input samples each side).
INTERPOLATION_HALF_SPAN = 10
#: Kaiser window shape of :func:`interpolate`'s filter (``resample_poly``'s default).
INTERPOLATION_BETA = 5.0


def bilinear(num: Sequence[float], den: Sequence[float],
             sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Digital filter ``(b, a)``, ``a[0] = 1``, of the analogue ``num(s) / den(s)``.

    Parameters
    ----------
    num, den
        Polynomial coefficients in s, highest power first.
    sample_rate
        Hz; ``s`` is replaced by ``2 fs (z - 1) / (z + 1)``.

    Returns
    -------
    b, a
        Coefficients in z^-1, both of length ``max(len(num), len(den))``.
    """
    order = max(len(num), len(den)) - 1
    k = 2.0 * float(sample_rate)

    def in_z(poly: Sequence[float]) -> np.ndarray:
        out = np.zeros(order + 1)
        for power, coefficient in enumerate(reversed(list(poly))):
            term = np.array([1.0])
            for factor in [(1.0, -1.0)] * power + [(1.0, 1.0)] * (order - power):
                term = np.convolve(term, factor)
            out += coefficient * k ** power * term
        return out

    b, a = in_z(num), in_z(den)
    return b / a[0], a / a[0]


def lfilter(b: Sequence[float], a: Sequence[float], x: np.ndarray,
            zi: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Filter ``x`` through ``b(z) / a(z)`` (order 2 at most) from the state ``zi``.

    The direct form II transposed of ``scipy.signal.lfilter``, whose state ``zi`` (two values)
    it takes and returns. The record is cut into about sqrt(n) blocks that are filtered side
    by side from rest; each block's start state then follows from the previous block's, and
    its free response is added: the same sums as sample by sample, regrouped, at numpy speed.

    Parameters
    ----------
    b, a
        Numerator and denominator in z^-1, at most 3 coefficients each, ``a[0] != 0``.
    x
        Input samples.
    zi
        State before the first sample (``scipy.signal.lfilter_zi`` convention), 2 values.

    Returns
    -------
    y, zf
        The output, same length as ``x``, and the state after the last sample.
    """
    if len(b) > 3 or len(a) > 3 or len(zi) != 2:
        raise ValueError("lfilter: a filter of order 2 at most with a state of 2 values")
    a0 = float(a[0])
    b0, b1, b2 = (list(map(float, b)) + [0.0, 0.0])[:3]
    _, a1, a2 = (list(map(float, a)) + [0.0, 0.0])[:3]
    b0, b1, b2, a1, a2 = b0 / a0, b1 / a0, b2 / a0, a1 / a0, a2 / a0
    x = np.asarray(x, dtype=float).ravel()
    state = (float(zi[0]), float(zi[1]))
    n = x.size
    if n == 0:
        return np.zeros(0), np.array(state)
    span = max(1, math.isqrt(n))
    blocks = -(-n // span)
    tail = n - (blocks - 1) * span  # samples in the last block
    padded = np.zeros(blocks * span)
    padded[:n] = x
    xs = np.ascontiguousarray(padded.reshape(blocks, span).T)  # xs[i]: step i of every block
    ys = np.empty_like(xs)
    z0, z1 = np.zeros(blocks), np.zeros(blocks)
    # free response: the output of step i from a start state s is first_row[i] . s, where
    # first_row[i] is the first row of the state transition matrix to the power i
    first_row = np.empty((span, 2))
    m00, m01, m10, m11 = 1.0, 0.0, 0.0, 1.0
    tail_state = tail_power = None
    for i in range(span):
        xi = xs[i]
        yi = z0 + b0 * xi
        ys[i] = yi
        z0 = z1 + xi * b1 - yi * a1
        z1 = xi * b2 - yi * a2
        first_row[i] = (m00, m01)
        # one more step of the free state: s0' = -a1 s0 + s1, s1' = -a2 s0
        m00, m01, m10, m11 = -a1 * m00 + m10, -a1 * m01 + m11, -a2 * m00, -a2 * m01
        if i == tail - 1:
            tail_state = (float(z0[-1]), float(z1[-1]))
            tail_power = (m00, m01, m10, m11)
    starts = np.empty((blocks, 2))
    s0, s1 = state
    for j in range(blocks):
        starts[j] = (s0, s1)
        s0, s1 = (m00 * s0 + m01 * s1 + float(z0[j]), m10 * s0 + m11 * s1 + float(z1[j]))
    ys += first_row @ starts.T
    p00, p01, p10, p11 = tail_power
    s0, s1 = starts[-1]
    zf = np.array([p00 * s0 + p01 * s1 + tail_state[0], p10 * s0 + p11 * s1 + tail_state[1]])
    return ys.T.ravel()[:n], zf


def kaiser_lowpass(numtaps: int, cutoff: float, beta: float) -> np.ndarray:
    """Linear-phase low-pass FIR, unit gain at 0 Hz: ``scipy.signal.firwin(numtaps, cutoff,
    window=("kaiser", beta))``.

    Parameters
    ----------
    numtaps
        Length of the filter.
    cutoff
        Cut-off as a fraction of the Nyquist frequency, 0 < cutoff < 1.
    beta
        Shape of the Kaiser window.
    """
    m = np.arange(numtaps) - 0.5 * (numtaps - 1)
    h = cutoff * np.sinc(cutoff * m) * np.kaiser(numtaps, beta)
    return h / np.sum(h)


def interpolate(x: np.ndarray, factor: int) -> np.ndarray:
    """``x`` at ``factor`` times its rate, band-limited to its Nyquist frequency:
    ``scipy.signal.resample_poly(x, factor, 1)`` (zero outside ``x``).

    Output sample ``k factor + r`` is a weighted sum of the
    ``2 INTERPOLATION_HALF_SPAN + 1`` input samples around ``k``, through phase ``r`` of the
    Kaiser-windowed sinc (:func:`kaiser_lowpass`, cut off at ``1 / factor``).
    """
    x = np.asarray(x, dtype=float).ravel()
    factor = int(factor)
    if factor == 1:
        return x.copy()
    span = INTERPOLATION_HALF_SPAN
    half = span * factor
    h = kaiser_lowpass(2 * half + 1, 1.0 / factor, INTERPOLATION_BETA) * factor
    # taps[r, t + span]: weight of x[k - t] in output k * factor + r
    index = half + np.arange(factor)[:, None] + np.arange(-span, span + 1)[None, :] * factor
    inside = (index >= 0) & (index <= 2 * half)
    taps = np.where(inside, h[np.clip(index, 0, 2 * half)], 0.0)
    padded = np.concatenate([np.zeros(span), x, np.zeros(span)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * span + 1)  # x[k - span ...]
    return (windows @ taps[:, ::-1].T).ravel()
