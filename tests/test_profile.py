"""Profiles: every kind of bad profile is refused with one clear message and exit code 2."""

import pytest
from support import PROFILES, cli, cli_here, cli_json_here

from fsi_lab.errors import ProfileError
from fsi_lab.profile import load_profile, parse_profile

GOOD = PROFILES / "wet-beam-sim.toml"


def _variant(tmp_path, old, new, name="bad.toml"):
    text = GOOD.read_text()
    assert old in text, f"test setup: {old!r} not in the profile"
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def test_shipped_profile_is_valid(registry):
    profile = load_profile(GOOD, registry)
    assert profile.can_run
    assert profile.roles["amplifier"].settings["gain"] == 2.0
    assert profile.channels["tip_velocity"].sensor == "vibrometer"
    assert profile.specimen.fluid == "water"
    assert profile.text == GOOD.read_text()


BAD_CASES = [
    ("syntax", "[run]\n", "[run\n", "TOML syntax error"),
    ("unknown key", "duration = 10.0", "duraton = 10.0",
     "run.duraton: unknown key; allowed keys are block_duration, duration, name, sample_rate"),
    ("unknown section", "\n[shaker]\n", "\n[shakr]\n",
     "shakr: unknown section; allowed sections are"),
    ("wrong type", "gain = 2.0", 'gain = "high"',
     "bench.amplifier.gain: got 'high' (str); expected a number >= 0 V/V and <= 100 V/V"),
    ("out of bounds", "sample_rate = 10000.0", "sample_rate = 1e6",
     "run.sample_rate: 1000000.0 is out of bounds; expected a number >= 1 Hz and <= 204800 Hz"),
    ("missing required", "max_gain = 10.0", "",
     "safety.max_gain: missing; expected a number > 0 V/V"),
    ("unknown plugin", 'plugin = "ramp-derivative"', 'plugin = "ramp"',
     "excitation.plugin: unknown excitation plugin 'ramp'; installed excitation plugins:"),
    ("unknown instrument", 'plugin = "shaker-amplifier"', 'plugin = "pa25e"',
     "bench.amplifier.plugin: unknown instrument plugin 'pa25e'"),
    ("wrong role", 'plugin = "shaker-amplifier"', 'plugin = "keysight33500"',
     "bench.amplifier.plugin: 'keysight33500' is a source driver, not an amplifier"),
    ("bad choice", 'fluid = "water"', 'fluid = "oil"',
     "specimen.fluid: got 'oil'; expected one of 'air', 'water'"),
    ("unit mismatch", 'unit = "m/s^2"', 'unit = "m/s"',
     "channels.base_acceleration.unit: 'm/s' is a unit of velocity"),
    ("unknown analysis", 'chain = ["spectrum"', 'chain = ["hilbert"',
     "analysis.hilbert.plugin: unknown analysis plugin 'hilbert'"),
    ("negative geometry", "length = 0.08", "length = -0.08",
     "specimen.length: -0.08 is out of bounds; expected a number >= 0.001 m and <= 10 m"),
    ("unknown sensor", 'sensor = "vibrometer"', 'sensor = "vibrometr"',
     "channels.tip_velocity.sensor: 'vibrometr' is not an instrument of this bench; expected "
     "empty or one of the roles with a [bench.<role>] table: 'source', 'amplifier', "
     "'vibrometer', 'acquisition'"),
    ("slash in a channel name", "[channels.tip_velocity]", '[channels."tip/velocity"]',
     "channels.tip/velocity: channel name 'tip/velocity' is not accepted; expected a letter "
     "followed by letters, digits, '_' or '-' (e.g. tip_velocity)"),
]


@pytest.mark.parametrize("case, old, new, fragment", BAD_CASES, ids=[c[0] for c in BAD_CASES])
def test_bad_profile_is_refused_and_nothing_is_written(tmp_path, case, old, new, fragment):
    path = _variant(tmp_path, old, new)
    out = tmp_path / "runs"
    proc = cli_here("run", str(path), "--out", str(out))
    assert proc.returncode == 2, proc.stderr
    assert str(path) in proc.stderr
    assert fragment in proc.stderr
    assert proc.stderr.count("fsi-lab: error:") == 1, proc.stderr  # one message
    assert "Traceback" not in proc.stderr
    assert not out.exists()

    check = cli_here("profile", "check", str(path))
    assert check.returncode == 2 and fragment in check.stderr


def test_json_error_is_one_object(tmp_path):
    path = _variant(tmp_path, "duration = 10.0", "duration = -1.0")
    data, proc = cli_json_here("profile", "check", str(path))
    assert proc.returncode == 2
    assert data["exit_code"] == 2 and "run.duration" in data["error"]


def test_missing_file_is_named(tmp_path):
    proc = cli_here("profile", "check", str(tmp_path / "nope.toml"))
    assert proc.returncode == 2
    assert "nope.toml: no such file; expected a profile (TOML text)" in proc.stderr


