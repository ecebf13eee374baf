"""``profile check`` checks what the run will need: a profile that the instruments, the beam
model or the record would refuse at run time is refused by the check, and by ``run`` before a
run file exists (one message naming the file and the key, exit 2)."""

import pytest
from support import GOOD_PROFILE, SIM_PROFILE, run_main

WET = GOOD_PROFILE.read_text()
SIM = SIM_PROFILE.format(duration=0.5, realtime="false", amplitude=0.5, amplifier_extra="",
                         acquisition_extra="", analysis="")


def _without(text, section):
    start = text.index(f"[{section}]")
    return text[:start] + text[text.index("\n[", start + 1) + 1:]


# (case, profile text, --set overrides, what the one message must say)
CASES = [
    ("empty profile", "", [], "nothing to run: no [bench.<role>] tables and no [excitation]"),
    ("comment-only profile", "# a profile\n# to be written\n", [], "nothing to run"),
    ("truncated profile", WET[:WET.index("[bench]")], [], "nothing to run"),
    ("digitiser input beyond its count (lab digitiser)", WET, ["channels.drive.input=5"],
     "bench.acquisition: channel 'drive' uses input 5; this digitiser has inputs 1 to 4"),
    ("digitiser input beyond its count (in-process digitiser)", SIM,
     ["channels.tip_velocity.input=9"],
     "bench.acquisition: channel 'tip_velocity' uses input 9; this digitiser has inputs 1 to 4"),
    ("vibrometer range the embedded vibrometer does not offer", WET,
     ["bench.vibrometer.range=1000mm/s/V"],
     "bench.vibrometer: range: '1000mm/s/V' is not offered by the embedded simulated vibrometer; "
     "expected '5mm/s/V' or '25mm/s/V' or '125mm/s/V'"),
    ("vibrometer range that is no range", WET, ["bench.vibrometer.range=fast"],
     "bench.vibrometer: range: 'fast' is not a velocity range like 125mm/s/V"),
    ("vibrometer decoder the embedded bench lacks", WET, ["bench.vibrometer.decoder=VD-09"],
     "bench.vibrometer: decoder: 'VD-09' is not offered by the embedded simulated vibrometer"),
    ("vibrometer line speed the embedded bench does not run", WET,
     ["bench.vibrometer.baud_rate=9600"], "bench.vibrometer: baud_rate: 9600 is not offered"),
    ("embedded bench without [specimen]", _without(WET, "specimen"), [],
     "bench.source: address 'embedded' names the embedded simulated bench, but the profile has "
     "no [specimen]"),
    ("in-process bench without [specimen]", _without(SIM, "specimen"), [],
     "bench.acquisition: the simulated bench needs the profile's [specimen]"),
    ("embedded address without the embedded bench", WET, ["bench.embedded=false"],
     "bench.source: address 'embedded' names the embedded simulated bench, but the profile does "
     "not say [bench] embedded = true"),
    ("NUL in run.name", WET.replace('name = "wet beam', 'name = "wet\\u0000beam'), [],
     r"run.name: 'wet\x00beam, ramp derivative (simulated)' holds the control character '\x00'"),
    ("specimen.length = 1e308", WET, ["specimen.length=1e308"],
     "specimen.length: 1e+308 is out of bounds; expected a number >= 0.001 m and <= 10 m"),
    ("model.c_f = 1e40", WET, ["model.c_f=1e40"],
     "model.c_f: 1e+40 is out of bounds; expected a number >= 0 kg/m^2 and <= 10000 kg/m^2"),
    ("no damping ratio", WET.replace("c_i = 0.65", "damping_ratios = []"), [],
     "model: damping.ratios: empty; expected one ratio per mode"),
    ("c_i and damping ratios both", WET, ["model.damping_ratios=0.01"],
     "model: damping: both c_i and ratios are given"),
    ("a beam the embedded bench cannot resolve", WET, ["run.sample_rate=1"],
     "bench.acquisition: the simulated bench cannot resolve the highest mode at 1 Hz even "
     "oversampled 64 times; lower model.modes or raise run.sample_rate"),
    ("a beam the in-process bench cannot resolve", SIM, ["specimen.fluid=air"],
     "bench.acquisition: sample_rate: 2000 Hz cannot resolve mode 4"),
    ("a record of no sample", WET, ["run.duration=1e-300"],
     "run.duration: 1e-300 s at run.sample_rate = 10000 Hz records 0 samples; expected at "
     "least 2"),
    ("a record longer than the digitiser holds", WET,
     ["run.duration=86400", "run.sample_rate=204800", "bench.acquisition.block_duration=0.1"],
     "bench.acquisition: 17,694,720,000 samples per input (86400 s at 204800 Hz); a record "
     "holds at most 2,147,483,647"),
    ("a waveform longer than the arb memory", WET, ["excitation.duration=200"],
     "bench.source: the excitation has 2,000,000 samples at 10000 Sa/s; the arb memory holds 8 "
     "to 1,000,000 points"),
    ("a waveform longer than any source", WET, ["bench.source.sample_rate=160e6"],
     "excitation: 'ramp-derivative' would make 160,000,000 samples at 1.6e+08 Sa/s; a source "
     "holds at most 16,000,000"),
    ("a channel the embedded bench does not wire to the amplifier", WET, ["bench.source.channel=2"],
     "bench.source: channel: 2; the embedded simulated generator's channel 1 is wired to the "
     "amplifier"),
    ("input ranges not one per input", WET, ["bench.acquisition.ranges_v=10,10"],
     "bench.acquisition: ranges_v has 2 values; expected one per input (4)"),
    ("IEPE supply on an input the digitiser lacks", WET, ["bench.acquisition.iepe_inputs=2.5"],
     "bench.acquisition: iepe_inputs names input 2.5; expected inputs 1 to 4"),
    ("a negative noise seed", SIM, ["bench.acquisition.seed=-1"],
     "bench.acquisition.seed: -1 is out of bounds; expected an integer >= 0 and <= 4.29497e+09"),
    ("shaker.suspension_hz = 1e308", WET, ["shaker.suspension_hz=1e308"],
     "shaker.suspension_hz: 1e+308 is out of bounds; expected a number >= 0.1 Hz and <= 2000 Hz"),
    ("shaker.mm_per_volt = 1e308", WET, ["shaker.mm_per_volt=1e308"],
     "shaker.mm_per_volt: 1e+308 is out of bounds; expected a number > 0 mm/V and <= 100 mm/V"),
    ("an integer of 400 digits", WET.replace("sample_rate = 10000.0", "sample_rate = " + "9" * 400),
     [], "run.sample_rate: an integer of 400 digits is out of bounds"),
    ("an integer of 400 digits on the command line", WET, ["run.sample_rate=" + "9" * 400],
     "run.sample_rate: got inf; expected a finite number"),
    ("analysis.hvd.components = 10**40", WET, ["analysis.hvd.components=" + "1" + "0" * 40],
     "analysis.hvd.components: 10000000000000000000000000000000000000000 is out of bounds; "
     "expected an integer >= 1 and <= 64 (and of magnitude below 2^63)"),
]


