"""The beam-in-fluid model as a profile describes it, and the bench physics built on it.

A profile's ``[specimen]`` gives the beam and fluid; its ``[model]`` section gives the number of
modes and the damping (C_i and C_f per unit length, or damping ratios per mode). The same model
drives ``fsi-lab model``, ``fsi-lab simulate`` (:mod:`fsi_lab.simulation`) and the simulated
bench, and every profile check builds it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.beam import PROJECTIONS, BeamModel, Damping
from fsi_lab.params import Param
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
        "total_mass_per_length": float(model.mass_per_length + model.added_mass),
        "drag_coefficient": float(model.drag_coefficient),
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
