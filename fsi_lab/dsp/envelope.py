"""A decimated envelope of a record, its floor, and how long the record stays above it.

The envelope is the half range ``(max - min) / 2`` of consecutive blocks (an offset does not
count), read a chunk at a time, so the same code serves a record in memory and a dataset in a
run file (:func:`block_envelope`). Its floor (:func:`envelope_floor`) is the median of the last
quarter of the record when that quarter is flat (the medians of its two halves within
:data:`FLAT` of each other) and the record rises at least :data:`RANGE` times above it - a tail
of noise - and never below :data:`REL_FLOOR` times the largest block (a noise-free simulation
decays for ever, through the floating-point range). A block is active when it is above
:data:`ABOVE` times the floor (:func:`active_blocks`). The same floor works on block maxima of
``|x|`` (:func:`.decays.decay_segments`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: Samples read at a time when the envelope is made.
CHUNK = 1 << 20
#: The record's last quarter is flat when the medians of its two halves differ by less than this
#: factor (a noise tail's medians of 50 blocks or more agree within a few %; an exponential decay
#: that falls 100-fold over the record falls 1.8-fold over an eighth of it, a 1/t decay 1.17-fold).
FLAT = 1.1
#: ... and it is a floor when the record's largest block is at least this many times above it.
RANGE = 100.0
#: Floor of a channel whatever its tail, as a share of its largest block: below the noise of any
#: acquisition (a 24-bit converter's noise is some 1e-6 of its range, which the record seldom
#: fills), far above the rounding of a simulation in double precision.
REL_FLOOR = 1e-7
#: A block is active when its half range exceeds this many times the floor (the half range of a
#: block of Gaussian noise stays within 1.5 times its median).
ABOVE = 3.0


def block_envelope(data: Any, block: int) -> np.ndarray:
    """Half range ``(max - min) / 2`` of each block of ``block`` samples of ``data`` (the last
    block may be shorter), reading at most about :data:`CHUNK` samples at a time.

    Parameters
    ----------
    data
        The samples: a 1-D array, or anything sliced like one (an ``h5py.Dataset``).
    block
        Samples per block, >= 1.

    Returns
    -------
    numpy.ndarray
        One value per block, unit of ``data``.
    """
    n = int(len(data))
    block = max(1, int(block))
    per_read = max(1, CHUNK // block) * block
    out = []
    for start in range(0, n, per_read):
        chunk = np.asarray(data[start:min(n, start + per_read)], dtype=np.float64)
        whole = chunk.size // block * block
        if whole:
            rows = chunk[:whole].reshape(-1, block)
            out.append(0.5 * (rows.max(axis=1) - rows.min(axis=1)))
        if whole < chunk.size:
            rest = chunk[whole:]
            out.append(np.array([0.5 * (rest.max() - rest.min())]))
    return np.concatenate(out) if out else np.empty(0)


def envelope_floor(envelope: np.ndarray) -> float:
    """The floor of a block envelope (see the module notes): the level of a flat tail of noise,
    or :data:`REL_FLOOR` times the largest block, whichever is higher; 0 for a silent channel."""
    top = float(np.max(envelope, initial=0.0))
    if not (top > 0.0 and math.isfinite(top)):
        return 0.0
    floor = REL_FLOOR * top
    quarter = envelope.size // 4
    if quarter >= 8:
        tail = envelope[-quarter:]
        half = quarter // 2
        first, second = float(np.median(tail[:half])), float(np.median(tail[half:]))
        level = float(np.median(tail))
        flat = first <= FLAT * second and second <= FLAT * first
        if flat and top >= RANGE * level:
            floor = max(floor, level)
    return floor


def active_blocks(envelope: np.ndarray) -> int:
    """Number of leading blocks up to and including the last one above :data:`ABOVE` times the
    envelope's floor (0 for a silent channel)."""
    floor = envelope_floor(envelope)
    if floor <= 0.0:
        return 0
    above = np.flatnonzero(envelope > ABOVE * floor)
    return int(above[-1]) + 1 if above.size else 0
