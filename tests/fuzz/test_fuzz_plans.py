"""Mutated sequence plans, by their tables (values replaced, keys removed or added, tables turned
into values) and by their bytes, given to ``fsi-lab sequence PLAN --out DIR``: the plan is
accepted (every run's profile checked), or refused with exit 2 and one message naming the plan
or its base profile, nothing written; never a traceback. The runs of an accepted plan are not
carried out here (test_sequence.py does that): the sequence stops before its first run."""

import tomllib

import pytest
from fuzzkit import FUZZ, check_command, scalars, tally, texts, toml_dumps, toml_values
from hypothesis import given, settings
from hypothesis import strategies as st
from support import SIM_PROFILE

import fsi_lab.plan
import fsi_lab.sequence

BASE_PLAN = """[plan]
profile = "base.toml"
name = "levels"
set = ["run.duration=0.5"]
settle_s = 1.0
on_failure = "stop"

[[step]]
name = "reference"

[[step]]
name = "levels"
repeats = 2
set = ["bench.amplifier.gain=1"]
[step.sweep]
"excitation.amplitude" = [0.25, 0.5]
"bench.amplifier.gain" = { from = 1, to = 2, points = 2, scale = "log" }
"""
STRUCTURAL_CASES = 100
BYTE_CASES = 60


@pytest.fixture
def stopped_before_the_runs(monkeypatch):
    """An accepted plan is checked and recorded, then ends before its first run; a plan
    holds at most 40 runs here, so that no case checks thousands."""
    monkeypatch.setattr(fsi_lab.sequence.SequenceRunner, "run", lambda self: "completed")
    monkeypatch.setattr(fsi_lab.plan, "MAX_RUNS", 40)


def _paths(node, prefix=()):
    if isinstance(node, dict):
        for key, value in node.items():
            yield prefix + (key,)
            yield from _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            if isinstance(value, dict):
                yield from _paths(value, prefix + (i,))


def _like(draw, old):
    if isinstance(old, bool):
        return draw(st.booleans())
    if isinstance(old, (int, float)):
        factor = draw(st.sampled_from([0, -1, 1e-300, 0.5, 2, 10, 1e3, 1e300]))
        scaled = old * factor
        return int(scaled) if isinstance(old, int) and abs(scaled) < 1e18 else scaled
    if isinstance(old, str):
        return draw(st.one_of(texts, st.just(old + "x"), st.sampled_from([
            "excitation.amplitude=3", "bench.amplifier.gain=50", "run.duration", "x.y=1",
            "continue", "base.toml", "missing.toml", "excitation.plugin=ramp-derivative"])))
    if isinstance(old, list):
        return draw(st.lists(st.one_of(st.sampled_from(old or [0]), scalars), max_size=4))
    return draw(toml_values)


@st.composite
def structural_mutants(draw):
    doc = tomllib.loads(BASE_PLAN)
    for _ in range(draw(st.sampled_from([1, 1, 2, 3]))):
        paths = list(_paths(doc))
        path = draw(st.sampled_from(paths))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        old = parent[path[-1]]
        operation = draw(st.sampled_from(["like"] * 6 + ["any", "delete", "add", "table"]))
        if operation == "like" and not isinstance(old, (dict, list)) or operation == "like" \
                and isinstance(old, list) and not all(isinstance(v, dict) for v in old):
            parent[path[-1]] = _like(draw, old)
        elif operation == "any":
            parent[path[-1]] = draw(toml_values)
        elif operation == "delete":
            del parent[path[-1]]
        elif operation == "add" and isinstance(parent, dict):
            parent[draw(st.sampled_from(["x", "set", "sweep", "repeats", "settle_s", "from",
                                         "points", "excitation.amplitude", "profile"]))] \
                = draw(toml_values)
        elif operation == "table":
            parent[path[-1]] = {} if not isinstance(old, dict) else draw(toml_values)
    return toml_dumps(doc).encode()


@st.composite
def byte_mutants(draw):
    data = bytearray(BASE_PLAN.encode())
    operation = draw(st.sampled_from(["cut", "insert", "flip", "encoding"]))
    if operation == "cut":
        data = data[:draw(st.integers(0, len(data)))]
    elif operation == "insert":
        at = draw(st.integers(0, len(data)))
        data[at:at] = draw(st.binary(min_size=1, max_size=8))
    elif operation == "flip":
        for _ in range(draw(st.integers(1, 6))):
            at = draw(st.integers(0, len(data) - 1))
            data[at] ^= 1 << draw(st.integers(0, 7))
    else:
        data = bytearray(BASE_PLAN.encode(draw(st.sampled_from(["utf-16", "utf-8-sig"]))))
    return bytes(data)


def _check_plan(tmp_path, count, data, json_flag):
    plan = tmp_path / "plan.toml"
    plan.write_bytes(data)
    out = tmp_path / f"out{count}"
    check_command(["sequence", str(plan), "--out", str(out), *json_flag],
                  named=[str(plan), str(tmp_path / "base.toml")],
                  inputs=[plan, tmp_path / "base.toml"], outputs=[out])


@pytest.mark.parametrize("mutants, cases, name", [
    (structural_mutants, STRUCTURAL_CASES, "plan tables"),
    (byte_mutants, BYTE_CASES, "plan bytes")])
def test_mutated_plans_are_accepted_or_refused(tmp_path, loaded_once, stopped_before_the_runs,
                                               mutants, cases, name):
    (tmp_path / "base.toml").write_text(SIM_PROFILE.format(
        duration=0.5, realtime="false", amplitude=0.5, amplifier_extra="",
        acquisition_extra="", analysis=""))
    count = [0]

    @settings(FUZZ, max_examples=cases)
    @given(mutants(), st.sampled_from([[], ["--json"]]))
    def case(data, json_flag):
        count[0] += 1
        _check_plan(tmp_path, count[0], data, json_flag)

    case()
    tally(name, count[0], cases)