def test_set_overrides_any_parameter_by_path(registry):
    profile = load_profile(GOOD, registry, ["excitation.height=0.02", "bench.amplifier.gain=3",
                                           "run.duration=2", "specimen.fluid=air",
                                           "analysis.channels=tip_velocity,drive"])
    assert profile.excitation["height"] == 0.02
    assert profile.roles["amplifier"].settings["gain"] == 3.0
    assert profile.run["duration"] == 2.0
    assert profile.specimen.fluid == "air"
    assert profile.analysis["channels"] == ["tip_velocity", "drive"]
    assert profile.overrides[0] == "excitation.height=0.02"


def test_set_appends_to_the_analysis_chain(registry):
    """analysis.chain+=NAME adds analyses to the chain in force (adding one meant typing the
    whole chain), each once; to the default chain where nothing gave one."""
    from fsi_lab.chain import default_chain

    shipped = load_profile(GOOD, registry).analysis["chain"]
    profile = load_profile(GOOD, registry, ["analysis.chain+=frf,hvd", "analysis.chain+=frf"])
    assert profile.analysis["chain"] == shipped + ["frf"]
    profile = load_profile(GOOD, registry, ["analysis.chain=spectrum", "analysis.chain+=hvd"])
    assert profile.analysis["chain"] == ["spectrum", "hvd"]
    bare = parse_profile("", "imported", registry, ["analysis.chain+=frf"],
                         sections=("analysis", "specimen"))
    assert bare.analysis["chain"] == default_chain(registry) + ["frf"]
    with pytest.raises(ProfileError, match=r"\+= appends to the analysis chain only"):
        load_profile(GOOD, registry, ["run.duration+=5"])


def test_set_excitation_plugin_starts_from_its_defaults(registry):
    # the plugin switch applies first wherever it stands; the profile's ramp parameters go
    profile = load_profile(GOOD, registry, ["excitation.count=4",
                                           "excitation.plugin=impulse-train"])
    assert profile.excitation_plugin == "impulse-train"
    assert profile.excitation["count"] == 4
    defaults = {p.name: p.default for p in registry.get("excitation", "impulse-train").params}
    assert profile.excitation["spacing"] == defaults["spacing"]
    assert "height" not in profile.excitation


@pytest.mark.parametrize("override, fragment", [
    ("excitation.hieght=1", "excitation.hieght: unknown key; allowed keys are height,"),
    ("run.duration=long", "run.duration: cannot read 'long'; expected a number"),
    ("bench.amplifier.gain=1000", "bench.amplifier.gain: 1000.0 is out of bounds"),
    ("nonsense=1", "expected key.path=value"),
    ("excitation.height", "expected key.path=value"),
    ("widget.size=1", "widget.size: no such parameter"),
    ("excitation.plugin=sawtooth", "excitation.plugin: unknown excitation plugin 'sawtooth'"),
])
def test_bad_set_is_refused(registry, override, fragment):
    with pytest.raises(ProfileError) as info:
        load_profile(GOOD, registry, [override])
    assert fragment in str(info.value) and str(GOOD) in str(info.value)


def test_a_value_refused_names_the_set_that_gave_it(registry):
    # the profile's own value is good; the second --set of the key is the one refused
    sets = ["excitation.height=0.001", "excitation.height=20"]
    with pytest.raises(ProfileError) as info:
        load_profile(GOOD, registry, sets)
    assert str(info.value).startswith(f"{GOOD}: --set excitation.height=20: excitation.height: "
                                      "20.0 is out of bounds")


def test_safety_limits_refuse_before_anything_is_written(tmp_path):
    out = tmp_path / "runs"
    proc = cli("run", str(GOOD), "--out", str(out), "--set", "excitation.height=0.1")
    assert proc.returncode == 2
    # the 5 V pulse comes out of the source's band-limited filter with its overshoot
    assert "exceeds safety.max_drive_v = 2 V (the samples peak at 5 V;" in proc.stderr
    assert "refused before anything was sent" in proc.stderr
    assert not out.exists()

    proc = cli("run", str(GOOD), "--out", str(out), "--set", "bench.amplifier.gain=9.5",
               "--set", "safety.max_stroke_mm=1")
    assert proc.returncode == 2
    assert "predicted stroke" in proc.stderr
    assert "exceeds safety.max_stroke_mm = 1 mm" in proc.stderr
    assert not out.exists()


def test_profile_check_reports_the_safety_verdict():
    data, proc = cli_json_here("profile", "check", str(GOOD))
    assert proc.returncode == 0
    safety = data["safety"]
    assert safety["ok"] is True
    # samples of 0.01 V*s over 0.02 s; the source's filter overshoots them by up to 17 %
    assert 0.5 < safety["peak_drive_v"] < 0.5 * 1.2
    assert 0 < safety["predicted_stroke_mm"] < safety["max_stroke_mm"]


