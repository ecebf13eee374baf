"""The specimen section of a profile: beam geometry, material and the surrounding fluid.

The defaults are the paper's steel cantilever (SCIENCE.md): E = 240 GPa, rho = 7200 kg/m^3,
L = 80 mm, H = 12.75 mm, thickness 0.08 mm, velocity measured at x = 80 mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from fsi_lab.params import Param, validate

#: Density of the fluids a profile may name, kg/m^3.
FLUID_DENSITY = {"air": 1.26, "water": 997.0}

SPECIMEN_PARAMS: tuple[Param, ...] = (
    Param("length", "float", "m", 0.08, minimum=1e-3, maximum=10.0,
          help="Free length of the cantilever from the clamp to the tip."),
    Param("width", "float", "m", 12.75e-3, minimum=1e-4, maximum=1.0,
          help="Beam width H (the dimension facing the flow)."),
    Param("thickness", "float", "m", 0.08e-3, minimum=1e-6, maximum=0.1,
          help="Beam thickness in the direction of vibration."),
    Param("youngs_modulus", "float", "Pa", 240e9, minimum=1e5, maximum=1.2e12,
          help="Young's modulus E of the beam material."),
    Param("density", "float", "kg/m^3", 7200.0, minimum=10.0, maximum=25000.0,
          help="Density of the beam material."),
    Param("fluid", "str", "", "water", choices=tuple(FLUID_DENSITY),
          help="Fluid around the beam: 'air' (dry) or 'water' (wet)."),
    Param("drag_coefficient", "float", "", 1.8, minimum=0.0, maximum=10.0,
          help="Drag coefficient C_d for the theoretical quadratic damping C_f = rho C_d H / 2."),
    Param("measurement_point", "float", "m", 0.08, minimum=0.0, maximum=10.0,
          help="Distance from the clamp to the point where the vibrometer measures."),
)


@dataclass(frozen=True)
class Specimen:
    """Validated beam and fluid description (SI units throughout)."""

    length: float
    width: float
    thickness: float
    youngs_modulus: float
    density: float
    fluid: str
    drag_coefficient: float
    measurement_point: float
    #: The keys neither a profile nor an override gave, for data without a profile (imported,
    #: described by ``--set specimen.*`` alone): their values are the paper's beam's.
    defaulted: tuple[str, ...] = field(default=(), compare=False)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any], where: str = "specimen") -> "Specimen":
        """Validate a profile's ``[specimen]`` table (raises ParameterError)."""
        return cls(**validate(SPECIMEN_PARAMS, values, where))

    @property
    def fluid_density(self) -> float:
        """Density of the surrounding fluid, kg/m^3."""
        return FLUID_DENSITY[self.fluid]


def defaults_note(specimen: Specimen | None) -> str | None:
    """The note that names a specimen's :attr:`Specimen.defaulted` keys with the values taken
    for them (the paper's beam's), or None when there are none."""
    if specimen is None or not specimen.defaulted:
        return None
    units = {p.name: p.unit for p in SPECIMEN_PARAMS}
    taken = [f"{name} {getattr(specimen, name):g}" + (f" {units[name]}" if units[name] else "")
             for name in specimen.defaulted]
    listed = ", ".join(taken[:-1]) + " and " + taken[-1] if len(taken) > 1 else taken[0]
    return (f"the beam is described by --set specimen.* alone (imported data has no profile): "
            f"{listed} {'are' if len(taken) > 1 else 'is'} the paper's beam's; give each that "
            "differs, --set specimen.KEY=VALUE, as the modal amplitudes, C_i and C_f in the "
            "modal coordinate, and the modal model depend on them")
