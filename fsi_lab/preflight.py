"""What a run will ask of its bench, checked before any instrument is opened.

:func:`check_safety` runs every instrument's own check on the run (:func:`check_instruments`),
with the waveform's length foreseen from the excitation's duration before it is generated (a
60 s waveform at 1 MSa/s is refused by a source that holds 1e6 points without being built),
generates the excitation (:func:`prepare_excitation`) and assesses it against the profile's
``[safety]`` limits. ``fsi-lab profile check``, ``fsi-lab run`` and the GUI call
it, so a profile the bench would refuse is refused before a run file exists.

Each instrument plugin may declare a ``check`` (see
:class:`~fsi_lab.contract.InstrumentPlugin`): it is given the run's plan (the bench context,
the channels' inputs, the record's rate and length, the waveform's size) and refuses what the
instrument would refuse during the run.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.bench_access import bench_context
from fsi_lab.contract import ROLE_INTERFACES, RunPlan
from fsi_lab.errors import PluginError, ProfileError
from fsi_lab.profile import Profile
from fsi_lab.registry import Registry
from fsi_lab.safety import SafetyReport, assess

#: Most samples a drive waveform may have: the largest arb memory of the generators fsi-lab
#: drives (a 33500B with its memory option); a longer one is refused before it is generated.
MAX_WAVEFORM_POINTS = 16_000_000


def run_setting(profile: Profile, role: str, name: str) -> Any:
    """The profile's ``bench.<role>.<name>``: a setting the role's class declares in its
    ``run_settings`` (:class:`~fsi_lab.contract.RoleSetting`), so that the runner reads no name
    a driver could leave out unawares. None when the plugin does not declare an optional one.

    Raises
    ------
    ValueError
        The role declares no run setting ``name`` (a mistake in fsi-lab, not in the profile).
    """
    ROLE_INTERFACES[role].run_setting(name)
    return profile.roles[role].settings.get(name)


def _too_long(profile: Profile, points: float, rate: float) -> ProfileError:
    return ProfileError(
        f"{profile.path}: excitation: {profile.excitation_plugin!r} would make {points:,.0f} "
        f"samples at {rate:g} Sa/s; a source holds at most {MAX_WAVEFORM_POINTS:,}: shorten "
        "the excitation or lower bench.source.sample_rate (or run.sample_rate when it is unset)")


def planned_waveform(profile: Profile, registry: Registry) -> tuple[int | None, float]:
    """The number of samples the profile's excitation will have (None when its plugin does not
    declare its duration) and their rate (Sa/s), known before the waveform is generated."""
    descriptor = registry.get("excitation", profile.excitation_plugin)
    rate = float(run_setting(profile, "source", "sample_rate") or profile.run["sample_rate"])
    if descriptor.duration is None:
        return None, rate
    # As the excitation plugins' time axis: round(duration x rate) samples.
    points = float(descriptor.duration(dict(profile.excitation))) * rate
    return (int(round(points)) if np.isfinite(points) else None), rate


def prepare_excitation(profile: Profile, registry: Registry) -> tuple[np.ndarray, float]:
    """Generate the profile's drive waveform (V) and its sample rate (Hz).

    Raises
    ------
    ProfileError
        The waveform would have more than :data:`MAX_WAVEFORM_POINTS` samples, or none.
    PluginError
        The excitation plugin failed.
    """
    descriptor = registry.get("excitation", profile.excitation_plugin)
    rate = float(run_setting(profile, "source", "sample_rate") or profile.run["sample_rate"])
    if descriptor.duration is not None:
        points = float(descriptor.duration(dict(profile.excitation))) * rate
        if points > MAX_WAVEFORM_POINTS:
            raise _too_long(profile, points, rate)
    try:
        waveform = np.asarray(descriptor.generate(dict(profile.excitation), rate), dtype=float)
    except Exception as exc:  # noqa: BLE001 - a plugin's failure, before anything is driven
        raise PluginError(
            f"{profile.path}: excitation plugin {profile.excitation_plugin!r} failed to generate "
            f"its waveform with {profile.excitation} at {rate:g} Hz: {type(exc).__name__}: {exc}"
        ) from None
    if waveform.size > MAX_WAVEFORM_POINTS:
        raise _too_long(profile, waveform.size, rate)
    if waveform.ndim != 1 or waveform.size == 0:
        raise ProfileError(
            f"{profile.path}: excitation {profile.excitation_plugin!r} produced no samples "
            f"with {profile.excitation}; check its parameters"
        )
    return waveform, rate


def run_plan(profile: Profile, waveform: np.ndarray | int, waveform_rate: float) -> RunPlan:
    """The :class:`~fsi_lab.contract.RunPlan` an instrument's check receives.

    Parameters
    ----------
    profile
        A validated, runnable profile.
    waveform
        The excitation the source will play, V, or its number of samples.
    waveform_rate
        Its sample rate, Sa/s.
    """
    context = bench_context(profile)
    return RunPlan(specimen=context.specimen, model=context.model, shaker=context.shaker,
                   bench=context.bench, purpose=context.purpose,
                   inputs={name: channel.input for name, channel in profile.channels.items()},
                   sample_rate=float(profile.run["sample_rate"]),
                   duration=float(profile.run["duration"]),
                   waveform_points=_points(waveform), waveform_rate=float(waveform_rate))


def _points(waveform: np.ndarray | int) -> int:
    """The number of samples of a waveform, or the number given."""
    return int(waveform) if isinstance(waveform, (int, np.integer)) else int(np.size(waveform))


def check_instruments(profile: Profile, registry: Registry, waveform: np.ndarray | int,
                      waveform_rate: float) -> None:
    """Run every instrument's own check on the run ``profile`` describes (``waveform``: the
    excitation, V, or its number of samples).

    Raises
    ------
    ProfileError
        Naming the profile, ``bench.<role>`` and what the instrument accepts.
    PluginError
        A plugin's check itself failed.
    """
    plan = run_plan(profile, waveform, waveform_rate)
    for role, config in profile.roles.items():
        check = registry.get("instrument", config.plugin).check
        if check is None:
            continue
        try:
            check(config.address, dict(config.settings), plan)
        except ValueError as exc:
            raise ProfileError(f"{profile.path}: bench.{role}: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - a plugin's own failure, named
            raise PluginError(
                f"{profile.path}: bench.{role}: plugin {config.plugin!r} failed to check the "
                f"run: {type(exc).__name__}: {exc}") from None


def check_safety(profile: Profile, registry: Registry) -> tuple[np.ndarray, float, SafetyReport]:
    """Check what the run asks of each instrument (:func:`~fsi_lab.preflight.check_instruments`,
    which raises; before the waveform is generated when its length can be foreseen), generate
    the waveform and assess it against ``[safety]`` (the verdict is in the report, not
    raised)."""
    points, rate = planned_waveform(profile, registry)
    if points is not None:
        if points > MAX_WAVEFORM_POINTS:
            raise _too_long(profile, points, rate)
        check_instruments(profile, registry, points, rate)
    waveform, rate = prepare_excitation(profile, registry)
    if waveform.size != points:
        check_instruments(profile, registry, waveform, rate)
    gain = run_setting(profile, "amplifier", "gain")
    if gain is None:  # a descriptor that bypassed the registry's contract check
        raise ProfileError(
            f"{profile.path}: bench.amplifier: plugin {profile.roles['amplifier'].plugin!r} "
            "declares no 'gain' parameter, so the gain limit cannot be checked"
        )
    # A source that declares ``arb_filter`` says how it reconstructs its output; without it
    # the check assumes the worse of a held and a band-limited output.
    arb_filter = run_setting(profile, "source", "arb_filter")
    report = assess(waveform, rate, float(gain), profile.safety, profile.shaker, arb_filter)
    return waveform, rate, report
