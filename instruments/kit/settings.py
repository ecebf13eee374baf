"""Declared instrument settings: one line names a setting's command, type, unit and bounds.

A :class:`Setting` is declared on a driver class (a :class:`~fsi_lab.instruments.kit.scpi.
ScpiInstrument`), in the spirit of PyMeasure's ``Instrument.control``: the declaration builds
the command that sets it and the query that reads it, checks a value against its bounds or
choices before anything is sent, parses the reply, and gives the profile parameter
(:meth:`Setting.param`) so that the setting is described once. Commands may hold fields
(``"SOUR{channel}:FUNC:ARB:SRAT"``), filled from keyword arguments or from the driver's
attributes of the same name.
"""

from __future__ import annotations

import math
import re
import string
from collections.abc import Mapping
from typing import Any

from fsi_lab.params import REQUIRED, Param

#: Types a setting may have, as :class:`~fsi_lab.params.Param` names them.
TYPES = ("float", "int", "bool", "str")
#: A word a free-text setting may take: printable ASCII without spaces or SCPI separators.
_WORD = re.compile(r'^[!#-+\-/-:<-~]+$')
#: How a number is written unless the setting says otherwise.
DEFAULT_FORMAT = {"float": ".10g", "int": "d"}


def _fields(template: str) -> tuple[str, ...]:
    """The field names of a command template (``"INP{input}:RANG"`` -> ``("input",)``)."""
    return tuple(name for _, name, _, _ in string.Formatter().parse(template) if name)


