"""Decimation for display: fewer points, every peak kept. Storage is never decimated."""

from __future__ import annotations

import numpy as np


def min_max_decimate(t: np.ndarray, y: np.ndarray, points: int) -> tuple[np.ndarray, np.ndarray]:
    """At most about ``points`` samples that keep every peak (min and max of each bin)."""
    n = y.size
    if n <= points:
        return t, y
    bins = max(1, points // 2)
    per = n // bins
    used = per * bins
    blocks = y[:used].reshape(bins, per)
    lo = blocks.argmin(axis=1) + np.arange(bins) * per
    hi = blocks.argmax(axis=1) + np.arange(bins) * per
    idx = np.sort(np.concatenate([lo, hi]))
    if used < n:
        idx = np.concatenate([idx, [n - 1]])
    return t[idx], y[idx]
