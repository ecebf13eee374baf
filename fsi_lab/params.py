"""Typed parameter schemas.

Every plugin declares its parameters once, as a tuple of :class:`Param`. That one declaration
drives validation of profile values, parsing of ``--set key=value`` strings, the generated
documentation and the GUI forms.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from fsi_lab.errors import ParameterError

_TYPES: dict[str, type | tuple[type, ...]] = {
    "float": (int, float),
    "int": int,
    "bool": bool,
    "str": str,
    "floats": (list, tuple),
    "strs": (list, tuple),
}


class _Required:
    """Marker for a parameter that has no default and must be given."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()

#: Integers are stored in run files as 64-bit attributes: larger ones are refused.
INT_LIMIT = 2**63 - 1
#: Control characters (NUL, line breaks, escape...) have no place in a parameter's text: they
#: cannot be stored in a run file's attributes or shown in one line of a message.
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


@dataclass(frozen=True)
class Param:
    """One declared parameter of a plugin.

    Parameters
    ----------
    name
        Key used in profiles and with ``--set`` (for example ``components``).
    type
        One of ``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"floats"`` (a list of numbers,
        bounds apply to each element) or ``"strs"`` (a list of strings, choices apply to each).
    unit
        SI unit of the value (``"V"``, ``"Hz"``, ``"s"``, ``"m"``), empty for plain numbers.
    default
        Value used when the profile does not give one; :data:`REQUIRED` if it must be given,
        ``None`` if the parameter is optional and "unset" has a meaning (for example
        "choose automatically").
    minimum, maximum
        Inclusive bounds for numbers.
    choices
        Allowed values for strings (or numbers).
    help
        One sentence shown in docs, ``fsi-lab plugins`` and as GUI tooltip.
    """

    name: str
    type: str
    unit: str = ""
    default: Any = REQUIRED
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[Any, ...] | None = None
    help: str = ""
    exclusive_minimum: bool = field(default=False)

    def __post_init__(self) -> None:
        if self.type not in _TYPES:
            raise ParameterError(
                f"parameter {self.name!r} has type {self.type!r}; allowed types are "
                f"{', '.join(_TYPES)}"
            )

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def describe(self) -> str:
        """What values are accepted, in words (used in error messages and docs)."""
        unit = f" {self.unit}" if self.unit else ""
        if self.choices is not None:
            prefix = "a list of " if self.type == "strs" else ""
            return prefix + "one of " + ", ".join(repr(c) for c in self.choices)
        text = {"float": "a number", "int": "an integer", "bool": "true or false",
                "str": "a string", "floats": "a list of numbers each",
                "strs": "a list of strings"}[self.type]
        lo = self.minimum
        hi = self.maximum
        low_word = ">" if self.exclusive_minimum else ">="
        if lo is not None and hi is not None:
            text += f" {low_word} {lo:g}{unit} and <= {hi:g}{unit}"
        elif lo is not None:
            text += f" {low_word} {lo:g}{unit}"
        elif hi is not None:
            text += f" <= {hi:g}{unit}"
        elif unit:
            text += f" in{unit}"
        return text

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly description of the parameter."""
        return {
            "name": self.name,
            "type": self.type,
            "unit": self.unit,
            "default": None if self.required else self.default,
            "required": self.required,
            "minimum": self.minimum,
            "exclusive_minimum": self.exclusive_minimum,
            "maximum": self.maximum,
            "choices": list(self.choices) if self.choices is not None else None,
            "help": self.help,
        }

    def check(self, value: Any, where: str) -> Any:
        """Return ``value`` converted to this parameter's type, or raise ParameterError.

        ``where`` is the key path used in the message (``excitation.amplitude``).
        """
        if self.default is None and (value is None or (value == "auto"
                                                       and self.type not in ("str", "strs"))):
            return None                     # unset: the plugin chooses ("auto")
        expected = _TYPES[self.type]
        # bool is an int subclass: refuse True where a number is expected, and vice versa.
        if isinstance(value, bool) != (self.type == "bool") or not isinstance(value, expected):
            raise ParameterError(
                f"{where}: got {_short(value)} ({type(value).__name__}); expected "
                f"{self.describe()}"
            )
        if self.type == "floats":
            items = []
            for i, item in enumerate(value):
                if isinstance(item, bool) or not isinstance(item, (int, float)):
                    raise ParameterError(
                        f"{where}[{i}]: got {_short(item)}; expected {self.describe()}"
                    )
                items.append(self._check_number(item, f"{where}[{i}]", as_float=True))
            return items
        if self.type == "strs":
            for i, item in enumerate(value):
                if not isinstance(item, str) or (
                    self.choices is not None and item not in self.choices
                ):
                    raise ParameterError(
                        f"{where}[{i}]: got {_short(item)}; expected {self.describe()}"
                    )
                _check_text(item, f"{where}[{i}]")
            return list(value)
        if self.type == "str":
            _check_text(value, where)
        if self.choices is not None and value not in self.choices:
            raise ParameterError(f"{where}: got {_short(value)}; expected {self.describe()}")
        if self.type in ("float", "int"):
            value = self._check_number(value, where, as_float=self.type == "float")
        return value

    def _check_number(self, value: int | float, where: str, as_float: bool) -> int | float:
        """``value`` bounds-checked (as a float when ``as_float``); an integer too large for a
        float or a 64-bit attribute is refused, not converted."""
        try:
            if as_float:
                value = float(value)
            elif abs(value) > INT_LIMIT:
                raise OverflowError
        except OverflowError:
            raise ParameterError(
                f"{where}: {_short(value)} is out of bounds; expected {self.describe()}"
                + ("" if as_float else " (and of magnitude below 2^63)")
            ) from None
        if not math.isfinite(value):
            raise ParameterError(f"{where}: got {value!r}; expected a finite number")
        too_low = self.minimum is not None and (
            value <= self.minimum if self.exclusive_minimum else value < self.minimum
        )
        too_high = self.maximum is not None and value > self.maximum
        if too_low or too_high:
            raise ParameterError(
                f"{where}: {value!r} is out of bounds; expected {self.describe()}"
            )
        return value

    def parse(self, text: str, where: str) -> Any:
        """Parse a command-line string (``--set``) into a checked value."""
        text = text.strip()
        if self.default is None and text.lower() in ("none", "auto", ""):
            return None
        try:
            if self.type == "bool":
                lowered = text.lower()
                if lowered not in ("true", "false", "1", "0", "yes", "no", "on", "off"):
                    raise ValueError
                value: Any = lowered in ("true", "1", "yes", "on")
            elif self.type == "int":
                value = int(text)
            elif self.type == "float":
                value = float(text)
            elif self.type == "floats":
                value = [float(item) for item in text.strip("[]").split(",") if item.strip()]
            elif self.type == "strs":
                value = [item.strip() for item in text.strip("[]").split(",") if item.strip()]
            else:
                value = text
        except ValueError:
            raise ParameterError(
                f"{where}: cannot read {_short(text)}; expected {self.describe()}"
            ) from None
        return self.check(value, where)


def _short(value: Any, limit: int = 60) -> str:
    """``repr(value)``, cut to about ``limit`` characters for a one-line message."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**limit:
        return f"an integer of {len(str(abs(value)))} digits"
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _check_text(text: str, where: str) -> None:
    """Refuse a string holding control characters (NUL, line breaks, escape)."""
    bad = _CONTROL.search(text)
    if bad:
        raise ParameterError(
            f"{where}: {_short(text)} holds the control character {bad.group()!r} at "
            f"position {bad.start()}; expected printable text"
        )


