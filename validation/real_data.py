"""Real recordings that well-kept PyPI packages ship, against the reference values they document.

Each record is analysed by fsi-lab's identification (:func:`fsi_lab.dsp.identify.identify`,
channel by channel, as ``fsi-lab analyze`` does) and, in the same run, by two peers: the
covariance-free data-driven stochastic subspace identification (SSI-dat) of pyOMA2 on all
channels together, and pysdkit's Hilbert Vibration Decomposition on each channel. Nothing is
fetched from the network: the records are files inside installed packages (the ``dev`` extra).

Records
-------
``pysdkit-beam``
    pysdkit 0.5.0 (MIT licence), ``pysdkit.data.load_bss_beam()``: three accelerometers on a
    beam after an impact, 2560 Hz, 1280 samples (0.5 s), linearly detrended; the experiment of
    G. Yu, "An underdetermined blind source separation method with application to modal
    identification", Shock and Vibration 2019, article 1637163 (experiment 1, ``data_test.mat``).
    Reference damped natural frequencies 30.78, 215.6, 585.9 and 1115.3 Hz: the values pysdkit
    documents for this record in its own test (``pysdkit/tests/test_bss.py``,
    ``test_beam_modes_and_mac``, which holds its own estimates to them within 2 % + 2 Hz),
    identified in the paper by BSS and a single-mode fit; no reference damping ratios are
    documented. The 585.9 and 1115.3 Hz modes have 4.4 and 2.3
    samples per cycle: fsi-lab's identification leaves them out with a note (it needs 6).
    The 30.78 Hz mode lasts about 15 cycles (2.7 % damping) under a 215.6 Hz mode six times
    its acceleration: a least-squares fit of four damped sinusoids to the record itself gives
    30.66 to 30.72 Hz on channels 0 and 1 (started 0 to 15 ms after sample 23, where the
    impact is over; 95 % intervals +-0.05 to 0.09 Hz), pyOMA2's SSI 30.74 Hz. fsi-lab's
    30.70 Hz agrees with both; the reference lies 0.2 to 0.4 % above what these 0.5 s hold,
    so the 0.2 % target is not reached on this mode (its warnings are on the damping law,
    none on the frequency).

Replicas
--------
Each channel is also rebuilt from SSI's modes (:func:`replica`: damped sinusoids from the
impact's end, amplitudes and phases fitted to the channel) with white noise at the record's own
broadband level, and identified over :data:`REPLICA_TRIALS` trials with known truth. On the
beam's replicas the 30.78 Hz mode reads within 0.04 % RMS of the replica's 30.738 Hz (0.4 to
0.5 % noise; coverage 0.90 to 0.95), the 215.6 Hz mode within 0.01 %: at this record's noise
and mode mix the method reaches the target five times over. What it reads on the record
itself departs from the replica's frequency by more than that: the record is not a sum of
linear damped sinusoids to that precision (the fit leaves 2 % of its variance, at the modes'
lines: 17 to 44 times the variance of its broadband noise), and no frequency of such a model
is "the" record's to 0.2 %.

Columns: the reference; fsi-lab's damped natural frequency per channel with its 95 % interval,
its error, its viscous damping ratio (the viscous law's decay rate over the natural angular
frequency) with its interval, and whether it was warned; the peers' values in the same run.
Modes are matched to a reference within :data:`MATCH` (relative). Target: within
:data:`TARGET` (0.2 %) of the reference.

Usage: ``python -m validation [TRIALS] real`` runs these rows alone.
"""

from __future__ import annotations

import logging
import math
import re
import warnings
from dataclasses import dataclass, field

import numpy as np

#: Relative distance within which an estimate is taken as the reference's mode.
MATCH = 0.05
#: The issue's target for natural frequencies on real data (relative).
TARGET = 0.002
#: pyOMA2 SSI settings: block rows, highest model order; a mode's value is the median of the
#: stable poles (pyOMA2's label 1) within :data:`CLUSTER` of it over all orders.
SSI_BLOCK_ROWS = 40
SSI_MAX_ORDER = 80
CLUSTER = 0.02
#: pysdkit HVD settings: components, low-pass in FFT bins of the mirrored record.
HVD_COMPONENTS = 4
HVD_FPAR = 10
#: Replicas (:func:`replica_rows`): trials per channel (at most), the noise's seed, and the
#: Welch segment (samples) its level is measured with.
REPLICA_TRIALS = 20
REPLICA_SEED = 2024
NOISE_SEGMENT = 256


