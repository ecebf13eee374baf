"""``--set key=value`` as a user may type it, on the parameter paths of the example profiles
(most values near what the parameter accepts, some anything), on other plugins' paths and on
paths that do not exist, given to ``fsi-lab profile check``: exit 0, or exit 2 with one message
naming the profile; never a traceback or a hang."""

import tomllib

from fuzzkit import FUZZ, check_command, number_texts, tally, texts
from hypothesis import given, settings
from hypothesis import strategies as st
from support import PROFILES

from fsi_lab.modelling import MODEL_PARAMS
from fsi_lab.profile import (
    ANALYSIS_PARAMS,
    BENCH_PARAMS,
    CHANNEL_PARAMS,
    RUN_PARAMS,
    SAFETY_PARAMS,
    SHAKER_PARAMS,
)
from fsi_lab.registry import load_registry
from fsi_lab.specimen import SPECIMEN_PARAMS

CASES = 700
REGISTRY = load_registry()
PLUGIN_NAMES = ["step", "ramp-derivative", "impulse-train", "random", "spectrum", "hvd",
                "inprocess-source", "keysight33500", "polytec", "scpi-daq", "nope"]


def _params(raw):
    """(key path, Param) for every parameter a profile's own tables and plugins declare."""
    found = [(f"{section}.{p.name}", p) for section, schema in (
        ("run", RUN_PARAMS), ("safety", SAFETY_PARAMS), ("shaker", SHAKER_PARAMS),
        ("specimen", SPECIMEN_PARAMS), ("model", MODEL_PARAMS), ("bench", BENCH_PARAMS),
        ("analysis", ANALYSIS_PARAMS)) for p in schema]
    found += [(f"channels.{name}.{p.name}", p) for name in raw.get("channels", {})
              for p in CHANNEL_PARAMS]
    excitation = REGISTRY.descriptors["excitation"].get(raw.get("excitation", {}).get("plugin"))
    found += [(f"excitation.{p.name}", p) for p in (excitation.params if excitation else ())]
    for role, table in raw.get("bench", {}).items():
        if isinstance(table, dict):
            plugin = REGISTRY.descriptors["instrument"][table["plugin"]]
            found += [(f"bench.{role}.{p.name}", p) for p in plugin.params]
    found += [(f"analysis.{name}.{p.name}", p)
              for name, d in REGISTRY.descriptors["analysis"].items() for p in d.params]
    return found


BASES = {path: _params(tomllib.loads(path.read_text()))
         for path in sorted(PROFILES.glob("*.toml"))}
OTHER_KEYS = ["run", "x.y", "run.", ".run.duration", "bench.x.y.z", "analysis.nope.x",
              "channels.a/b.input", "excitation", "excitation.plugin", "bench.source.plugin",
              "bench.vibrometer.address", "channels.new.input", "bench.source.noise_v"]


def _near(param):
    """Text for ``param``: mostly near what it accepts (its bounds, choices, default)."""
    if param.choices is not None:
        near = st.sampled_from([str(c) for c in param.choices])
    elif param.type in ("float", "int", "floats"):
        anchors = [b for b in (param.minimum, param.maximum) if b is not None]
        if isinstance(param.default, (int, float)) and not isinstance(param.default, bool):
            anchors.append(param.default)
        factors = [1.0, 0.999, 1.001, 0.5, 2.0, -1.0, 0.0, 1e-9, 1e9]
        numbers = st.builds(lambda a, f: a * f, st.sampled_from(anchors or [1.0]),
                            st.sampled_from(factors))
        if param.type == "int":
            numbers = numbers.map(lambda x: str(int(x)) if abs(x) < 1e18 else repr(x))
        else:
            numbers = numbers.map(repr)
        near = numbers if param.type != "floats" else st.lists(numbers, max_size=5).map(",".join)
    elif param.type == "bool":
        near = st.sampled_from(["true", "false", "on", "no", "2"])
    else:
        near = texts
    return st.one_of(near, near, near, number_texts, texts)


@st.composite
def overrides(draw, base):
    params = BASES[base]
    items = []
    for _ in range(draw(st.sampled_from([1, 1, 1, 2, 3]))):
        if draw(st.integers(0, 9)) == 7:  # (hypothesis favours 0: 7 is one case in ten)
            key = draw(st.sampled_from(OTHER_KEYS))
            value = draw(st.one_of(number_texts, texts, st.sampled_from(PLUGIN_NAMES)))
        else:
            key, param = draw(st.sampled_from(params))
            value = draw(_near(param))
        items.append(key if draw(st.integers(0, 19)) == 7 else f"{key}={value}")
    return items


def test_set_values_are_checked_or_refused(tmp_path, loaded_once):
    count = [0]

    @settings(FUZZ, max_examples=CASES)
    @given(st.sampled_from(sorted(BASES)).flatmap(lambda b: st.tuples(st.just(b), overrides(b))),
           st.sampled_from([[], ["--json"]]))
    def case(drawn, json_flag):
        count[0] += 1
        base, items = drawn
        args = ["profile", "check", str(base), *json_flag]
        for item in items:
            args += ["--set", item]
        check_command(args, named=[str(base)], inputs=[base])

    case()
    tally("--set values", count[0], CASES)
