"""Units and the physical quantities they imply."""

from __future__ import annotations

STANDARD_GRAVITY = 9.80665  # m/s^2 per g

#: Unit -> quantity. The unit of a CSV column or channel decides what the column holds.
QUANTITY_OF_UNIT = {
    "m": "displacement",
    "m/s": "velocity",
    "m/s^2": "acceleration",
    "g": "acceleration",
    "V": "voltage",
}

#: Quantity -> the SI unit data of that quantity is stored in.
SI_UNIT = {
    "displacement": "m",
    "velocity": "m/s",
    "acceleration": "m/s^2",
    "voltage": "V",
}

QUANTITIES = tuple(SI_UNIT)


def to_si(unit: str) -> tuple[str, float]:
    """SI unit for ``unit`` and the factor that converts values to it (g -> m/s^2)."""
    if unit == "g":
        return "m/s^2", STANDARD_GRAVITY
    return unit, 1.0