Schema = Sequence[Param]


def validate(schema: Schema, values: Mapping[str, Any], where: str) -> dict[str, Any]:
    """Check ``values`` against ``schema`` and fill in defaults.

    Parameters
    ----------
    schema
        The declared parameters.
    values
        Values given by a profile or a caller.
    where
        Key path prefix for error messages, e.g. ``"analysis.hvd"``.

    Returns
    -------
    dict
        One entry per declared parameter, converted and bounds-checked.

    Raises
    ------
    ParameterError
        Unknown key, missing required key, wrong type or out-of-bounds value; the message
        names the full key path and what is accepted.
    """
    by_name = {p.name: p for p in schema}
    unknown = sorted(set(values) - set(by_name))
    if unknown:
        allowed = ", ".join(sorted(by_name)) or "no parameters"
        raise ParameterError(
            f"{where}.{unknown[0]}: unknown key; allowed keys are {allowed}"
        )
    result: dict[str, Any] = {}
    for param in schema:
        key = f"{where}.{param.name}"
        if param.name in values:
            result[param.name] = param.check(values[param.name], key)
        elif param.required:
            raise ParameterError(f"{key}: missing; expected {param.describe()}")
        else:
            result[param.name] = param.default
    return result


def find(schema: Schema, name: str) -> Param | None:
    """Return the parameter called ``name``, or None."""
    for param in schema:
        if param.name == name:
            return param
    return None
