"""What the aggregation of runs needs from one run file (the task each worker runs).

:func:`extract_run` identifies the modes of every analysed channel of a run file as its own
analysis does (the ``hvd`` plugin, method ``bands``, with the run's analysis settings; the
record is only read), and keeps of each mode what the aggregation across runs uses: its free
decays' extrema with their noise correlation (for the union fit,
:mod:`fsi_lab.aggregate_fit`), its own C_i and C_f with their intervals, its backbone and damping
curve, and the conversions to C_i and C_f (mu + M, the modal scale).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fsi_lab.errors import AnalysisError, FsiLabError, InputFileError


def identification_of(result: Any) -> Any:
    """The :class:`~fsi_lab.dsp.identify.Identification` an ``hvd`` result carries (its typed
    ``components`` result, method ``bands``), or None (method ``hvd``, or none made)."""
    decomposition = getattr(result, "decomposition", None)
    return getattr(decomposition, "identification", None)


@dataclass(frozen=True)
class ExtractTask:
    """One run file to extract: its path, ``--set`` overrides of its analysis settings,
    ``--mass-per-length`` (kg/m, or None: from the run's specimen) and a label (``run 3``)."""

    path: str
    sets: tuple[str, ...] = ()
    mass_per_length: float | None = None
    label: str = ""


@dataclass
class ModeExtract:
    """One mode of one run.

    Attributes
    ----------
    channel, index
        The channel and the component number the run's analysis gives the mode.
    frequency_hz, frequency_ci
        Small-amplitude natural frequency and its 95 % interval, Hz.
    w0, alpha, quantity, noise_floor
        The identification's oscillator (rad/s, 1/(U^2 s^2)), what its extrema are extrema of
        (``velocity`` or ``displacement``) and its noise floor (U).
    decays
        The extrema of its free decays (:class:`~fsi_lab.dsp.identify.DecayExtrema`).
    bands, band
        The band filters (:class:`~fsi_lab.dsp.bands.ModeBands`) and the mode's band: the
        correlation of its extrema's errors.
    params, cov
        Its own quadratic law ``(a, beta)`` and covariance (as its analysis widened it).
    widening
        How much its analysis widened its intervals beyond its extrema's scatter
        (:func:`fsi_lab.aggregate_fit.run_widening`).
    mass_per_length, modal_scale, amplitude_convention
        mu + M (kg/m), the mode shape at the measuring point (1: amplitudes as measured) and the
        words that say so: ``C_i = 2 m a``, ``C_f = m beta modal_scale``, modal amplitude =
        measured / modal_scale.
    backbone_amplitude, backbone_frequency
        Its backbone: displacement amplitude (m, measured) and frequency (Hz).
    damping_amplitude, damping_zeta, damping_frequency
        Its damping curve from successive extrema (one period apart): displacement amplitude
        (m, measured), damping ratio and frequency (Hz).
    amplitude_range
        Displacement amplitude of its largest and smallest extremum used, m (measured).
    warnings
        The identification's warnings on the mode.
    joint
        Whether its ``params`` come from a fit together with a close mode to the record's
        samples (:mod:`fsi_lab.dsp.joint_fit`), not from its extrema.
    delta_aicc
        Its identification's AICc of each damping law less the lowest.
    """

    channel: str
    index: int
    frequency_hz: float
    frequency_ci: tuple[float, float]
    w0: float
    alpha: float
    quantity: str
    noise_floor: float
    decays: list
    bands: Any
    band: int
    params: np.ndarray
    cov: np.ndarray
    mass_per_length: float
    modal_scale: float
    amplitude_convention: str
    backbone_amplitude: np.ndarray
    backbone_frequency: np.ndarray
    damping_amplitude: np.ndarray
    damping_zeta: np.ndarray
    damping_frequency: np.ndarray
    amplitude_range: tuple[float, float]
    widening: float = 1.0
    warnings: list[str] = field(default_factory=list)
    joint: bool = False
    delta_aicc: dict[str, float] = field(default_factory=dict)

    def run_decays(self):
        """The mode's decays for the union fit (:class:`~fsi_lab.aggregate_fit.RunDecays`)."""
        from fsi_lab.aggregate_fit import RunDecays

        return RunDecays(self.decays, self.bands.correlation(self.band), self.noise_floor,
                         self.w0, self.alpha, self.quantity, self.params, self.cov,
                         self.widening, self.joint, dict(self.delta_aicc))

    def coefficients(self, level: float = 0.95) -> dict[str, Any]:
        """The run's own C_i (kg/(m s)) and C_f (kg/m^2) with their intervals."""
        import scipy.stats as sstats

        # the intervals of the run's analysis: t with its fit's degrees of freedom (n - p - k)
        dof = max(sum(d.amplitude.size for d in self.decays) - 2 - len(self.decays), 1)
        q = float(sstats.t.ppf(0.5 + 0.5 * level, dof))
        se = np.sqrt(np.maximum(np.diag(self.cov), 0.0))
        ci, cf = 2.0 * self.mass_per_length, self.mass_per_length * self.modal_scale
        a, beta = (float(v) for v in self.params)
        return {"c_i": ci * a, "c_i_ci95": [ci * (a - q * se[0]), ci * (a + q * se[0])],
                "c_f": cf * beta, "c_f_ci95": [cf * (beta - q * se[1]), cf * (beta + q * se[1])]}


@dataclass
class RunExtract:
    """What the aggregation uses of one run file: its modes, or why it has none
    (``exit_code`` 2 when the file was refused, 1 when its analysis failed)."""

    path: str
    label: str
    modes: list[ModeExtract] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    exit_code: int = 0
    start_time: str = ""
    overrides: list[str] = field(default_factory=list)
    #: a hash of the samples of the channels analysed (:func:`record_fingerprint`): records
    #: equal sample for sample have the same one ("": not known)
    fingerprint: str = ""
    #: what the run's stored analysis (``fsi-lab analyze``, as ``fsi-lab show`` prints it) was
    #: computed with beyond the run's own settings and this extraction is not (its ``--set``
    #: texts, ``--mass-per-length=VALUE``): the extract then differs from that analysis
    unapplied: list[str] = field(default_factory=list)


def record_fingerprint(channels: dict[str, Any]) -> str:
    """A hash of ``channels``' samples (name: channel, as analysed: float64, up to where the
    analysis stops), with their names and sample rates: two run files whose analysed channels
    hold the same samples give the same one, whatever their uuids (a copy given a new uuid, or
    two runs of the simulated bench with one ``bench.seed``: one record, not two
    measurements). "" for no channel."""
    import hashlib

    if not channels:
        return ""
    digest = hashlib.blake2b(digest_size=16)
    for name in sorted(channels):
        channel = channels[name]
        data = np.ascontiguousarray(channel.data, dtype=np.float64)
        digest.update(f"{name}\0{float(channel.sample_rate)!r}\0{data.size}\0".encode())
        digest.update(memoryview(data).cast("B"))
    return digest.hexdigest()


def _plugin_params(registry, profile, name: str, **fixed) -> dict[str, Any]:
    """A plugin's parameters as the run's analysis has them (its defaults when the chain does
    not run it), with ``fixed`` values."""
    from fsi_lab.params import validate

    if name in profile.analysis_params:
        return {**profile.analysis_params[name], **fixed}
    return {**validate(registry.get("analysis", name).params, {}, f"analysis.{name}"),
            **fixed}


def _mass_per_length(task: ExtractTask, profile) -> float:
    from fsi_lab.plugins.analysis._equivalent_damping import specimen_mass_per_length

    if task.mass_per_length is not None:
        if not (task.mass_per_length > 0):
            raise InputFileError(f"--mass-per-length {task.mass_per_length}: expected kg/m > 0")
        return float(task.mass_per_length)
    if profile.specimen is None:
        raise InputFileError(
            f"{task.path}: C_i and C_f need mu + M, the mass per length of beam plus added "
            "fluid mass: the run has no [specimen]; pass --mass-per-length KG_PER_M")
    return specimen_mass_per_length(profile.specimen)


def _mode(channel: str, k: int, ident, context, eq_params: dict[str, Any], mass: float
          ) -> ModeExtract:
    from fsi_lab.aggregate_fit import run_widening
    from fsi_lab.dsp.damping import damping_decrement
    from fsi_lab.plugins.analysis._equivalent_damping import amplitude_convention

    mode = ident.modes[k]
    scale, convention = amplitude_convention(context, eq_params, mode.frequency_hz)
    w = 2.0 * math.pi * mode.frequency_hz
    to_displacement = 1.0 / w if mode.quantity == "velocity" else 1.0
    amps, zetas, freqs = [], [], []
    for d in mode.decays:
        if d.amplitude.size >= 4:
            curve = damping_decrement(d.times, d.amplitude, mode.frequency_hz, span=2)
            amps.append(curve.amplitude * to_displacement)
            zetas.append(curve.zeta)
            freqs.append(curve.frequency)
    extrema = np.concatenate([d.amplitude for d in mode.decays]) * to_displacement
    quad = mode.quadratic
    extract = ModeExtract(
        channel=channel, index=k, frequency_hz=float(mode.frequency_hz),
        frequency_ci=(float(mode.frequency_ci[0]), float(mode.frequency_ci[1])),
        w0=w, alpha=float(mode.alpha), quantity=mode.quantity,
        noise_floor=float(mode.noise_floor), decays=list(mode.decays), bands=ident.bands,
        band=int(ident.band_of[k]), params=np.array(quad.params, dtype=np.float64),
        cov=np.array(quad.cov, dtype=np.float64), mass_per_length=mass,
        modal_scale=float(scale), amplitude_convention=convention,
        backbone_amplitude=np.asarray(mode.backbone.amplitude, dtype=np.float64),
        backbone_frequency=np.asarray(mode.backbone.frequency, dtype=np.float64),
        damping_amplitude=np.concatenate(amps) if amps else np.empty(0),
        damping_zeta=np.concatenate(zetas) if zetas else np.empty(0),
        damping_frequency=np.concatenate(freqs) if freqs else np.empty(0),
        amplitude_range=(float(extrema.max()), float(extrema.min())),
        warnings=list(mode.warnings), joint="joint_modes" in mode.start_drift,
        delta_aicc={law: float(v) for law, v in mode.laws.delta.items()})
    if extract.joint:      # (its own fit used no extrema: nothing to compare a refit with)
        return extract
    try:
        extract.widening = run_widening(extract.run_decays())
    except AnalysisError:  # its own fit holds; a refit that fails says nothing against it
        extract.widening = 1.0
    return extract


def _modes(out: RunExtract, name: str, ident, context, eq_params: dict[str, Any],
           mass: float) -> None:
    out.modes.extend(_mode(name, k, ident, context, eq_params, mass)
                     for k in range(len(ident.modes)))


def extract_run(task: ExtractTask, registry=None) -> RunExtract:
    """Identify the modes of every analysed channel of ``task.path`` (module notes).

    A channel whose identification fails is named in ``errors``; the others are kept.

    Raises
    ------
    FsiLabError
        The run file cannot be read or analysed at all (naming it; exit code 2 for bad input).
    """
    from fsi_lab.chain import channels_to_analyse, cut_quiet_tail
    from fsi_lab.contract import AnalysisContext
    from fsi_lab.run_profile import (
        analysis_profile,
        require_no_specimen,
        require_something_to_analyse,
        worker_registry,
    )
    from fsi_lab.runfile import read_run, require_analysable

    registry = registry if registry is not None else worker_registry()
    run = read_run(task.path)
    require_analysable(run)
    status = run.attrs.get("exit_status", "completed")
    if status != "completed":
        raise InputFileError(f"{task.path}: its run ended {status}; only completed runs are "
                             "aggregated")
    profile = analysis_profile(run, registry, task.sets)
    require_no_specimen(run, profile, task.mass_per_length)
    require_something_to_analyse(run, profile)
    if "hvd" not in profile.analysis["chain"]:
        raise InputFileError(
            f"{task.path}: its analysis chain ({', '.join(profile.analysis['chain']) or 'empty'})"
            " identifies no modes; aggregating needs hvd in it, e.g. --set "
            "analysis.chain=hvd")
    mass = _mass_per_length(task, profile)
    hvd = registry.get("analysis", "hvd")
    hvd_params = _plugin_params(registry, profile, "hvd", method="bands")
    eq_params = _plugin_params(registry, profile, "equivalent-damping")
    out = RunExtract(path=str(task.path), label=task.label or Path(task.path).name,
                     start_time=str(run.attrs.get("start_time", "")),
                     overrides=list(run.attrs.get("overrides", [])))
    names = channels_to_analyse(run.channels, profile.analysis.get("channels", []))
    reference = profile.analysis.get("reference")
    # the record up to where its own analysis stops (its quiet tail left out, as run_chain does)
    channels, _ = cut_quiet_tail(run.channels, names + ([reference] if reference else []))
    identified: list[str] = []
    for name in names:
        if name not in channels:
            out.errors.append(f"channel {name!r} is not in the run")
            continue
        context = AnalysisContext(channel=channels[name], channels=channels,
                                  results={}, specimen=profile.specimen,
                                  mass_per_length=task.mass_per_length,
                                  reference=reference)
        try:
            result = hvd.run(context, hvd_params)
            _modes(out, name, identification_of(result), context, eq_params, mass)
            identified.append(name)
        except (FsiLabError, AnalysisError) as exc:
            out.errors.append(f"channel {name}: {exc}")
            out.exit_code = 1
    out.fingerprint = record_fingerprint({name: channels[name] for name in identified})
    out.unapplied = _unapplied(task)
    return out


def _unapplied(task: ExtractTask) -> list[str]:
    """The overrides of ``task.path``'s stored analysis that ``task`` does not give (spaces
    around ``=`` aside); none when the file holds no readable analysis."""
    from fsi_lab.runfile import analysis_overrides, read_analysis_overrides

    def plain(item: str) -> str:
        key, sep, value = item.partition("=")
        return f"{key.strip()}{sep}{value.strip()}"

    try:
        stored = read_analysis_overrides(task.path)
    except InputFileError:          # (a damaged /analysis: nothing to compare with)
        return []
    given = {plain(item) for item in analysis_overrides(task.sets, task.mass_per_length)}
    return [item for item in stored if plain(item) not in given]


def extract_identified(task: ExtractTask, identified: dict[str, tuple[Any, Any]], profile,
                       registry) -> RunExtract:
    """The extract of a run whose analysis has just identified its modes (a sequence's run:
    the identification is not done twice).

    Parameters
    ----------
    task
        The run file and its label.
    identified
        Per channel, the :class:`~fsi_lab.dsp.identify.Identification` the run's ``hvd``
        (method ``bands``) gave and the analysis context it was given.
    profile
        The run's profile (its specimen and analysis settings).
    registry
        Loaded plugins.
    """
    from fsi_lab.runfile import read_run

    run = read_run(task.path, load_data=False)
    out = extract_modes(task.label or Path(task.path).name, identified,
                        profile.analysis_params, profile.specimen, task.mass_per_length,
                        registry, path=str(task.path))
    out.start_time = str(run.attrs.get("start_time", ""))
    out.overrides = list(run.attrs.get("overrides", []))
    out.fingerprint = record_fingerprint({name: context.channel for name, (_, context)
                                          in identified.items()})
    return out


def extract_modes(label: str, identified: dict[str, tuple[Any, Any]],
                  analysis_params: dict[str, dict[str, Any]], specimen: Any,
                  mass_per_length: float | None, registry, path: str = "") -> RunExtract:
    """The extract of identifications already made (a run's, or a segment's of a long record:
    :mod:`fsi_lab.segmented`).

    Parameters
    ----------
    label
        Names the run or segment.
    identified
        Per channel, the :class:`~fsi_lab.dsp.identify.Identification` and the analysis
        context it was given.
    analysis_params
        The analysis plugins' parameters (the profile's).
    specimen
        The run's specimen, or None.
    mass_per_length
        mu + M (kg/m) for data without a specimen, or None.
    registry
        Loaded plugins.

    Raises
    ------
    InputFileError
        Neither a specimen nor ``mass_per_length``: C_i and C_f cannot be given.
    """
    from types import SimpleNamespace

    out = RunExtract(path=path, label=label)
    task = ExtractTask(path or label, mass_per_length=mass_per_length)
    profile = SimpleNamespace(specimen=specimen, analysis_params=analysis_params)
    mass = _mass_per_length(task, profile)
    eq_params = _plugin_params(registry, profile, "equivalent-damping")
    for name, (ident, context) in identified.items():
        try:
            _modes(out, name, ident, context, eq_params, mass)
        except (FsiLabError, AnalysisError) as exc:
            out.errors.append(f"channel {name}: {exc}")
            out.exit_code = 1
    return out
