"""What every fuzzing test shares: the command run in this process with the invariants checked,
a TOML writer for mutated profiles, and strategies for the values a user may type or feed.

Every case must end with exit 0, or exit 2 with exactly one message that names the input at
fault; never a traceback; nothing written on a refusal; the input files unchanged. Hypothesis is
derandomised (the same cases on every run) and has no deadline (the machine may be slow).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any, Iterable

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from support import run_main

#: The settings of every fuzzing test: reproducible, no time limit per case, no database.
FUZZ = settings(derandomize=True, deadline=None, database=None, print_blob=False,
                suppress_health_check=list(HealthCheck))

_MESSAGE = "fsi-lab: error: "
#: Cases run to the end of their checks in this session, by test (reported at the end of the
#: session); cases Hypothesis abandoned while drawing them are not counted.
TALLY: dict[str, int] = {}


def tally(name: str, count: int, wanted: int) -> None:
    """Record that test ``name`` ran ``count`` cases to the end of their checks, and require
    the ``wanted`` number."""
    TALLY[name] = count
    assert count >= wanted, f"{name}: {count} cases generated; {wanted} wanted"


def check_command(args: list[str], named: Iterable[str], inputs: Iterable[Path] = (),
                  outputs: Iterable[Path] = (), codes: tuple[int, ...] = (0, 2)) -> int:
    """Run ``fsi-lab ARGS`` in this process and check the invariants; return the exit code.

    Parameters
    ----------
    args
        The command line.
    named
        Texts of which a refusal's message must contain one (the file, or the option at fault).
    inputs
        Files that must be byte for byte the same afterwards.
    outputs
        Files that must not exist after a refusal.
    codes
        Exit codes accepted.
    """
    before = {path: path.read_bytes() for path in inputs if path.is_file()}
    code, out, err = run_main(*args)
    context = f"fsi-lab {' '.join(map(str, args))[:300]}\nexit {code}\nstderr: {err[-2000:]}"
    assert "Traceback" not in err and "Traceback" not in out, context
    assert code in codes, context
    if "--json" in args and code in (0, 2):
        obj = json.loads(out)  # exactly one JSON object on stdout
        assert isinstance(obj, dict), context
        if code == 2:
            assert obj["exit_code"] == 2, context
    if code == 2:
        messages = [line for line in err.splitlines() if line.startswith(_MESSAGE)]
        assert len(messages) == 1 and err.count(_MESSAGE) == 1, context
        text = messages[0][len(_MESSAGE):]
        assert any(text.startswith(name) or f"{name}: " in text for name in named), context
        for path in outputs:
            assert not path.exists(), context
    for path, data in before.items():
        assert path.read_bytes() == data, context
    return code


# --------------------------------------------------------------------------- TOML
_BARE = re.compile(r"[A-Za-z0-9_-]+")


def _key(key: str) -> str:
    return key if _BARE.fullmatch(key) else json.dumps(key, ensure_ascii=False)


def toml_value(value: Any) -> str:
    """``value`` written as a TOML value (tables inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"no TOML for {value!r}")


def toml_dumps(doc: dict[str, Any]) -> str:
    """A TOML document whose tables are ``[a.b]`` sections (what tomllib reads back)."""
    lines: list[str] = []

    def table(node: dict[str, Any], path: list[str]) -> None:
        scalars = {k: v for k, v in node.items() if not isinstance(v, dict)}
        tables = {k: v for k, v in node.items() if isinstance(v, dict)}
        if path and (scalars or not tables):
            lines.append("[" + ".".join(_key(p) for p in path) + "]")
        lines.extend(f"{_key(k)} = {toml_value(v)}" for k, v in scalars.items())
        for key, sub in tables.items():
            table(sub, path + [key])

    table(doc, [])
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- values
EDGE_FLOATS = [0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e308, -1e308, 1e40, -1e40, 1e-9,
               float("nan"), float("inf"), float("-inf"), 0.5, 1.0, -1.0, 2.0, 10.0, 100.0,
               86400.0, 204800.0, 160e6]
EDGE_INTS = [0, 1, -1, 2, 3, 4, 5, 7, 64, 65, 2**31, 2**63 - 1, 2**63, -(2**63), 10**40,
             10**400]

floats = st.one_of(st.sampled_from(EDGE_FLOATS), st.floats(allow_nan=True, allow_infinity=True))
ints = st.one_of(st.sampled_from(EDGE_INTS), st.integers(min_value=-10**6, max_value=10**6))
#: Text with whatever a user or a damaged file can put in: controls, non-ASCII, TOML syntax.
texts = st.one_of(st.sampled_from(["", " ", "embedded", "none", "auto", "a\x00b", "x\ny",
                                   "125mm/s/V", "1000mm/s/V", "water", "air", "[", "=", "\"",
                                   "\u00e9t\u00e9", "tip_velocity", "base_acceleration"]),
                  st.text(max_size=12))
scalars = st.one_of(st.booleans(), ints, floats, texts)
toml_values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=6)


#: Numbers as a user might type them, or something close to one.
number_texts = st.one_of(
    floats.map(repr), ints.map(str),
    st.sampled_from(["1e999", "-1e999", "nan", "inf", "-inf", "1_000", "0x10", "1e", "--1",
                     "9" * 400, "", " 5 ", "1,5", "[1,2]", "1/2", "\u0661"]))