@dataclass(frozen=True)
class Record:
    """A real recording and its documented reference values."""

    name: str
    source: str
    signals: np.ndarray             # (channels, samples)
    fs: float                       # Hz
    quantity: str                   # for fsi-lab: "acceleration", "velocity", "displacement"
    reference_hz: tuple[float, ...]  # damped natural frequencies
    reference_damping: tuple[float, ...] | None = None
    free_from: int = 0              # first sample after the excitation (the impact) is over


def pysdkit_beam() -> Record:
    """pysdkit's beam record (see the module notes)."""
    from pysdkit.data import load_bss_beam

    data = load_bss_beam()
    return Record(name="pysdkit-beam",
                  source="pysdkit 0.5.0 (MIT), load_bss_beam: Yu, Shock Vib. 2019, exp. 1",
                  signals=np.asarray(data["signal"], dtype=np.float64), fs=float(data["fs"]),
                  quantity="acceleration", reference_hz=(30.78, 215.6, 585.9, 1115.3),
                  free_from=23)


RECORDS = {"pysdkit-beam": pysdkit_beam}


@dataclass
class Ours:
    """fsi-lab's identification of one reference mode on one channel."""

    channel: int
    frequency: float = math.nan                 # damped, Hz
    frequency_ci: tuple[float, float] = (math.nan, math.nan)
    zeta: float = math.nan
    zeta_ci: tuple[float, float] = (math.nan, math.nan)
    warnings: list[str] = field(default_factory=list)
    refused: str = ""


@dataclass
class Peer:
    """A peer's value for one reference mode (NaN where it found none)."""

    frequency: float = math.nan                 # damped, Hz
    zeta: float = math.nan


@dataclass
class ModeRow:
    """One reference mode of one record."""

    record: str
    reference: float
    reference_damping: float
    ours: list[Ours]
    ssi: Peer
    hvd: list[Peer]


def _matched(values: np.ndarray, reference: float) -> int | None:
    if values.size == 0:
        return None
    k = int(np.argmin(np.abs(values / reference - 1.0)))
    return k if abs(values[k] / reference - 1.0) <= MATCH else None


def _names(note: str, reference: float) -> bool:
    """Whether ``note`` names a frequency (``... Hz``) within :data:`MATCH` of ``reference``."""
    return any(abs(float(hz) / reference - 1.0) <= MATCH
               for hz in re.findall(r"(\d+(?:\.\d+)?) Hz", note))


def fsi_lab_modes(record: Record) -> list[list[Ours]]:
    """fsi-lab's estimate of each reference mode (outer list) on each channel (inner)."""
    from fsi_lab.dsp.identify import identify
    from fsi_lab.errors import AnalysisError

    out: list[list[Ours]] = [[] for _ in record.reference_hz]
    for ch, x in enumerate(record.signals):
        try:
            found = identify(x, record.fs, quantity=record.quantity)
        except AnalysisError as exc:
            for row in out:
                row.append(Ours(ch, refused=str(exc)))
            continue
        damped = np.array([m.damped_frequency_hz for m in found.modes])
        for i, ref in enumerate(record.reference_hz):
            k = _matched(damped, ref)
            if k is None:
                note = next((n for n in found.notes if _names(n, ref)), "not found")
                out[i].append(Ours(ch, refused=note))
                continue
            mode = found.modes[k]
            viscous = mode.laws.fits["viscous"]
            omega = 2.0 * math.pi * mode.frequency_hz
            lo, hi = viscous.interval("a")
            scale = mode.damped_frequency_hz / mode.frequency_hz
            out[i].append(Ours(ch, frequency=mode.damped_frequency_hz,
                               frequency_ci=(mode.frequency_ci[0] * scale,
                                             mode.frequency_ci[1] * scale),
                               zeta=viscous.value("a") / omega, zeta_ci=(lo / omega, hi / omega),
                               warnings=list(mode.warnings)))
    return out


def ssi_modes(record: Record) -> list[Peer]:
    """pyOMA2's SSI-dat on all channels: per reference mode, the median damped frequency and
    damping ratio of the stable poles near it over every model order."""
    from pyoma2.algorithms.ssi import SSI
    from pyoma2.setup.single import SingleSetup

    logging.getLogger("pyoma2").setLevel(logging.ERROR)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        setup = SingleSetup(np.ascontiguousarray(record.signals.T), fs=record.fs)
        algorithm = SSI(name="ssi", method="dat", br=SSI_BLOCK_ROWS, ordmax=SSI_MAX_ORDER,
                        calc_unc=False)
        setup.add_algorithms(algorithm)
        setup.run_by_name("ssi")
    result = algorithm.result
    fn, xi, label = result.Fn_poles, result.Xi_poles, result.Lab
    out = []
    for ref in record.reference_hz:
        near = (label == 1) & (np.abs(fn / ref - 1.0) < CLUSTER)
        if not near.any():
            out.append(Peer())
            continue
        f, z = float(np.median(fn[near])), float(np.median(xi[near]))
        out.append(Peer(frequency=f * math.sqrt(max(1.0 - z * z, 0.0)), zeta=z))
    return out


