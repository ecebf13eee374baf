"""Components of a record made of its mode bands, in the form the analysis chain shares.

:func:`band_components` turns an :class:`.identify.Identification` into one full-length
component per mode (rows ordered like its modes): the band signal of each free-decay window
(split with that window's own end predictions, so the filters see no excitation), and outside
the windows the band signal of the whole record, marked untrusted (``edge_mask``). Envelopes
and instantaneous frequencies come from the analytic signal of each band. The same layout as
:class:`.hvd.HVDResult`, so the chain's later analyses and the views read either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.fft as sfft

from fsi_lab.dsp._signal import FFT_WORKERS
from fsi_lab.dsp.bands import ModeBands, split
from fsi_lab.dsp.identify import Identification


@dataclass(frozen=True)
class BandComponents:
    """One component per mode band of a record, by decreasing amplitude.

    Attributes
    ----------
    components, envelopes, frequencies
        Band signals (unit of the record, or integrated once for an acceleration), their
        envelopes and instantaneous frequencies (Hz), shape ``(K, N)``.
    residual
        What the bands leave of the record, shape ``(N,)``.
    edge_mask
        True outside the free part of every decay window (excitation, build-ups), ``(K, N)``.
    bands
        The band filters; row ``k`` uses band ``band_of[k]``.
    band_of
        Band of each component.
    windows
        Free-decay windows ``[start, stop)`` and where their free part starts, samples.
    sample_rate
        Hz.
    identification
        What :func:`.identify.identify` found, when these are the record's own components.
    integrate
        How many times the bands were integrated (1 for an acceleration record).
    record
        The record the bands were taken from (its mean removed).
    """

    components: np.ndarray
    envelopes: np.ndarray
    frequencies: np.ndarray
    residual: np.ndarray
    edge_mask: np.ndarray
    bands: ModeBands
    band_of: tuple[int, ...]
    windows: tuple[tuple[int, int, int], ...]
    sample_rate: float
    identification: Identification | None = None
    integrate: int = 0
    record: np.ndarray | None = None
    t0: float = 0.0
    switches: tuple = field(default=())
    band: tuple[float, float] | None = None

    @property
    def n_components(self) -> int:
        return int(self.components.shape[0])

    @property
    def cutoffs(self) -> np.ndarray:
        """Half the width of each component's flat band, Hz (the scale of its smear, in the
        sense of HVD's low-pass cut-off)."""
        return np.array([0.5 * (self.bands.flat(b)[1] - self.bands.flat(b)[0])
                         for b in self.band_of])

    @property
    def peaks(self) -> np.ndarray:
        """Centre frequency of each band, Hz, largest component first."""
        return np.array([self.bands.centres[b] for b in self.band_of])

    def settle(self, k: int) -> float:
        """0 s: each window is filtered on its own, from its free start."""
        return 0.0

    def mean_frequency(self, k: int) -> float:
        """The component's natural frequency when identified, else its band's centre, Hz."""
        if self.identification is not None:
            return float(self.identification.modes[k].frequency_hz)
        return float(self.bands.centres[self.band_of[k]])

    def redo(self, x: np.ndarray) -> "BandComponents":
        """The same bands and windows applied to another record of the same length and rate
        (a model's output, to be compared with the measurement); it keeps this record's
        identification, whose frequencies and noise floors the comparison uses."""
        x = np.asarray(x, dtype=np.float64)
        return _assemble(x - float(np.mean(x)), self.sample_rate, self.bands, self.band_of,
                         self.windows, self.identification, self.integrate)

    def integrated(self, times: int) -> "BandComponents":
        """The components integrated ``times`` more times, band by band and window by window
        (a velocity band becomes a displacement band with no high-pass of its own)."""
        return _assemble(self.record, self.sample_rate, self.bands, self.band_of, self.windows,
                         self.identification, self.integrate + int(times))


def _analytic(rows: np.ndarray) -> np.ndarray:
    """Analytic signals of the rows (FFT, zero-padded to a fast length)."""
    return np.stack([_analytic_row(row) for row in rows]) if rows.shape[0] else \
        np.empty(rows.shape, dtype=complex)


def _analytic_row(row: np.ndarray) -> np.ndarray:
    """The analytic signal of one row (FFT zero-padded to a fast length of twice it; the
    same numbers, to the bit, as the rows transformed together)."""
    n = row.size
    m = sfft.next_fast_len(2 * n)
    spec = sfft.fft(row, n=m, workers=FFT_WORKERS)
    h = np.zeros(m)
    h[0] = 1.0
    h[1:(m + 1) // 2] = 2.0
    if m % 2 == 0:
        h[m // 2] = 1.0
    spec *= h
    del h
    return sfft.ifft(spec, workers=FFT_WORKERS, overwrite_x=True)[:n]


def _envelopes_and_frequencies(rows: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Envelope and instantaneous frequency (Hz) of each row, from its analytic signal, a row
    at a time (so only one row's transform is held)."""
    env = np.empty(rows.shape)
    freq = np.empty(rows.shape)
    for k, row in enumerate(rows):
        z = _analytic_row(row)
        np.abs(z, out=env[k])
        angle = np.angle(z)
        del z
        freq[k] = np.gradient(np.unwrap(angle)) * (fs / (2.0 * math.pi))
    return env, freq


def _assemble(x: np.ndarray, fs: float, bands: ModeBands, band_of: tuple[int, ...],
              windows: tuple[tuple[int, int, int], ...], ident: Identification | None,
              integrate: int) -> BandComponents:
    whole = split(x, fs, bands, integrate=integrate)
    residual = x - whole.sum(axis=0) if not integrate else np.zeros(x.size)
    rows = whole[list(band_of)]  # (a copy)
    del whole
    mask = np.ones(rows.shape, dtype=bool)
    for start, free, stop in windows:
        part = split(x[start:stop], fs, bands, integrate=integrate)
        rows[:, start:stop] = part[list(band_of)]
        mask[:, free:stop] = False
    env, freq = _envelopes_and_frequencies(rows, fs)
    return BandComponents(components=rows, envelopes=env, frequencies=freq, residual=residual,
                          edge_mask=mask, bands=bands, band_of=tuple(band_of),
                          windows=tuple(windows), sample_rate=float(fs), identification=ident,
                          integrate=int(integrate), record=x)


def band_components(x: np.ndarray, fs: float, ident: Identification,
                    integrate: int = 0) -> BandComponents:
    """The components of record ``x`` (sampled at ``fs`` Hz) for the modes ``ident`` found
    in it (see the module notes); ``integrate`` = 1 for an acceleration record (the
    components are then velocities)."""
    windows = tuple((int(a), int(b), int(c)) for a, b, c in ident.free_windows)
    x = np.asarray(x, dtype=np.float64)
    return _assemble(x - float(np.mean(x)), fs, ident.bands, tuple(ident.band_of), windows,
                     ident, integrate)
