"""Mutated profiles, by their tables (values replaced, keys removed or added, tables turned
into values) and by their bytes (cut short, bytes inserted or flipped, other encodings), given
to ``fsi-lab profile check``: exit 0, or exit 2 with one message naming the file; never a
traceback or a hang; the profile left as it was."""

import tomllib

from fuzzkit import FUZZ, check_command, scalars, tally, texts, toml_dumps, toml_values
from hypothesis import given, settings
from hypothesis import strategies as st
from support import PROFILES, SIM_PROFILE

BASES = {path.name: path.read_text() for path in sorted(PROFILES.glob("*.toml"))}
BASES["in-process.toml"] = SIM_PROFILE.format(
    duration=0.5, realtime="false", amplitude=0.5, amplifier_extra="", acquisition_extra="",
    analysis='[analysis]\nchain = ["spectrum", "hvd"]\nchannels = ["tip_velocity"]\n')
STRUCTURAL_CASES = 350
BYTE_CASES = 250


def _paths(node, prefix=()):
    """Every key path of a parsed profile, tables included."""
    for key, value in node.items():
        yield prefix + (key,)
        if isinstance(value, dict):
            yield from _paths(value, prefix + (key,))


def _like(draw, old):
    """A value of the same kind as ``old``, mostly near it: most cases get past the type
    checks to the bounds, the instruments' checks and the safety check."""
    if isinstance(old, bool):
        return draw(st.booleans())
    if isinstance(old, (int, float)):
        factor = draw(st.sampled_from([0, -1, 1e-300, 1e-3, 0.1, 0.5, 0.9, 1.1, 2, 10, 1e3,
                                       1e300]))
        scaled = old * factor
        return int(scaled) if isinstance(old, int) and abs(scaled) < 1e18 else scaled
    if isinstance(old, str):
        return draw(st.one_of(texts, st.just(old.upper()), st.just(old + "x")))
    if isinstance(old, list):
        return draw(st.lists(st.one_of(st.sampled_from(old or [0]), scalars), max_size=6))
    return draw(toml_values)


@st.composite
def structural_mutants(draw):
    name = draw(st.sampled_from(sorted(BASES)))
    doc = tomllib.loads(BASES[name])
    for _ in range(draw(st.sampled_from([1, 1, 1, 2, 3]))):
        paths = list(_paths(doc))
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        old = parent[path[-1]]
        operation = draw(st.sampled_from(["like"] * 6 + ["any", "delete", "add", "table"]))
        if operation == "like" and not isinstance(old, dict):
            parent[path[-1]] = _like(draw, old)
        elif operation == "any":
            parent[path[-1]] = draw(toml_values)
        elif operation == "delete":
            del parent[path[-1]]
        elif operation == "add":
            parent[draw(st.sampled_from(["x", "plugin", "address", "gain", "input", "sensor",
                                         "chain", "embedded", "reference", "tip_velocity"]))] \
                = draw(toml_values)
        elif operation == "table":
            parent[path[-1]] = {} if not isinstance(old, dict) else draw(toml_values)
    return name, toml_dumps(doc).encode()


@st.composite
def byte_mutants(draw):
    name = draw(st.sampled_from(sorted(BASES)))
    data = bytearray(BASES[name].encode())
    operation = draw(st.sampled_from(["cut", "insert", "flip", "lines", "encoding"]))
    if operation == "cut":
        data = data[:draw(st.integers(0, len(data)))]
    elif operation == "insert":
        at = draw(st.integers(0, len(data)))
        data[at:at] = draw(st.binary(min_size=1, max_size=8))
    elif operation == "flip":
        for _ in range(draw(st.integers(1, 6))):
            at = draw(st.integers(0, len(data) - 1))
            data[at] ^= 1 << draw(st.integers(0, 7))
    elif operation == "lines":
        lines = bytes(data).split(b"\n")
        at = draw(st.integers(0, len(lines) - 1))
        lines[at:at + 1] = draw(st.sampled_from([[], [lines[at]] * 2, [b"[run]"], [b"[[x]]"]]))
        data = bytearray(b"\n".join(lines))
    else:
        data = bytearray(BASES[name].encode(draw(st.sampled_from(["utf-16", "utf-32",
                                                                  "utf-8-sig"]))))
    return name, bytes(data)


def _check_profile(tmp_path, loaded_once, data, json_flag):
    path = tmp_path / "profile.toml"
    path.write_bytes(data)
    check_command(["profile", "check", str(path), *json_flag], named=[str(path)],
                  inputs=[path])


def test_mutated_profile_tables_are_checked_or_refused(tmp_path, loaded_once):
    count = [0]

    @settings(FUZZ, max_examples=STRUCTURAL_CASES)
    @given(structural_mutants(), st.sampled_from([[], ["--json"]]))
    def case(mutant, json_flag):
        count[0] += 1
        _check_profile(tmp_path, loaded_once, mutant[1], json_flag)

    case()
    tally("profile tables", count[0], STRUCTURAL_CASES)


def test_mutated_profile_bytes_are_checked_or_refused(tmp_path, loaded_once):
    count = [0]

    @settings(FUZZ, max_examples=BYTE_CASES)
    @given(byte_mutants(), st.sampled_from([[], ["--json"]]))
    def case(mutant, json_flag):
        count[0] += 1
        _check_profile(tmp_path, loaded_once, mutant[1], json_flag)

    case()
    tally("profile bytes", count[0], BYTE_CASES)