@pytest.mark.parametrize("case, text, overrides, fragment", CASES, ids=[c[0] for c in CASES])
def test_what_the_run_would_refuse_is_refused_by_the_check(tmp_path, case, text, overrides,
                                                           fragment):
    path = tmp_path / "profile.toml"
    path.write_text(text)
    before = path.read_bytes()
    sets = [arg for item in overrides for arg in ("--set", item)]
    out = tmp_path / "runs"
    for command in (["profile", "check"], ["run"]):
        extra = ["--out", str(out)] if command == ["run"] else []
        code, stdout, stderr = run_main(*command, str(path), *sets, *extra)
        assert code == 2, (command, stdout, stderr)
        assert stderr.count("fsi-lab: error:") == 1 and "Traceback" not in stderr, stderr
        assert stderr.startswith(f"fsi-lab: error: {path}: "), stderr
        assert fragment in stderr, stderr
    assert not out.exists()  # no run file, not even the folder
    assert path.read_bytes() == before


def test_the_example_profiles_pass_the_check():
    from support import PROFILES

    for path in sorted(PROFILES.glob("*.toml")):
        code, stdout, stderr = run_main("profile", "check", str(path))
        assert code == 0, (path, stderr)
        assert stdout.startswith(f"{path}: valid\nsafety: ") and stdout.endswith(": ok\n")


def test_a_profile_its_safety_limits_refuse_is_not_called_valid():
    from support import PROFILES

    path = PROFILES / "wet-beam-sim.toml"
    code, stdout, stderr = run_main("profile", "check", str(path), "--set",
                                    "bench.amplifier.gain=30")
    assert code == 2, stderr
    assert stdout.startswith(f"{path}: its keys and values are valid, but its safety limits "
                             "refuse the run it describes\nsafety: "), stdout
    assert ": REFUSED: amplifier gain 30 exceeds safety.max_gain" in stdout, stdout


@pytest.mark.parametrize("duration, rate", [("1", "1e12"), ("1e9", "2000"), ("1e-9", "1000")])
def test_simulate_refuses_a_record_it_cannot_hold(tmp_path, duration, rate):
    out = tmp_path / "sim.h5"
    code, _, err = run_main("simulate", str(GOOD_PROFILE), "--duration", duration, "--rate",
                            rate, "-o", str(out))
    assert code == 2 and err.count("fsi-lab: error:") == 1 and "Traceback" not in err, err
    assert f"--duration {float(duration):g} s at --rate {float(rate):g} Hz makes" in err
    assert "expected 2 to 2,147,483,648: change --duration or --rate" in err
    assert not out.exists()


def test_a_waveform_the_source_cannot_hold_is_refused_before_it_is_generated(monkeypatch):
    """15 s at 1 MSa/s (15 million samples, within what any source holds, 1.6 GB to make) for
    a generator that holds 1e6 points: refused from the excitation's duration, the waveform
    never built."""
    from fsi_lab.plugins.excitation import ramp_derivative

    def never(*args):
        raise AssertionError("the waveform was generated")

    monkeypatch.setattr(ramp_derivative, "ramp_derivative", never)
    code, _, err = run_main("profile", "check", str(GOOD_PROFILE), "--set",
                            "excitation.duration=15", "--set", "bench.source.sample_rate=1e6")
    assert code == 2, err
    assert ("bench.source: the excitation has 15,000,000 samples at 1e+06 Sa/s; the arb memory "
            "holds 8 to 1,000,000 points") in err
