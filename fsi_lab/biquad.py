"""Second-order IIR filters compiled with numba, for the simulations' long records.

:func:`biquads` runs one input through several second-order sections (``b, a`` of three
coefficients, ``a[0] = 1`` after normalisation) in the transposed direct form II of
``scipy.signal.lfilter``, with the same operations in the same order, so the outputs are the
same to the bit; it saves loading scipy.signal (a second or more) and the temporaries of a
filter per call. ``cache=True``: the first call in a fresh environment compiles for about a
second; later processes load the cache.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numba import njit


@njit(cache=True)
def _biquads(coef: np.ndarray, x: np.ndarray, state: np.ndarray, out: np.ndarray) -> None:
    """out[k] = section k of ``coef[k] = (b0, b1, b2, a1, a2)`` applied to x from ``state[k]``
    (updated in place)."""
    for k in range(coef.shape[0]):
        b0, b1, b2, a1, a2 = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3], coef[k, 4]
        z0 = state[k, 0]
        z1 = state[k, 1]
        for n in range(x.shape[0]):
            xn = x[n]
            yn = z0 + b0 * xn
            z0 = z1 + xn * b1 - yn * a1
            z1 = xn * b2 - yn * a2
            out[k, n] = yn
        state[k, 0] = z0
        state[k, 1] = z1


class Biquads:
    """Stateful filtering of one input through several second-order sections.

    Parameters
    ----------
    sections
        ``(b, a)`` pairs, three coefficients each (fewer are padded with zeros), ``a[0] != 0``.
    """

    def __init__(self, sections: Sequence[tuple[Sequence[float], Sequence[float]]]) -> None:
        rows = []
        for b, a in sections:
            b = (list(map(float, b)) + [0.0, 0.0])[:3]
            a = (list(map(float, a)) + [0.0, 0.0])[:3]
            if len(b) > 3 or len(a) > 3 or a[0] == 0.0:
                raise ValueError("biquads: sections of order 2 at most with a[0] != 0")
            rows.append([b[0] / a[0], b[1] / a[0], b[2] / a[0], a[1] / a[0], a[2] / a[0]])
        self._coef = np.ascontiguousarray(rows, dtype=np.float64).reshape(-1, 5)
        self.state = np.zeros((self._coef.shape[0], 2))
        # Load (or compile) the kernel now, not at the first block: a simulated bench runs its
        # world in the runner's process, where a pause of the first call during the record
        # (the GIL held while numba loads its cache) would starve the amplifier's watchdog.
        self.advance(np.zeros(0))

    def advance(self, x: np.ndarray) -> np.ndarray:
        """The outputs of every section for the next block ``x``, shape ``(sections, len(x))``
        (the state carries over from the previous block)."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        out = np.empty((self._coef.shape[0], x.size))
        _biquads(self._coef, x, self.state, out)
        return out
