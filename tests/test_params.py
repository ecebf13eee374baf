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
    with pytest.raises(ParameterError,
                       match=r"x.components: cannot read 'two'; expected an integer"):
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


@pytest.mark.parametrize("name, value, fragment", [
    # an integer of more than 308 digits cannot become a float (OverflowError before)
    ("amplitude", 10**400, "excitation.amplitude: an integer of 401 digits is out of bounds"),
    ("ratios", [10**309], "excitation.ratios[0]: an integer of 310 digits is out of bounds"),
    ("components", 10**400, "excitation.components: an integer of 401 digits is out of bounds"),
    # nor can an integer beyond 64 bits be stored in a run file's attributes
    ("components", 2**63, "excitation.components: 9223372036854775808 is out of bounds; "
                          "expected an integer >= 1 (and of magnitude below 2^63)"),
])
def test_integers_too_large_for_a_float_or_a_run_file_are_refused(name, value, fragment):
    with pytest.raises(ParameterError) as info:
        validate(SCHEMA, {"gain": 1, name: value}, "excitation")
    assert str(info.value).startswith(fragment), str(info.value)


def test_the_largest_storable_integer_is_accepted():
    assert validate(SCHEMA, {"gain": 1, "components": 2**63 - 1}, "x")["components"] == 2**63 - 1


@pytest.mark.parametrize("value, fragment", [
    ("a\x00b", r"'a\x00b' holds the control character '\x00' at position 1"),
    ("two\nlines", r"'two\nlines' holds the control character '\n' at position 3"),
])
def test_control_characters_in_text_are_refused(value, fragment):
    text = Param("name", "str", "", "")
    words = Param("names", "strs", "", [])
    with pytest.raises(ParameterError) as info:
        text.check(value, "run.name")
    assert str(info.value) == f"run.name: {fragment}; expected printable text"
    with pytest.raises(ParameterError, match=r"analysis.names\[1\]: .*control character"):
        words.check(["ok", value], "analysis.names")
    assert text.check("wet beam, 5 \u00b5m", "run.name") == "wet beam, 5 \u00b5m"