def hvd_modes(record: Record) -> list[list[Peer]]:
    """pysdkit's HVD on each channel: per reference mode, the carrier frequency of the
    component nearest it (HVD gives no damping)."""
    from pysdkit import HVD

    carriers = []
    for x in record.signals:
        _, freqs = HVD(K=HVD_COMPONENTS, fpar=HVD_FPAR, mirror=True).fit_transform(
            x, return_all=True)
        carriers.append(np.asarray(freqs) * record.fs)
    out = []
    for ref in record.reference_hz:
        row = []
        for hz in carriers:
            k = _matched(hz, ref)
            row.append(Peer(frequency=float(hz[k])) if k is not None else Peer())
        out.append(row)
    return out


@dataclass
class ReplicaRow:
    """fsi-lab on a replica of one channel of a record, for one of its modes, over trials."""

    record: str
    reference: float
    channel: int
    truth: float                    # the replica's damped frequency, Hz
    noise: float                    # its white noise RMS over its largest value
    trials: int
    errors: list[float] = field(default_factory=list)   # relative, where the mode was found
    covered: int = 0
    warned: int = 0


def replica(record: Record, modes: list[Peer], channel: int) -> tuple[np.ndarray, float]:
    """Channel ``channel`` of ``record`` rebuilt from ``modes`` (damped frequencies and damping
    ratios; NaN ones left out): damped sinusoids from :attr:`Record.free_from` on, their
    amplitudes and phases fitted to the channel by least squares, zero before. Returned with
    the RMS of white noise at the record's broadband level: the median power spectral density
    of what the fit leaves (its misfit sits at the modes' lines, its noise everywhere)."""
    from scipy.signal import welch

    x = record.signals[channel]
    t = (np.arange(x.size) - record.free_from) / record.fs
    columns = []
    for mode in modes:
        if not math.isfinite(mode.frequency):
            continue
        damped = 2.0 * math.pi * mode.frequency
        rate = mode.zeta * damped / math.sqrt(1.0 - mode.zeta ** 2)
        columns += [np.exp(-rate * t) * np.cos(damped * t), np.exp(-rate * t) * np.sin(damped * t)]
    basis = np.stack(columns, axis=1)
    free = slice(record.free_from, None)
    coef, *_ = np.linalg.lstsq(basis[free], x[free], rcond=None)
    clean = basis @ coef
    clean[:record.free_from] = 0.0
    _, psd = welch(x[free] - clean[free], record.fs, nperseg=min(NOISE_SEGMENT, x[free].size))
    return clean, float(np.sqrt(np.median(psd) * record.fs / 2.0))


def replica_rows(names: list[str] | None = None, trials: int = REPLICA_TRIALS
                 ) -> list[ReplicaRow]:
    """fsi-lab on :func:`replica` of every channel of every record (or those named), with fresh
    noise in each of ``trials`` trials: per channel and reference mode that SSI found, the
    error of the damped frequency against the replica's own, the coverage of its interval and
    the trials warned."""
    from fsi_lab.dsp.identify import identify
    from fsi_lab.errors import AnalysisError

    rows = []
    for name, load in RECORDS.items():
        if names and name not in names:
            continue
        record = load()
        modes = ssi_modes(record)
        for channel in range(record.signals.shape[0]):
            clean, sigma = replica(record, modes, channel)
            here = [ReplicaRow(record.name, ref, channel, mode.frequency,
                               sigma / float(np.max(np.abs(clean))), trials)
                    for ref, mode in zip(record.reference_hz, modes)
                    if math.isfinite(mode.frequency)]
            for trial in range(trials):
                rng = np.random.default_rng([REPLICA_SEED, channel, trial])
                try:
                    found = identify(clean + sigma * rng.standard_normal(clean.size), record.fs,
                                     quantity=record.quantity)
                except AnalysisError:
                    continue
                damped = np.array([m.damped_frequency_hz for m in found.modes])
                for row in here:
                    k = _matched(damped, row.truth)
                    if k is None:
                        continue
                    mode = found.modes[k]
                    scale = mode.damped_frequency_hz / mode.frequency_hz
                    row.errors.append(mode.damped_frequency_hz / row.truth - 1.0)
                    row.covered += (mode.frequency_ci[0] * scale <= row.truth
                                    <= mode.frequency_ci[1] * scale)
                    row.warned += bool(mode.warnings)
            rows += here
    return rows