@pytest.mark.parametrize("name", ["source_voltage", "Tip-2", "x"])
def test_channel_names_of_letters_digits_underscores_and_hyphens_are_accepted(registry, name):
    text = GOOD.read_text().replace("[channels.drive]", f"[channels.{name}]", 1)
    assert name in parse_profile(text, "p.toml", registry).channels


@pytest.mark.parametrize("name", ["tip.velocity", "2nd", "_drive", "tip velocity", ""])
def test_channel_names_that_would_break_paths_are_refused(registry, name):
    text = GOOD.read_text().replace("[channels.drive]", f'[channels."{name}"]', 1)
    with pytest.raises(ProfileError) as info:
        parse_profile(text, "p.toml", registry)
    assert str(info.value).startswith(f"p.toml: channels.{name}: channel name {name!r} is not "
                                      "accepted")


def test_sensor_must_be_a_role_of_the_bench(registry):
    text = GOOD.read_text()
    start = text.index("[bench.vibrometer]")
    without = text[:start] + text[text.index("[bench.acquisition]"):]
    with pytest.raises(ProfileError) as info:
        parse_profile(without, "p.toml", registry)
    assert ("p.toml: channels.tip_velocity.sensor: 'vibrometer' is not an instrument of this "
            "bench; expected empty or one of the roles with a [bench.<role>] table: 'source', "
            "'amplifier', 'acquisition'") == str(info.value)
    with pytest.raises(ProfileError, match="channels.tip_velocity.sensor: 'amplifer'"):
        load_profile(GOOD, registry, ["channels.tip_velocity.sensor=amplifer"])
    assert load_profile(GOOD, registry, ["channels.tip_velocity.sensor="]).channels[
        "tip_velocity"].sensor == ""


def test_sensor_is_not_checked_when_the_bench_is_left_out(registry):
    # fsi-lab safe keeps only what opening the instruments needs; analyze only the analysis
    text = GOOD.read_text().replace('sensor = "vibrometer"', 'sensor = "vibrometr"')
    for sections in (("bench", "specimen", "model", "shaker"), ("analysis", "specimen"),
                     ("channels", "analysis")):
        profile = parse_profile(text, "p.toml", registry, sections=sections)
        assert ("channels" in sections) == bool(profile.channels)
    with pytest.raises(ProfileError, match="'vibrometr' is not an instrument of this bench"):
        parse_profile(text, "p.toml", registry, sections=("bench", "channels"))


def test_every_numeric_parameter_of_the_core_instruments_and_excitations_has_bounds(registry):
    from fsi_lab.modelling import MODEL_PARAMS
    from fsi_lab.profile import (
        ANALYSIS_PARAMS,
        BENCH_PARAMS,
        CHANNEL_PARAMS,
        RUN_PARAMS,
        SAFETY_PARAMS,
        SHAKER_PARAMS,
    )
    from fsi_lab.specimen import SPECIMEN_PARAMS

    schemas = {"run": RUN_PARAMS, "safety": SAFETY_PARAMS, "shaker": SHAKER_PARAMS,
               "specimen": SPECIMEN_PARAMS, "model": MODEL_PARAMS, "bench": BENCH_PARAMS,
               "channels.<name>": CHANNEL_PARAMS, "analysis": ANALYSIS_PARAMS}
    for kind in ("instrument", "excitation"):
        for name, descriptor in registry.descriptors[kind].items():
            schemas[f"{kind} {name}"] = descriptor.params
    unbounded = [f"{where}.{p.name}" for where, schema in schemas.items() for p in schema
                 if p.type in ("float", "int", "floats") and p.choices is None
                 and (p.minimum is None or p.maximum is None)]
    assert len(schemas) >= 20 and unbounded == []


def test_a_channel_in_g_is_refused_at_the_profile_check(sim_profile):
    """A profile channel in g was accepted, and the run then completed with its modal model
    refusing the reference ('expected the base acceleration in m/s^2'): runs store SI units,
    so g is refused before anything runs, saying what to write instead."""
    from support import run_main

    path = sim_profile()
    text = path.read_text()
    old = 'unit = "m/s^2"\nsensitivity = 0.0102\n'
    assert old in text
    path.write_text(text.replace(old, 'unit = "g"\nsensitivity = 0.1\n'))
    code, out, err = run_main("profile", "check", str(path))
    assert code == 2, (out, err)
    assert err.strip() == (
        f"fsi-lab: error: {path}: channels.base_acceleration.unit: 'g' is not accepted for a "
        "recorded channel (runs store SI units, and the analysis and the modal model read an "
        "acceleration in m/s^2); expected 'm/s^2' with the sensitivity in V/(m/s^2): 0.1 V/g "
        "is 0.0101972 V/(m/s^2)")
    code, out, err = run_main("profile", "check", str(sim_profile()), "--set",
                              "channels.base_acceleration.unit=g")
    assert code == 2 and "channels.base_acceleration.unit: got 'g'; expected one of 'm', " \
        "'m/s', 'm/s^2', 'V'" in err, err
