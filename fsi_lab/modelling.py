"""The beam-in-fluid model as a profile describes it, and simulated runs from it.

A profile's ``[specimen]`` gives the beam and fluid; its ``[model]`` section gives the number of
modes and the damping (C_i and C_f per unit length, or damping ratios per mode). The same model
drives ``fsi-lab model``, ``fsi-lab simulate`` and the simulated bench.
"""

from __future__ import annotations

import traceback
from pathlib import Path
from typing import Any, Callable

import numpy as np

from fsi_lab.beam import PROJECTIONS, BeamModel, Damping
from fsi_lab.errors import RunAborted
from fsi_lab.params import Param
from fsi_lab.runfile import INTERRUPTED, RunFileWriter, utc_now, write_attrs
from fsi_lab.shaker import ShakerModel

MODEL_PARAMS: tuple[Param, ...] = (
    Param("modes", "int", "", 4, minimum=1, maximum=50, help="Number of beam modes kept."),
    Param("c_i", "float", "kg/(m s)", None, minimum=0.0, maximum=1e4,
          help="Linear (material) damping per unit length C_i; unset means none, or the "
               "damping ratios when given."),
    Param("c_f", "float", "kg/m^2", None, minimum=0.0, maximum=1e4,
          help="Quadratic (fluid) damping per unit length C_f; unset means the theoretical "
               "rho_f C_d H / 2 (Eq. 26)."),
    Param("damping_ratios", "floats", "", None, minimum=0.0, maximum=1.0,
          help="Linear damping ratio per mode, instead of c_i (the dry model uses 0.002, 0.001)."),
    Param("rayleigh", "bool", "", False,
          help="Extend two damping ratios to every mode by Rayleigh damping."),
    Param("projection", "str", "", "per-mode", choices=PROJECTIONS,
          help="Quadratic damping per mode (the paper) or projected consistently (Galerkin)."),
)

#: Name of the simulated channels and what they hold.
SIMULATED_CHANNELS = {
    "drive": ("voltage", "V"),
    "base_acceleration": ("acceleration", "m/s^2"),
    "tip_velocity": ("velocity", "m/s"),
}


def beam_model(specimen: Any, model: dict[str, Any], modes: int | None = None) -> BeamModel:
    """The :class:`~fsi_lab.beam.BeamModel` of a specimen and a validated ``[model]`` section.

    ``modes`` overrides ``model["modes"]``.
    """
    modes = model["modes"] if modes is None else modes
    provisional = BeamModel.from_specimen(specimen, modes=modes, damping=Damping())
    c_f = provisional.c_f_theory if model["c_f"] is None else model["c_f"]
    ratios = model["damping_ratios"]
    damping = Damping(c_i=model["c_i"] or 0.0, c_f=c_f,
                      ratios=tuple(ratios) if ratios is not None else None,
                      rayleigh=model["rayleigh"], projection=model["projection"])
    return provisional.with_damping(damping)


def model_summary(model: BeamModel) -> dict[str, Any]:
    """The ``fsi-lab model --json`` object."""
    return {
        "fluid": model.fluid,
        "added_mass_ratio": float(model.added_mass_ratio),
        "natural_frequencies_hz": [float(f) for f in model.natural_frequencies_hz],
        "c_f_theory": float(model.c_f_theory),
        "modes": model.modes,
        "mass_per_length": float(model.mass_per_length),
        "added_mass": float(model.added_mass),
        "damping": {"c_i": model.damping.c_i, "c_f": model.damping.c_f,
                    "damping_ratios": [float(z) for z in model.damping_ratios],
                    "projection": model.damping.projection},
    }


class BenchPhysics:
    """Source volts -> amplifier -> shaker -> base motion -> beam -> tip velocity, block by block.

    Parameters
    ----------
    model
        The beam.
    shaker
        A profile's ``[shaker]`` values.
    sample_rate
        Rate of every block, Hz.
    point
        Where the vibrometer measures, m from the clamp.
    """

    def __init__(self, model: BeamModel, shaker: dict[str, Any], sample_rate: float,
                 point: float) -> None:
        from fsi_lab.modal_integrator import ModalSimulator  # compiles with numba: load on use

        self.shaker = ShakerModel.from_profile(sample_rate, shaker)
        self.beam = ModalSimulator(model, sample_rate, [point],
                                   outputs=("absolute_velocity",))

    def advance(self, amplifier_volts: np.ndarray) -> dict[str, np.ndarray]:
        """Base displacement (m), base acceleration (m/s^2) and the absolute velocity (m/s) at
        the measuring point for the next block of amplifier output voltage (V)."""
        displacement, acceleration = self.shaker.advance(amplifier_volts)
        velocity = self.beam.advance(acceleration)["absolute_velocity"][:, 0]
        return {"base_displacement": displacement, "base_acceleration": acceleration,
                "tip_velocity": velocity}


def simulate_run(profile: Any, waveform: np.ndarray, waveform_rate: float, duration: float,
                 sample_rate: float, out: Path, modes: int | None, attrs: dict[str, Any],
                 progress: Callable[[float], None] = lambda fraction: None) -> Path:
    """Write a run file of the model driven by the profile's excitation.

    The excitation (source volts) passes through the amplifier gain and the ``[shaker]`` model
    to give the base acceleration that drives the beam. Records longer than the excitation are
    padded with zeros. Channels: ``drive`` (V), ``base_acceleration`` (m/s^2) and
    ``tip_velocity`` (absolute velocity at ``specimen.measurement_point``, m/s), the layout of a
    measured run.
    """
    model = beam_model(profile.specimen, profile.model, modes)
    physics = BenchPhysics(model, profile.shaker, sample_rate, profile.specimen.measurement_point)
    gain = float(profile.roles["amplifier"].settings.get("gain", 1.0)) if profile.roles else 1.0
    total = int(round(duration * sample_rate))
    t = np.arange(total) / sample_rate
    drive = np.interp(t, np.arange(waveform.size) / waveform_rate, waveform, right=0.0)
    writer = RunFileWriter(out, {**attrs, "kind": "simulated"})
    ending = {"exit_status": "failed", "error": "", "traceback": ""}
    try:
        writer.write_excitation(waveform, waveform_rate,
                                {"plugin": profile.excitation_plugin, "amplifier_gain": gain},
                                profile.excitation)
        for name, (quantity, unit) in SIMULATED_CHANNELS.items():
            writer.create_channel(name, {"units": unit, "quantity": quantity,
                                         "sample_rate": sample_rate, "t0": 0.0,
                                         "sensitivity": 1.0, "source_instrument": "model"})
        block = max(1, int(sample_rate))  # one-second blocks
        for start in range(0, total, block):
            chunk = drive[start:start + block]
            motion = physics.advance(chunk * gain)
            writer.append("drive", chunk)
            writer.append("base_acceleration", motion["base_acceleration"])
            writer.append("tip_velocity", motion["tip_velocity"])
            progress(min(1.0, (start + block) / total))
        write_attrs(writer.file.create_group("model"), model_summary(model))
        ending["exit_status"] = "completed"
    except (KeyboardInterrupt, RunAborted) as exc:  # recorded as the runner records an abort
        ending.update(exit_status="aborted", error=str(exc) or INTERRUPTED)
        raise
    except BaseException as exc:
        ending.update(error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
        raise
    finally:
        writer.set_attrs({**ending, "stop_time": utc_now()})
        writer.close()
    return out