def render_replicas(rows: list[ReplicaRow]) -> str:
    """The replica rows as a markdown table."""
    head = ("| record | reference Hz | channel | replica's f_d Hz | noise % of peak | found | "
            "bias % | RMS % | largest % | coverage | warned |")
    lines = [head, "|" + "|".join("---" for _ in range(head.count("|") - 1)) + "|"]
    for row in rows:
        e = 100.0 * np.array(row.errors)
        if e.size == 0:
            lines.append(f"| {row.record} | {row.reference:g} | {row.channel} | "
                         f"{row.truth:.3f} | {100.0 * row.noise:.2f} | 0/{row.trials} | "
                         "left out in every trial | | | | |")
            continue
        stats = (
                 f"{e.mean():+.3f} | {math.sqrt(float(np.mean(e * e))):.3f} | "
                 f"{float(np.max(np.abs(e))):.3f} | {row.covered / e.size:.2f}")
        lines.append(f"| {row.record} | {row.reference:g} | {row.channel} | {row.truth:.3f} | "
                     f"{100.0 * row.noise:.2f} | {e.size}/{row.trials} | {stats} | "
                     f"{row.warned}/{e.size} |")
    return "\n".join(lines)


def evaluate(names: list[str] | None = None) -> list[ModeRow]:
    """Every record (or those named), each mode a row, the peers run on the same data."""
    rows = []
    for name, load in RECORDS.items():
        if names and name not in names:
            continue
        record = load()
        ours, ssi, hvd = fsi_lab_modes(record), ssi_modes(record), hvd_modes(record)
        damping = record.reference_damping or (math.nan,) * len(record.reference_hz)
        for i, ref in enumerate(record.reference_hz):
            rows.append(ModeRow(record.name, ref, damping[i], ours[i], ssi[i], hvd[i]))
    return rows


def _pct(value: float, reference: float) -> str:
    return "-" if not math.isfinite(value) else f"{100.0 * (value / reference - 1.0):+.2f}"


def verdict(ours: Ours, reference: float) -> str:
    """``met`` (within the target), ``refused`` (left out with a reason), ``missed, warned``,
    or ``MISSED SILENTLY`` (off the target, its interval excluding the reference, no warning)."""
    if ours.refused:
        return "refused"
    if abs(ours.frequency / reference - 1.0) <= TARGET:
        return "met"
    if ours.warnings or ours.frequency_ci[0] <= reference <= ours.frequency_ci[1]:
        return "missed, warned"
    return "MISSED SILENTLY"


def render(rows: list[ModeRow]) -> str:
    """The real-data rows as a markdown table."""
    head = ("| record | reference Hz | channel | fsi-lab f_d Hz (95 %) | error % | fsi-lab zeta "
            "(95 %) | warnings | SSI f_d Hz (error %) | SSI zeta | HVD f_d Hz (error %) | "
            "verdict |")
    lines = [head, "|" + "|".join("---" for _ in range(head.count("|") - 1)) + "|"]
    for row in rows:
        ssi = ("-" if not math.isfinite(row.ssi.frequency) else
               f"{row.ssi.frequency:.2f} ({_pct(row.ssi.frequency, row.reference)})")
        ssi_zeta = "-" if not math.isfinite(row.ssi.zeta) else f"{row.ssi.zeta:.4f}"
        for ours, hvd in zip(row.ours, row.hvd):
            h = ("-" if not math.isfinite(hvd.frequency) else
                 f"{hvd.frequency:.2f} ({_pct(hvd.frequency, row.reference)})")
            if ours.refused:
                text = ours.refused if len(ours.refused) <= 70 else ours.refused[:67] + "..."
                mine = f"refused: {text}"
                err = zeta = warned = "-"
            else:
                mine = (f"{ours.frequency:.3f} ({ours.frequency_ci[0]:.2f} to "
                        f"{ours.frequency_ci[1]:.2f})")
                err = _pct(ours.frequency, row.reference)
                zeta = f"{ours.zeta:.4f} ({ours.zeta_ci[0]:.4f} to {ours.zeta_ci[1]:.4f})"
                warned = str(len(ours.warnings))
            lines.append(f"| {row.record} | {row.reference:g} | {ours.channel} | {mine} | {err} "
                         f"| {zeta} | {warned} | {ssi} | {ssi_zeta} | {h} | "
                         f"{verdict(ours, row.reference)} |")
    return "\n".join(lines)