class Setting:
    """One setting of an instrument, declared as a class attribute of its driver.

    Read on a driver instance (``amplifier.gain``) it queries the instrument; assigned
    (``amplifier.gain = 2.5``) it checks the value and sends the command, then checks the
    instrument's error queue. Settings whose command has fields the driver does not hold as
    attributes are used through :meth:`~fsi_lab.instruments.kit.scpi.ScpiInstrument.get` and
    :meth:`~fsi_lab.instruments.kit.scpi.ScpiInstrument.set` with the fields as keywords.

    Parameters
    ----------
    command
        The SCPI header that sets it (``"GAIN"``, ``"INP{input}:RANG"``); the value follows it
        after one space.
    type
        ``"float"``, ``"int"``, ``"bool"`` or ``"str"``.
    unit
        SI unit of the value (``"V/V"``, ``"Hz"``), empty for plain numbers and words.
    minimum, maximum
        Inclusive bounds of a number, in ``unit``.
    choices
        The values a ``str`` setting takes and the word the instrument uses for each
        (``{"normal": "NORM", "off": "OFF"}``), or a tuple of words used as they are (None: any
        one word of printable ASCII, e.g. a name); for a ``bool``, the words for True and False
        (default ``("ON", "OFF")``).
    fmt
        Format specification of a number (default ``".10g"`` for floats, ``"d"`` for ints).
    query
        The query that reads it, when it is not ``command + "?"``; None for a setting that can
        only be written.
    readonly
        A value the instrument reports but that cannot be set (``INP{input}:SCAL?``).
    tolerance
        Relative tolerance of :meth:`ScpiInstrument.set`'s read-back (``verify=True``).
    accepted
        What the instrument accepts, in words, added to the message when it refuses a value.
    help
        One sentence: what the setting does (the profile parameter's help).
    """

    def __init__(self, command: str, type: str, unit: str = "", *,
                 minimum: float | None = None, maximum: float | None = None,
                 choices: Mapping[Any, str] | tuple[str, ...] | None = None,
                 fmt: str | None = None, query: str | None = "", readonly: bool = False,
                 tolerance: float = 1e-4, accepted: str = "", help: str = "") -> None:
        if type not in TYPES:
            raise ValueError(f"Setting {command!r}: type {type!r}; expected one of "
                             f"{', '.join(TYPES)}")
        if type == "bool":
            choices = choices or ("ON", "OFF")
            if not isinstance(choices, Mapping):
                choices = {True: choices[0], False: choices[1]}
        elif isinstance(choices, tuple):
            choices = {word: word for word in choices}
        self.command = command
        self.type = type
        self.unit = unit
        self.minimum = minimum
        self.maximum = maximum
        self.choices: dict[Any, str] | None = dict(choices) if choices else None
        self.fmt = fmt or DEFAULT_FORMAT.get(type, "")
        self.query = None if query is None else (query or command + "?")
        self.readonly = readonly
        self.tolerance = tolerance
        self.accepted = accepted
        self.help = help
        self.name = command

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    # ------------------------------------------------------------------ descriptor
    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        if instance is None:
            return self
        return instance.get(self.name)

    def __set__(self, instance: Any, value: Any) -> None:
        instance.set(self.name, value)

    # ------------------------------------------------------------------ declaration
    @property
    def fields(self) -> tuple[str, ...]:
        """Names of the fields its command and query take (``("channel",)``)."""
        return tuple(dict.fromkeys(_fields(self.command) + _fields(self.query or "")))

    def param(self, default: Any = REQUIRED, help: str | None = None,
              name: str | None = None) -> Param:
        """The profile parameter that gives this setting: same type, unit, bounds and choices.

        Parameters
        ----------
        default
            The parameter's default (:data:`~fsi_lab.params.REQUIRED`, None for "unset").
        help
            Its help (default: the setting's).
        name
            Its name in the profile (default: the setting's attribute name).
        """
        choices = tuple(self.choices) if self.type == "str" and self.choices else None
        return Param(name or self.name, self.type, self.unit, default, minimum=self.minimum,
                     maximum=self.maximum, choices=choices,
                     help=self.help if help is None else help)

    def describe(self) -> str:
        """What values it accepts, in words (``"a number >= 0 V/V and <= 100 V/V"``)."""
        return self.param(None).describe()

    # ------------------------------------------------------------------ commands
    def check(self, value: Any) -> Any:
        """``value`` converted to the setting's type; ValueError naming the setting and what
        it accepts when the value is of another type or out of bounds."""
        wrong = ValueError(f"{self.name} = {value!r}: accepted {self.describe()}")
        if self.type == "bool":
            if not isinstance(value, bool):
                raise wrong
            return value
        if self.type == "str":
            if self.choices is not None and value not in self.choices:
                raise wrong
            if self.choices is None and not (isinstance(value, str) and _WORD.match(value)):
                raise ValueError(f"{self.name} = {value!r}: accepted one word of printable "
                                 "ASCII (no spaces, quotes, commas or semicolons)")
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise wrong
        if self.type == "int" and value != int(value):
            raise wrong
        value = int(value) if self.type == "int" else float(value)
        if (self.minimum is not None and value < self.minimum) \
                or (self.maximum is not None and value > self.maximum) or math.isnan(value):
            raise wrong
        return value

    def word(self, value: Any) -> str:
        """How the instrument writes ``value`` (checked): ``"ON"``, ``"NORM"``, ``"2.5"``."""
        value = self.check(value)
        if self.choices is not None:
            return self.choices[value]
        return format(value, self.fmt)

    def command_for(self, value: Any, **fields: Any) -> str:
        """The command that sets ``value`` (``"SOUR1:FUNC:ARB:SRAT 1000"``)."""
        if self.readonly:
            raise ValueError(f"{self.name} is read-only ({self.query})")
        return f"{self.command.format(**fields)} {self.word(value)}"

    def query_for(self, **fields: Any) -> str:
        """The query that reads it (``"SOUR1:FUNC:ARB:SRAT?"``)."""
        if self.query is None:
            raise ValueError(f"{self.name} cannot be read back ({self.command} has no query)")
        return self.query.format(**fields)

    def generic(self, value: Any) -> str:
        """The command without its fields, for messages (``"OUTP OFF"`` for ``"OUTP{channel}"``)."""
        bare = "".join(text for text, _, _, _ in string.Formatter().parse(self.command))
        return f"{bare} {self.word(value)}"

    def parse(self, reply: str) -> Any:
        """The value a reply to :meth:`query_for` says (ValueError naming what was expected)."""
        text = reply.strip()
        if self.type == "bool":
            words = {w.upper(): v for v, w in self.choices.items()}
            words.update({"1": True, "0": False, "ON": True, "OFF": False})
            if text.upper() in words:
                return words[text.upper()]
            raise ValueError("expected 0 or 1")  # SCPI booleans read back as 0 or 1
        if self.type == "str" and self.choices is None:
            return text.strip('"')
        if self.type == "str":
            for value, word in self.choices.items():
                if text.upper() == word.upper():
                    return value
            raise ValueError(f"expected one of {', '.join(self.choices.values())}")
        if self.type == "int":
            try:
                return int(text.lstrip("+"))
            except ValueError:
                raise ValueError("expected an integer") from None
        try:
            return float(text)
        except ValueError:
            raise ValueError("expected a number") from None

    def __repr__(self) -> str:
        return f"Setting({self.name!r}, {self.command!r}, {self.type!r}, {self.unit!r})"
