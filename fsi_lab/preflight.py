"""What a run will ask of its bench, checked before any instrument is opened.

:func:`check_safety` generates the excitation (:func:`prepare_excitation`), runs every
instrument's own check on the run (:func:`check_instruments`) and assesses the waveform against
the profile's ``[safety]`` limits. ``fsi-lab profile check``, ``fsi-lab run`` and the GUI call
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


def run_plan(profile: Profile, waveform: np.ndarray, waveform_rate: float) -> RunPlan:
    """The :class:`~fsi_lab.contract.RunPlan` an instrument's check receives.

    Parameters
    ----------
    profile
        A validated, runnable profile.
    waveform
        The excitation the source will play, V.
    waveform_rate
        Its sample rate, Sa/s.
    """
    context = bench_context(profile)
    return RunPlan(specimen=context.specimen, model=context.model, shaker=context.shaker,
                   bench=context.bench, purpose=context.purpose,
                   inputs={name: channel.input for name, channel in profile.channels.items()},
                   sample_rate=float(profile.run["sample_rate"]),
                   duration=float(profile.run["duration"]),
                   waveform_points=int(np.size(waveform)), waveform_rate=float(waveform_rate))


def check_instruments(profile: Profile, registry: Registry, waveform: np.ndarray,
                      waveform_rate: float) -> None:
    """Run every instrument's own check on the run ``profile`` describes.

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
    """Generate the waveform, check what the run asks of each instrument
    (:func:`~fsi_lab.preflight.check_instruments`, which raises) and assess the waveform
    against ``[safety]`` (the verdict is in the report, not raised)."""
    waveform, rate = prepare_excitation(profile, registry)
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
