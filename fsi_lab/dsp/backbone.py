"""Backbone curves: instantaneous frequency against instantaneous amplitude.

The paper (Section 2.2) pairs the zero-crossing frequency of each period with the extremum
amplitude of the same period; see :mod:`.instantaneous` for how each is measured. The amplitude
is in the unit of the record: pass a displacement for the backbone against displacement
amplitude (the paper's Figs. 7, 15, 21a), a velocity for the backbone against velocity amplitude.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fsi_lab.dsp.decays import FreeDecays
from fsi_lab.dsp.instantaneous import Instantaneous, instantaneous


@dataclass(frozen=True)
class Backbone:
    """A backbone curve, in time order.

    Attributes
    ----------
    time
        Time of each point (centre of the period measured), s.
    amplitude
        Instantaneous amplitude, unit of the record (m for a displacement).
    frequency
        Instantaneous frequency, Hz.
    decay
        Index of the free decay of each point (:mod:`.decays`), or None (not split).
    decays
        The free decays the points were taken from, or None.
    """

    time: np.ndarray
    amplitude: np.ndarray
    frequency: np.ndarray
    decay: np.ndarray | None = None
    decays: FreeDecays | None = None


def backbone_from(inst: Instantaneous) -> Backbone:
    """The backbone of an :class:`~.instantaneous.Instantaneous` analysis."""
    return Backbone(time=inst.frequency_times.copy(), amplitude=inst.amplitude.copy(),
                    frequency=inst.frequency.copy())


def backbone(x: Any, fs: float, *, smooth: int = 0, offset: Any = "cycles",
             min_amplitude: float | None = None) -> Backbone:
    """Backbone curve (frequency against amplitude) of one component or free decay.

    Parameters
    ----------
    x
        Samples, unit U (displacement in m for the paper's backbone); one quasi-harmonic
        oscillation (an HVD component, or a single-mode decay).
    fs
        Sample rate, Hz.
    smooth, offset, min_amplitude
        As for :func:`.instantaneous.instantaneous` (``smooth = 5`` is the paper's
        5-points-each-side moving average).

    Returns
    -------
    Backbone
        Time (s), amplitude (U) and frequency (Hz) per period.

    Raises
    ------
    AnalysisError
        As :func:`.instantaneous.instantaneous` (NaN/inf, constant, clipped or short record,
        fewer than 3 zero crossings, fewer than 8 samples per cycle).
    """
    return backbone_from(instantaneous(x, fs, offset=offset, smooth=smooth,
                                       min_amplitude=min_amplitude))
