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
