"""Components of a decomposition that switch from one mode to another.

HVD extracts the largest component at each instant: when two modes' envelopes cross (a short
impulse makes a higher mode the larger at first, and it decays faster), a component follows one
mode, then the other, and its frequency, damping and C_i / C_f would mix the two.
:func:`mode_switches` finds such components from their instantaneous frequency over the free
parts of the record's decays.
"""

from __future__ import annotations

import numpy as np

from fsi_lab.dsp._signal import moving_average
from fsi_lab.dsp.decays import decay_segments

#: Samples whose envelope is below SWITCH_LEVEL x the
#: record's largest (trusted) envelope are not looked at (their frequency is noise-prone) ...
SWITCH_LEVEL = 1e-2
#: ... an instantaneous frequency within SWITCH_TOLERANCE (relative) of a spectral peak sits
#: near that peak (a Duffing decay's drift beyond it is near no peak: never a switch) ...
SWITCH_TOLERANCE = 0.1
#: ... only stays near one peak of at least SWITCH_CYCLES of its periods count (a component
#: passing a peak while its filters settle after an impulse is no switch) ...
SWITCH_CYCLES = 5.0
#: ... and a component switches when a second peak holds at least SWITCH_SHARE of the time
#: it spends near peaks.
SWITCH_SHARE = 0.1


def _free_samples(x: np.ndarray, fs: float, settle: float, period: float) -> np.ndarray:
    """Boolean mask of the samples of ``x`` inside a free decay: from each decay's largest
    sample plus ``settle`` s to its end minus twice that (the last decay: to the record's end);
    the decays are those of :func:`.decays.decay_segments` (blocks of ``period`` s)."""
    segments = decay_segments(x, fs, period)
    free = np.zeros(x.size, dtype=bool)
    lag = int(round(settle * fs))
    for j, (lo, hi) in enumerate(segments):
        if len(segments) == 1:
            lo = int(np.argmax(np.abs(x)))
        if j < len(segments) - 1:
            hi -= 2 * lag
        if hi > lo + lag:
            free[lo + lag:hi] = True
    return free


def _stays(labels: np.ndarray, rate: float, peaks: np.ndarray) -> np.ndarray:
    """Time (s) spent near each of ``peaks`` (Hz) in stays of at least SWITCH_CYCLES of its
    periods; ``labels`` holds the peak index of consecutive samples at ``rate`` Hz, -1 where
    near none or not looked at."""
    cuts = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    starts = np.concatenate(([0], cuts))
    length = np.diff(np.concatenate((starts, [labels.size])))
    lab = labels[starts]
    keep = (lab >= 0) & (length >= SWITCH_CYCLES * rate / peaks[np.maximum(lab, 0)])
    return np.bincount(lab[keep], weights=length[keep], minlength=peaks.size) / rate


def _distinct(peaks: np.ndarray, apart: float) -> np.ndarray:
    """``peaks`` (Hz, largest first) without those within ``apart`` (relative) of a larger
    one: a noise ripple next to a mode is no second mode."""
    kept: list[float] = []
    for f in peaks:
        if all(abs(f - g) > apart * g for g in kept):
            kept.append(float(f))
    return np.asarray(kept)


def mode_switches(x: np.ndarray, fs: float, envelopes: np.ndarray, frequencies: np.ndarray,
                  edge_mask: np.ndarray, cutoffs: np.ndarray, settles: np.ndarray,
                  peaks: np.ndarray) -> tuple[tuple[float, float] | None, ...]:
    """Which HVD components switch from one mode to another (two envelopes cross).

    HVD extracts the largest component at each instant: when two modes' envelopes cross (a
    short impulse makes a higher mode the larger at first, and it decays faster), a component
    follows one mode, then the other. Looked at: the free parts of the record's decays
    (:func:`.decays.decay_segments`, from each decay's largest sample plus the component's
    settling time, to its end less twice that), where the component's envelope is at
    least SWITCH_LEVEL of the largest and its edge mask trusts it. There its instantaneous
    frequency, averaged over 2 / cutoff (the beat of two modes of similar size makes it
    ripple), is near a spectral peak when within SWITCH_TOLERANCE of it (of peaks closer than
    twice that, only the largest counts); stays near a peak shorter than SWITCH_CYCLES of its
    periods do not count. A component switches when a second peak holds at least
    SWITCH_SHARE of the time spent near peaks. A frequency drifting with the amplitude (a
    Duffing decay) stays near one peak, or near none: no switch.

    Parameters
    ----------
    x
        The record decomposed, any unit U.
    fs
        Sample rate, Hz.
    envelopes, frequencies, edge_mask
        The components' envelopes (U), instantaneous frequencies (Hz) and untrusted samples,
        shape ``(K, len(x))`` (:class:`HVDResult`).
    cutoffs
        The components' cut-offs, Hz, shape ``(K,)``.
    settles
        The components' settling times after an impulse, s, shape ``(K,)``
        (:func:`.hvd.settle_time`).
    peaks
        The record's significant spectral peaks, Hz, largest first
        (:func:`.spectrum.free_decay_peaks`).

    Returns
    -------
    tuple
        Per component, None or the two peaks (Hz) it switches between, the one it stays
        near longer first.
    """
    peaks = _distinct(np.asarray(peaks, dtype=np.float64), 2.0 * SWITCH_TOLERANCE)
    k_total = envelopes.shape[0]
    trusted = ~edge_mask
    if peaks.size < 2 or not trusted.any():
        return (None,) * k_total
    floor = SWITCH_LEVEL * float(np.max(envelopes[trusted]))
    stride = max(1, int(fs / (20.0 * float(peaks.max()))))     # 20 samples per shortest period
    out: list[tuple[float, float] | None] = []
    for k in range(k_total):
        use = _free_samples(x, fs, float(settles[k]), 1.0 / float(peaks[0]))
        use &= trusted[k] & (envelopes[k] >= floor)
        # Averaged over 2 / cutoff (at least 4 periods of the beat between this component and
        # the nearest other peak): two modes of similar size make the frequency ripple.
        f = moving_average(frequencies[k, ::stride],
                           int(round(fs / stride / float(cutoffs[k]))))
        near = np.argmin(np.abs(f[:, None] - peaks[None, :]), axis=1)
        close = np.abs(f - peaks[near]) <= SWITCH_TOLERANCE * peaks[near]
        labels = np.where(use[::stride] & close, near, -1)
        time = _stays(labels, fs / stride, peaks)
        order = np.argsort(-time, kind="stable")
        total = float(time.sum())
        if total > 0 and time[order[1]] >= SWITCH_SHARE * total:
            out.append((float(peaks[order[0]]), float(peaks[order[1]])))
        else:
            out.append(None)
    return tuple(out)
