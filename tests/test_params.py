"""The parameter schema: validation, defaults, command-line parsing and messages."""

import pytest

from fsi_lab.errors import ParameterError
from fsi_lab.params import REQUIRED, Param, validate

SCHEMA = (
    Param("amplitude", "float", "V", 0.5, minimum=-10.0, maximum=10.0, help="Peak."),
    Param("components", "int", "", 2, minimum=1),
    Param("method", "str", "", "decrement", choices=("decrement", "eq5", "eq7")),
    Param("enabled", "bool", "", True),
    Param("cutoff", "float", "Hz", None, minimum=0.0, exclusive_minimum=True),
    Param("ratios", "floats", "", [0.002], minimum=0.0, maximum=1.0),
    Param("gain", "float", "V/V", REQUIRED, minimum=0.0),
)


def test_defaults_are_filled_and_values_converted():
    values = validate(SCHEMA, {"gain": 2, "amplitude": 1}, "bench.x")
    assert values == {"amplitude": 1.0, "components": 2, "method": "decrement",
                      "enabled": True, "cutoff": None, "ratios": [0.002], "gain": 2.0}
    assert isinstance(values["amplitude"], float)


@pytest.mark.parametrize("values, fragment", [
    ({"gain": 1, "amplitud": 1.0}, "excitation.amplitud: unknown key; allowed keys are"),
    ({}, "excitation.gain: missing; expected a number >= 0"),
    ({"gain": "2"}, "excitation.gain: got '2' (str); expected a number"),
    ({"gain": 1, "amplitude": 11.0}, "excitation.amplitude: 11.0 is out of bounds; expected a "
                                     "number >= -10 V and <= 10 V"),
    ({"gain": 1, "components": 1.5}, "excitation.components: got 1.5 (float); expected an integer"),
    ({"gain": 1, "components": True}, "expected an integer"),
    ({"gain": 1, "enabled": 1}, "excitation.enabled: got 1 (int); expected true or false"),
    ({"gain": 1, "method": "fit"}, "expected one of 'decrement', 'eq5', 'eq7'"),
    ({"gain": 1, "cutoff": 0.0}, "expected a number > 0 Hz"),
    ({"gain": 1, "ratios": [0.1, 2.0]}, "excitation.ratios[1]: 2.0 is out of bounds"),
    ({"gain": float("nan")}, "expected a finite number"),
])
def test_bad_values_name_the_key_and_what_is_accepted(values, fragment):
    with pytest.raises(ParameterError) as info:
        validate(SCHEMA, values, "excitation")
    assert fragment in str(info.value)


@pytest.mark.parametrize("name, text, expected", [
    ("amplitude", "0.25", 0.25),
    ("components", "3", 3),
    ("enabled", "false", False),
    ("enabled", "on", True),
    ("method", "eq5", "eq5"),
    ("cutoff", "auto", None),
    ("ratios", "0.002,0.001", [0.002, 0.001]),
])
def test_parse_command_line_strings(name, text, expected):
    param = next(p for p in SCHEMA if p.name == name)
    assert param.parse(text, f"x.{name}") == expected


def test_parse_refuses_unreadable_text():
    with pytest.raises(ParameterError, match=r"x.components: cannot read 'two'; expected an integer"):
        SCHEMA[1].parse("two", "x.components")


def test_describe_is_json_friendly():
    info = SCHEMA[0].as_dict()
    assert info == {"name": "amplitude", "type": "float", "unit": "V", "default": 0.5,
                    "required": False, "minimum": -10.0, "exclusive_minimum": False,
                    "maximum": 10.0, "choices": None, "help": "Peak."}
    assert SCHEMA[-1].as_dict()["required"] is True
    assert SCHEMA[4].as_dict()["exclusive_minimum"] is True


def test_unknown_type_is_refused():
    with pytest.raises(ParameterError, match="allowed types"):
        Param("x", "complex")
