"""Units and the physical quantities they imply."""

from __future__ import annotations

import math
import re

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


#: Prefixes a written unit of length or voltage may carry (a vibrometer's mm/s, a
#: displacement in um or µm, a signal in mV), and the factor each stands for.
PREFIXES = {"": 1.0, "m": 1e-3, "u": 1e-6, "\u00b5": 1e-6, "\u03bc": 1e-6, "n": 1e-9}
#: How exported files write the square of m/s^2 (a signal analyser's m/s², m/s2).
_SQUARED = {"/s^2": "/s^2", "/s\u00b2": "/s^2", "/s2": "/s^2", "/s/s": "/s^2"}
#: Time units a time column may be written in, and their factor to s.
TIME_UNITS = {"s": 1.0, "ms": 1e-3}


def parse_unit(written: str) -> tuple[str, float] | None:
    """The unit of :data:`QUANTITY_OF_UNIT` that ``written`` spells, and the factor from it.

    Parameters
    ----------
    written
        A unit as a file writes it: one of :data:`QUANTITY_OF_UNIT`, or m, m/s, m/s^2 or V
        with a prefix of :data:`PREFIXES` (mm, um, µm/s, mm/s^2, mV); m/s^2 also as m/s²,
        m/s2 or m/s/s.

    Returns
    -------
    tuple of (str, float) or None
        The unit (a key of :data:`QUANTITY_OF_UNIT`) and the factor that converts values in
        ``written`` to it (``"mm/s"`` gives ``("m/s", 1e-3)``); None for a unit not
        understood.

    Examples
    --------
    >>> parse_unit("mm/s")
    ('m/s', 0.001)
    >>> parse_unit("m/s\u00b2")
    ('m/s^2', 1.0)
    >>> parse_unit("in/s") is None
    True
    """
    text = written.strip()
    if text in QUANTITY_OF_UNIT:
        return text, 1.0
    for spelled, square in _SQUARED.items():
        if text.endswith(spelled):
            text = text[: -len(spelled)] + square
    for base in ("m/s^2", "m/s", "m", "V"):
        prefix = text[: -len(base)] if text.endswith(base) else None
        if prefix is not None and prefix in PREFIXES:
            return base, PREFIXES[prefix]
    return None


def to_si(unit: str) -> tuple[str, float]:
    """SI unit for ``unit`` and the factor that converts values to it (g -> m/s^2)."""
    if unit == "g":
        return "m/s^2", STANDARD_GRAVITY
    return unit, 1.0


#: A sensitivity as a data sheet writes it: a number, volts (V, mV, uV) and the unit per
#: which, after a slash (``200 mV/(mm/s)``, ``100mV/g``).
_NUMBER = r"^\s*(?P<number>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*"
_SENSITIVITY = re.compile(_NUMBER + r"(?P<volts>[^\s/]*V)\s*/\s*(?P<unit>.+?)\s*$")
#: A scale factor, the motion per volt (a vibrometer decoder's range, 5mm/s/V)
_SCALE = re.compile(_NUMBER + r"(?P<unit>.+)/\s*(?P<volts>[^\s/()]*V)\s*$")
#: How a sensitivity is written, for the messages.
SENSITIVITY_FORM = ("a number, volts (V or mV) and the unit per which, e.g. 200mV/(mm/s) (a "
                    "vibrometer's decoder at 5 mm/s per V) or 100mV/g (an accelerometer), or "
                    "a scale factor as a decoder's range gives it, 5mm/s/V")


def parse_sensitivity(written: str) -> tuple[float, str] | None:
    """A sensor's sensitivity in volts per SI unit, and that unit.

    Parameters
    ----------
    written
        As a data sheet gives it: a positive number, volts (``V``, ``mV``, ``uV``), a slash
        and a unit :func:`parse_unit` reads other than volts, in parentheses or not; or as a
        scale factor, the unit per volt (``5mm/s/V``, a vibrometer decoder's range).

    Returns
    -------
    tuple of (float, str) or None
        Volts per SI unit (V/(m/s) for a vibrometer), and the SI unit (``m``, ``m/s`` or
        ``m/s^2``); None for a sensitivity not understood or not positive.

    Examples
    --------
    >>> parse_sensitivity("200 mV/(mm/s)")
    (200.0, 'm/s')
    >>> volts, unit = parse_sensitivity("100mV/g")
    >>> print(f"{volts:.5f} V/({unit})")
    0.01020 V/(m/s^2)
    >>> parse_sensitivity("5 mm/s/V")
    (200.0, 'm/s')
    >>> parse_sensitivity("5 mm/s") is None
    True
    """
    scale = False
    match = _SENSITIVITY.match(written)
    if match is None:
        match, scale = _SCALE.match(written), True
        if match is None:
            return None
    volts, unit = parse_unit(match["volts"]), match["unit"].strip()
    if unit.startswith("(") and unit.endswith(")"):
        unit = unit[1:-1]
    per = parse_unit(unit)
    if volts is None or volts[0] != "V" or per is None or per[0] == "V":
        return None
    si_unit, to_si_factor = to_si(per[0])
    number = float(match["number"])
    if scale and number * per[1] * to_si_factor == 0.0:
        return None
    value = (volts[1] / (number * per[1] * to_si_factor) if scale else
             number * volts[1] / (per[1] * to_si_factor))
    if not (math.isfinite(value) and value > 0.0):
        return None
    return value, si_unit


def voltage_hint(quantity: str) -> str:
    """For a message on a channel of ``quantity``: how a column imported in volts becomes
    the motion it measures (``"; ..."``), or nothing for another quantity."""
    if quantity != "voltage":
        return ""
    return ("; a column imported in volts becomes the motion it measures with its sensor's "
            "sensitivity: fsi-lab import ... --sensitivity NAME=200mV/(mm/s)")
