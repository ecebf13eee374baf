"""What a run will ask of its instruments, checked before any of them is opened.

Each instrument plugin may declare a ``check`` (see
:class:`~fsi_lab.contract.InstrumentPlugin`): it is given the run's plan (the bench context,
the channels' inputs, the record's rate and length, the waveform's size) and refuses what the
instrument would refuse during the run. ``fsi-lab profile check`` and ``fsi-lab run`` call it
after generating the waveform, so such a profile is refused before a run file exists.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.bench_access import bench_context
from fsi_lab.errors import PluginError, ProfileError
from fsi_lab.profile import Profile
from fsi_lab.registry import Registry


def run_plan(profile: Profile, waveform: np.ndarray, waveform_rate: float) -> dict[str, Any]:
    """The ``plan`` an instrument's check receives (:data:`fsi_lab.contract.RUN_PLAN_KEYS`).

    Parameters
    ----------
    profile
        A validated, runnable profile.
    waveform
        The excitation the source will play, V.
    waveform_rate
        Its sample rate, Sa/s.
    """
    return {**bench_context(profile),
            "inputs": {name: channel.input for name, channel in profile.channels.items()},
            "sample_rate": float(profile.run["sample_rate"]),
            "duration": float(profile.run["duration"]),
            "waveform_points": int(np.size(waveform)), "waveform_rate": float(waveform_rate)}


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
