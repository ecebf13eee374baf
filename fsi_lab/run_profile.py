"""What a run file is analysed with: its profile's analysis settings and the plugins.

:func:`analysis_profile` builds what ``fsi-lab analyze`` analyses a run file with: the run's own
profile's ``[analysis]`` and ``[specimen]`` (or the default chain for imported data), the run's
recorded overrides of them, then the new ones (:mod:`fsi_lab.batch` and the aggregation's
extraction, :mod:`fsi_lab.aggregate_extract`, use them).
"""

from __future__ import annotations

import dataclasses
import json

from fsi_lab.errors import InputFileError
from fsi_lab.specimen import SPECIMEN_PARAMS

#: The sections of a run's profile the analysis reads.
ANALYSIS_SECTIONS = ("analysis", "specimen")


def analysis_profile(run, registry, sets: list[str] | tuple[str, ...] = ()):
    """The profile ``fsi-lab analyze`` analyses ``run`` (a :class:`~fsi_lab.runfile.RunData`)
    with: its ``[analysis]`` and ``[specimen]``, its recorded overrides of them, then ``sets``.

    Imported data (no profile) gets the default chain and the reference given on import.

    Raises
    ------
    ProfileError
        The profile, or an override, is refused (naming the run file and the key).
    """
    from fsi_lab.chain import default_chain
    from fsi_lab.profile import parse_profile

    text = run.profile_text
    if not text.strip():  # imported data: the default chain, and the reference given on import
        chain = default_chain(registry)
        text = "[analysis]\nchain = " + json.dumps(chain) + "\n"
        if run.reference:
            text += "reference = " + json.dumps(run.reference) + "\n"
    # The run's own --set overrides of what analysis reads come first, the new ones after.
    recorded = [item for item in run.attrs.get("overrides", [])
                if item.partition(".")[0].strip() in ANALYSIS_SECTIONS]
    profile = parse_profile(text, f"{run.path}:/profile", registry, recorded + list(sets),
                            sections=ANALYSIS_SECTIONS)
    if run.profile_text.strip() or profile.specimen is None:
        return profile
    # Imported data: the overrides alone describe the beam, the paper's beam the rest.
    given = {item.partition("=")[0].strip().partition(".")[2].strip()
             for item in recorded + list(sets)
             if item.partition("=")[0].strip().partition(".")[0].strip() == "specimen"}
    defaulted = tuple(p.name for p in SPECIMEN_PARAMS if p.name not in given)
    return dataclasses.replace(
        profile, specimen=dataclasses.replace(profile.specimen, defaulted=defaulted))


def require_no_specimen(run, profile, mass_per_length: float | None) -> None:
    """InputFileError when ``--mass-per-length`` is given for a run that has a specimen (its
    profile's ``[specimen]``, or ``specimen.*`` overrides of imported data): the specimen gives
    mu + M, and two beams for one record would leave the stored numbers unexplained."""
    if mass_per_length is None or profile.specimen is None:
        return
    where = ("its profile's [specimen]" if run.profile_text.strip()
             else "the specimen.* overrides given for it")
    raise InputFileError(
        f"{run.path}: --mass-per-length {mass_per_length:g}: this run has a specimen "
        f"({where}), which gives mu + M; --mass-per-length is for data without one; expected "
        "no --mass-per-length, or the beam the run should be analysed as given with --set "
        "specimen.KEY=VALUE")


def require_something_to_analyse(run, profile) -> None:
    """InputFileError unless the run has a channel the chain analyses (named or by quantity)."""
    from fsi_lab.chain import channels_to_analyse
    from fsi_lab.units import voltage_hint

    if not channels_to_analyse(run.channels, profile.analysis.get("channels", [])):
        listed = ", ".join(f"{n} ({c.quantity}, {c.unit})" for n, c in run.channels.items())
        raise InputFileError(
            f"{run.path}: nothing to analyse: no velocity or displacement channel (channels: "
            f"{listed or 'none'}); an acceleration or voltage channel is analysed when named, "
            "e.g. --set analysis.channels=NAME"
            + voltage_hint("voltage" if any(c.quantity == "voltage"
                                            for c in run.channels.values()) else ""))



_REGISTRY = None


def worker_registry():
    """The plugins, loaded once per worker process."""
    global _REGISTRY
    if _REGISTRY is None:
        from fsi_lab.registry import load_registry

        _REGISTRY = load_registry()
    return _REGISTRY
