"""The `fsi-lab` command: analyze, show, run --json and file errors."""

import json

import h5py
import numpy as np
import pytest
from support import cli, cli_here, cli_json, cli_json_here

from fsi_lab.runfile import read_run


@pytest.fixture
def imported_run(tmp_path):
    t = np.arange(2000) / 1000.0
    rows = zip(0.02 * np.sin(2 * np.pi * 9 * t), np.ones_like(t) * 0.3)
    csv_path = tmp_path / "rec.csv"
    csv_path.write_text("tip [m/s],flat [m/s]\n" + "\n".join(f"{a},{b}" for a, b in rows))
    out = tmp_path / "rec.h5"
    assert cli_here("import", str(csv_path), "--rate", "1000", "-o", str(out)).returncode == 0
    return out


def test_analyze_runs_the_chain_and_isolates_failures(imported_run, example_plugin_dir):
    env = {"PYTHONPATH": str(example_plugin_dir)}
    data, proc = cli_json("analyze", str(imported_run), "--set", "analysis.chain=rms,crossings",
                          "--set", "analysis.rms.scale=2", env=env)
    assert proc.returncode == 0, proc.stderr
    tip, flat = data["channels"]["tip"], data["channels"]["flat"]
    assert tip["rms"] == pytest.approx(2 * 0.02 / np.sqrt(2), rel=1e-3)
    assert tip["components"] == [{"index": 0, "crossings": 36}]
    # the constant channel fails in `crossings` only; its rms is still there
    assert flat["rms"] == pytest.approx(0.0, abs=1e-12)
    # the core names the plugin and the channel before the plugin's own words
    assert flat["errors"] == [{"plugin": "crossings", "message":
                               "crossings on channel 'flat': crossings: channel flat: 0 zero "
                               "crossings, need at least 1"}]
    assert "analysis crossings on channel flat" in proc.stderr

    with h5py.File(imported_run, "r") as handle:
        group = handle["analysis/tip/rms"]
        assert group.attrs["status"] == "ok"
        assert group.attrs["rms"] == pytest.approx(tip["rms"])
        assert group["params"].attrs["scale"] == 2.0
        assert group["squared"].attrs["units"] == "(unit)^2"
        failed = handle["analysis/flat/crossings"]
        assert failed.attrs["status"] == "failed" and "0 zero crossings" in failed.attrs["error"]
        assert json.loads(handle["analysis"].attrs["summary"]) == data
    # raw data untouched
    assert read_run(imported_run).channels["tip"].data.size == 2000

    # a new analysis replaces the old results only
    data2, proc = cli_json("analyze", str(imported_run), "--set", "analysis.chain=rms", env=env)
    assert proc.returncode == 0
    with h5py.File(imported_run, "r") as handle:
        assert "crossings" not in handle["analysis/tip"]
        assert handle["channels/tip"].shape == (2000,)


def test_analyze_refuses_settings_outside_analysis(imported_run):
    proc = cli_here("analyze", str(imported_run), "--set", "run.duration=3")
    assert proc.returncode == 2
    assert "only analysis, specimen parameters can be set here" in proc.stderr


def test_show_describes_a_run(imported_run):
    data, proc = cli_json_here("show", str(imported_run))
    assert proc.returncode == 0
    assert data["channels"]["tip"]["samples"] == 2000
    assert data["channels"]["tip"]["quantity"] == "velocity"
    assert data["attrs"]["kind"] == "imported"
    text = cli_here("show", str(imported_run)).stdout
    assert "channel tip: velocity [m/s], 2000 samples at 1000 Hz (2.000 s)" in text


@pytest.mark.parametrize("content, fragment", [
    (b"not hdf5 at all", "not a readable HDF5 file"),
    (None, "not an fsi-lab run file"),
])
def test_foreign_or_corrupt_files_are_refused(tmp_path, content, fragment):
    path = tmp_path / "other.h5"
    if content is None:
        with h5py.File(path, "w") as handle:
            handle["x"] = np.arange(3)
    else:
        path.write_bytes(content)
    for command in ("show", "analyze"):
        proc = cli(command, str(path))
        assert proc.returncode == 2, proc.stderr
        assert str(path) in proc.stderr and fragment in proc.stderr


def test_run_json_is_one_object_with_path_status_and_safety(sim_profile, tmp_path,
                                                             example_plugin_dir):
    profile = sim_profile(analysis='[analysis]\nchain = ["rms"]\nchannels = ["tip_velocity"]\n')
    data, proc = cli_json("run", str(profile), "--out", str(tmp_path / "runs"),
                          env={"PYTHONPATH": str(example_plugin_dir)})
    assert proc.returncode == 0, proc.stderr
    assert data["exit_status"] == "completed"
    assert data["final_state"]["amplifier"]["output_enabled"] is False
    assert data["safety"]["ok"] is True
    assert data["analysis"]["run"] == data["run"]
    assert data["analysis"]["channels"]["tip_velocity"]["rms"] > 0
    assert read_run(data["run"]).attrs["exit_status"] == "completed"
    assert "[state] completed" not in proc.stdout  # logs stay on stderr


def test_summary_text_flags_coefficients_whose_interval_contains_zero():
    from fsi_lab.cli import format_summary

    def summary(c_f_ci95):
        return {"channels": {"tip_velocity": {"components": [{
            "index": 0, "frequency_hz": 17.0,
            "equivalent_damping": {"c_i": 0.65, "c_f": 3.0, "r2": 0.1,
                                   "c_i_ci95": [0.6, 0.7], "c_f_ci95": c_f_ci95}}]}}}

    unresolved = format_summary(summary([-30.0, 36.0]))
    assert "C_f is not resolved (its interval contains 0)" in unresolved
    assert "C_i is not resolved" not in unresolved
    assert "not resolved" not in format_summary(summary([1.0, 5.0]))


def test_summary_text_gives_the_fluid_term_s_power_beside_the_law():
    """The power of the velocity the fluid term grows with, and its interval, follow the
    preferred law on the component's line; a mode without the test has no such words."""
    from fsi_lab.cli import format_summary

    def summary(**power):
        return {"channels": {"tip_velocity": {"components": [{
            "index": 0, "frequency_hz": 17.0,
            "equivalent_damping": {"c_i": 0.65, "c_f": 33.0, "r2": 1.0,
                                   "c_i_ci95": [0.6, 0.7], "c_f_ci95": [32.0, 34.0],
                                   "preferred_law": "quadratic", **power}}]}}}

    text = format_summary(summary(fluid_power=1.9637, fluid_power_ci95=[1.4366, 2.4908]))
    assert "preferred law: quadratic, fluid term as |v|^1.96 (95 %: 1.44 to 2.49)" in text
    assert "fluid term" not in format_summary(summary())


def test_summary_text_says_a_c_f_without_a_beam_model_is_per_the_amplitude_measured():
    """Without a beam model (--mass-per-length) C_f belongs to the displacement at the sensor,
    half the modal C_f at a cantilever's tip: the line under the component says how to get the
    modal one; with the modal conversion, no such line."""
    from fsi_lab.cli import format_summary

    def summary(convention):
        return {"channels": {"tip_velocity": {"components": [{
            "index": 0, "frequency_hz": 17.0,
            "equivalent_damping": {"c_i": 0.65, "c_f": 16.3, "r2": 1.0,
                                   "c_i_ci95": [0.6, 0.7], "c_f_ci95": [16.0, 16.6],
                                   "amplitude_convention": convention}}]}}}

    measured = format_summary(summary("measured (displacement amplitude at the measuring "
                                      "point)"))
    assert ("C_f is per the amplitude measured at the sensor (no beam model); the modal C_f "
            "is W_n(x_meas) times it") in measured
    assert "modal_scale=W" in measured
    assert "amplitude measured" not in format_summary(summary("modal: q_2 = w(x_meas) / "
                                                              "W_2(x_meas), W_2(x_meas) = 2"))


def test_summary_text_gives_the_preferred_viscous_law_s_damping_ratio_in_percent():
    from fsi_lab.cli import format_summary

    viscous = {"delta_aicc": 0.0, "a": 0.145, "c_i": 0.002175, "c_i_ci95": [0.002173, 0.002177],
               "damping_ratio": 0.0020004, "damping_ratio_ci95": [0.0019981, 0.0020027]}
    text = format_summary({"channels": {"tip_velocity": {"components": [{
        "index": 0, "frequency_hz": 11.53,
        "equivalent_damping": {"c_i": 0.002176, "c_f": -3.8e-5, "r2": 1.0,
                               "c_i_ci95": [0.002163, 0.002189], "c_f_ci95": [-7e-4, 6e-4],
                               "preferred_law": "viscous",
                               "laws": {"viscous": viscous}}}]}}})
    line = next(x for x in text.splitlines() if "viscous law (preferred)" in x)
    assert line.strip() == ("viscous law (preferred): C_i = 0.002175 kg/(m s) (95 %: 0.002173 "
                            "to 0.002177), damping ratio 0.2 % (95 %: 0.1998 to 0.2003 %)")


def test_summary_text_says_whose_coefficients_the_modal_model_ran_with():
    """The model is one beam with one C_i and C_f (here component 0's fit): the line under
    component 1 must not pass them off as component 1's."""
    from fsi_lab.cli import format_summary

    def model(error):
        return {"c_i": 0.6543, "c_f": 30.55, "envelope_rms_error": error,
                "frequency_error_pct": 0.5}

    text = format_summary({"channels": {"tip_velocity": {
        "modal_model": {"c_i": 0.6543, "c_f": 30.55,
                        "c_source": "equivalent-damping component 0 (mode 2)"},
        "components": [
            {"index": 0, "frequency_hz": 17.0, "modal_model": model(0.07),
             "equivalent_damping": {"c_i": 0.6543, "c_f": 30.55, "r2": 0.8}},
            {"index": 1, "frequency_hz": 47.1, "modal_model": model(0.04),
             "equivalent_damping": {"c_i": 0.6895, "c_f": -3.73, "r2": 0.0}}]}}})
    lines = [line for line in text.splitlines() if "modal model" in line]
    assert len(lines) == 2
    for line in lines:
        assert ("modal model (C_i = 0.6543 kg/(m s), C_f = 30.55 kg/m^2 from equivalent-damping "
                "component 0 "
                "(mode 2)) vs measurement") in line
    assert "0.6895" not in lines[1]


def test_strict_and_the_text_summary_see_the_frf_warnings(tmp_path):
    """The FRF keeps its warnings at channel level (``frf``'s ``warnings``), not under a
    component: ``--strict`` fails on them and the text summary prints them. A lightly damped
    resonance (20 Hz, zeta 0.002: a half-power band of 0.08 Hz) seen at a 1.95 Hz resolution
    (256-sample segments at 500 Hz), where its damping ratio is not resolved."""
    import scipy.signal as ssig

    fs, n, w = 500.0, 2 ** 14, 2 * np.pi * 20.0
    sdof = ssig.StateSpace([[0.0, 1.0], [-w * w, -2 * 0.002 * w]], [[0.0], [-1.0]],
                           [[0.0, 1.0]], [[0.0]]).to_discrete(1 / fs, method="zoh")
    base = np.random.default_rng(4).standard_normal(n)
    tip = ssig.dlsim(sdof, base)[1][:, 0]
    csv_path = tmp_path / "rec.csv"
    csv_path.write_text("base [m/s^2],tip [m/s]\n"
                        + "\n".join(f"{a!r},{b!r}" for a, b in zip(base.tolist(), tip.tolist())))
    run = tmp_path / "rec.h5"
    proc = cli_here("import", str(csv_path), "--rate", "500", "--reference", "base", "-o", str(run))
    assert proc.returncode == 0, proc.stderr
    chain = ("--set", "analysis.chain=frf", "--set", "analysis.frf.segment=256")
    data, proc = cli_json_here("analyze", str(run), *chain)
    assert proc.returncode == 0, proc.stderr
    warnings = data["channels"]["tip"]["frf"]["warnings"]
    assert warnings and not data["channels"]["tip"].get("components")
    proc = cli_here("analyze", str(run), *chain, "--strict")
    assert proc.returncode == 3, proc.stderr
    strict = [line for line in proc.stderr.splitlines() if line.startswith("[strict]")]
    assert strict == [f"[strict] channel tip frf: {w}" for w in warnings]
    assert [line for line in proc.stdout.splitlines() if "warning:" in line] == [
        f"  frf warning: {w}" for w in warnings]
    # the analysis stored in the run file fails `show --strict` the same way
    proc = cli_here("show", str(run), "--strict")
    assert proc.returncode == 3
    assert [line for line in proc.stderr.splitlines() if line.startswith("[strict]")] == strict


def test_show_strict_passes_a_clean_analysis_and_fails_none(imported_run, example_plugin_dir):
    proc = cli_here("show", str(imported_run), "--strict")
    assert proc.returncode == 3
    assert proc.stderr.splitlines() == [
        f"[strict] no analysis stored: fsi-lab analyze {imported_run}"]
    env = {"PYTHONPATH": str(example_plugin_dir)}
    assert cli("analyze", str(imported_run), "--set", "analysis.chain=rms",
               env=env).returncode == 0
    data, proc = cli_json("show", str(imported_run), "--strict", env=env)
    assert proc.returncode == 0, proc.stderr
    assert data["analysis"]["channels"]["tip"]["rms"] > 0
    proc = cli_here("show", str(imported_run.parent), "--strict")
    assert proc.returncode == 2
    assert f"--strict: {imported_run.parent} is a sequence's record; expected a run file" \
        in proc.stderr


def test_show_gives_the_excitation_s_parameters_with_their_units(sim_profile, tmp_path):
    """A run file records its excitation's parameter values only: ``show --json`` listed
    them without units. It adds the installed plugin's units (``param_units``), and the text
    prints the excitation with them."""
    data, proc = cli_json("run", str(sim_profile()), "--out", str(tmp_path), "--no-analysis")
    assert proc.returncode == 0, proc.stderr
    shown, proc = cli_json_here("show", data["run"])
    assert proc.returncode == 0, proc.stderr
    excitation = shown["excitation"]
    assert excitation["params"]["amplitude"] == 0.5
    assert excitation["param_units"]["amplitude"] == "V"
    (line,) = [ln for ln in cli_here("show", data["run"]).stdout.splitlines()
               if ln.startswith("excitation:")]
    assert f"{excitation['plugin']} (" in line and "amplitude 0.5 V" in line


def test_analyze_keeps_the_runs_own_overrides(sim_profile, tmp_path):
    analysis = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
    data, proc = cli_json("run", str(sim_profile(analysis=analysis)), "--out", str(tmp_path),
                          "--set", "analysis.spectrum.max_peaks=2", "--set", "run.duration=0.5")
    assert proc.returncode == 0, proc.stderr

    def stored_max_peaks():
        with h5py.File(data["run"], "r") as handle:
            return int(handle["analysis/tip_velocity/spectrum/params"].attrs["max_peaks"])

    assert stored_max_peaks() == 2
    assert len(data["analysis"]["channels"]["tip_velocity"]["spectrum_peaks_hz"]) <= 2
    again, proc = cli_json_here("analyze", data["run"])
    assert proc.returncode == 0, proc.stderr
    assert stored_max_peaks() == 2
    assert again["channels"]["tip_velocity"]["spectrum_peaks_hz"] == \
        data["analysis"]["channels"]["tip_velocity"]["spectrum_peaks_hz"]
    # a new --set still wins over the recorded one
    _, proc = cli_json_here("analyze", data["run"], "--set", "analysis.spectrum.max_peaks=5")
    assert proc.returncode == 0, proc.stderr
    assert stored_max_peaks() == 5


def test_usage_and_file_system_errors_still_give_one_json_object(tmp_path):
    data, proc = cli_json_here("simulate", "profiles/wet-beam-sim.toml", "-o",
                               str(tmp_path / "x.h5"))
    assert proc.returncode == 2
    assert data == {"error": "fsi-lab simulate: the following arguments are required: "
                             "--duration, --rate (see fsi-lab simulate --help)", "exit_code": 2}
    assert proc.stderr == ("fsi-lab: error: fsi-lab simulate: the following arguments are "
                           "required: --duration, --rate (see fsi-lab simulate --help)\n")
    csv = tmp_path / "rec.csv"
    csv.write_text("time [s],tip [m/s]\n0,1\n0.001,2\n0.002,1\n")
    under_a_file = csv / "rec.h5"  # its folder is a file
    data, proc = cli_json_here("import", str(csv), "-o", str(under_a_file))
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert data["exit_code"] == 1 and str(csv) in data["error"]


def test_analyze_with_a_shorter_chain_leaves_recorded_plugin_settings_aside(sim_profile,
                                                                           tmp_path):
    analysis = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
    data, proc = cli_json("run", str(sim_profile(analysis=analysis)), "--out", str(tmp_path),
                          "--set", "analysis.spectrum.max_peaks=2")
    assert proc.returncode == 0, proc.stderr
    # the recorded spectrum setting must not block a chain without spectrum
    again, proc = cli_json_here("analyze", data["run"], "--set", "analysis.chain=hvd")
    assert proc.returncode == 0, proc.stderr
    assert "spectrum_peaks_hz" not in again["channels"]["tip_velocity"]
    assert again["channels"]["tip_velocity"]["components"]


def test_a_run_file_without_the_channel_to_analyse_exits_2_and_says_so(sim_profile, tmp_path):
    """The analysed channel deleted from a run file: `analyze` said "failed None: ..." and
    exited 0, with --json too."""
    analysis = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
    data, proc = cli_json("run", str(sim_profile(analysis=analysis)), "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    with h5py.File(data["run"], "r+") as f:
        del f["channels/tip_velocity"]
    proc = cli_here("analyze", data["run"])
    assert proc.returncode == 2
    assert "  not analysed: channel 'tip_velocity' is not in the run; channels are " \
           in proc.stdout
    assert "None" not in proc.stdout
    assert f"{data['run']}: nothing was identified: channel tip_velocity: channel " \
           "'tip_velocity' is not in the run" in proc.stderr
    again, proc = cli_json_here("analyze", data["run"])
    assert proc.returncode == 2
    assert again["channels"]["tip_velocity"]["errors"][0]["plugin"] is None


def test_a_run_whose_record_identifies_nothing_exits_2_as_analyze_does(tmp_path):
    """In air the wet profile's record has no free decay of the beam: its one peak is the
    shaker's resonance driving it (hvd is refused saying so, not that 2 components found one
    peak) and nothing is identified. `run` printed that and exited 0 where `analyze` of the
    same file exits 2; now both exit 2, `run` adding that its file is complete."""
    proc = cli("run", "profiles/wet-beam-sim.toml", "--out", str(tmp_path),
               "--set", "specimen.fluid=air", timeout=300)
    assert proc.returncode == 2, proc.stderr
    (path,) = tmp_path.glob("*.h5")
    assert proc.stderr.rstrip().endswith("(the run file is complete)")
    assert f"fsi-lab: error: {path}: nothing was identified: channel tip_velocity: hvd " \
           in proc.stderr
    assert read_run(path).attrs["exit_status"] == "completed"
    again = cli_here("analyze", str(path))
    assert again.returncode == 2
    # The refusal is said once; the analyses that needed hvd's result are named after it
    # (they repeated it, one line each and one log line each on stderr).
    lines = again.stdout.splitlines()
    refusal = "no spectral peak has a free decay of its own; the spectral peak at "
    assert sum(1 for line in lines if refusal in line) == 1
    assert "(a shaker's own resonance) and drives the record" in again.stdout
    assert "2 component(s) asked for" not in again.stdout
    assert "  no result, for want of hvd's (hvd failed, above): integrate, instantaneous, " \
           "backbone, damping, equivalent-damping, modal-model" in lines
    logged = [line for line in again.stderr.splitlines() if line.startswith("[error] analysis ")]
    assert len(logged) == 7
    assert sum(1 for line in logged if refusal in line) == 1


def test_a_noise_free_simulation_is_not_said_to_hold_coloured_noise(tmp_path):
    """`fsi-lab simulate` writes the bench's physics without noise: the bands' tails hold the
    record's numerical residue, which the chain compared with a white noise of 1e-17 and
    warned "the noise in this mode's band is 754943998.9 times the record's white noise".
    That residue is no noise: no such warning, and the paper's C_i and C_f."""
    path = tmp_path / "sim.h5"
    made = cli_here("simulate", "profiles/wet-beam-sim.toml", "--duration", "10", "--rate",
                    "10000", "-o", str(path))
    assert made.returncode == 0, made.stderr
    data, proc = cli_json_here("analyze", str(path))
    assert proc.returncode == 0, proc.stderr
    comps = data["channels"]["tip_velocity"]["components"]
    assert comps and not any("times the record's white noise" in w
                             for c in comps for w in c["warnings"])
    mode2 = min(comps, key=lambda c: abs(c["frequency_hz"] - 17.06))
    assert mode2["equivalent_damping"]["c_i"] == pytest.approx(0.65, rel=0.01)
    assert mode2["equivalent_damping"]["c_f"] == pytest.approx(33.0, rel=0.02)


def test_only_failures_for_want_of_a_failed_result_alone_are_named_once():
    """An analysis named after the failure it could not do without gives no other reason; one
    that gives another reason too, or waits on an analysis that failed for want of a third,
    keeps its whole message."""
    from fsi_lab.registry import load_registry
    from fsi_lab.summary import format_summary

    errors = [
        ("hvd", "identify: 2 component(s) asked for"),
        ("integrate", "hvd failed earlier in the chain on this channel, so its 'components' "
                      "result is missing (hvd: identify: 2 component(s) asked for)"),
        ("modal-model", "needs the 'reference' result earlier in the chain on this channel, "
                        "which did not run; the 'components' result, which hvd failed to give "
                        "on this channel (identify: 2 component(s) asked for)"),
        ("after-integrate", "needs the 'curves' result, which integrate failed to give on this "
                            "channel (hvd failed earlier ...)"),
        ("damping", "needs the 'components' result, which hvd failed to give on this channel "
                    "(identify: 2 component(s) asked for)"),
    ]
    summary = {"channels": {"tip": {"errors": [
        {"plugin": name, "message": f"{name} on channel 'tip': {text}"}
        for name, text in errors]}}}
    lines = format_summary(summary, load_registry()).splitlines()
    assert [line.split(":")[0] for line in lines[1:]] == [
        "  failed hvd", "  failed modal-model", "  failed after-integrate",
        "  no result, for want of hvd's (hvd failed, above)"]
    assert lines[-1].endswith(": integrate, damping")


def test_mass_per_length_is_refused_for_a_run_that_has_a_specimen(sim_profile, tmp_path,
                                                                    imported_run):
    from support import run_main

    analysis = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
    code, out, err = run_main("run", str(sim_profile(analysis=analysis, duration=0.5)),
                              "--out", str(tmp_path / "runs"))
    assert code == 0, err
    path = next((tmp_path / "runs").glob("*.h5"))
    before = path.read_bytes()
    for extra in ([], ["--jobs", "1"]):
        code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.2", *extra)
        assert code == 2, err
        assert f"{path}: --mass-per-length 0.2: this run has a specimen (its profile's " \
            "[specimen]), which gives mu + M; --mass-per-length is for data without one" in err
        assert path.read_bytes() == before  # nothing analysed, nothing written
    # nor does an aggregate of it take another beam's mu + M
    code, out, err = run_main("aggregate", str(path), "--mass-per-length", "0.2")
    assert code == 2 and f"{path}: --mass-per-length 0.2: this run has a specimen" in out + err
    # imported data given a beam by --set specimen.* too: one or the other
    code, out, err = run_main("analyze", str(imported_run), "--mass-per-length", "0.2",
                              "--set", "specimen.fluid=water")
    assert code == 2 and "this run has a specimen (the specimen.* overrides given for it)" \
        in err, err
    # and without a specimen it is what gives mu + M
    code, out, err = run_main("analyze", str(imported_run), "--mass-per-length", "0.2")
    assert code in (0, 2) and "--mass-per-length" not in err, err


def test_the_stored_analysis_records_the_overrides_it_was_computed_with(tmp_path):
    from support import run_main, write_decay_run

    path = write_decay_run(tmp_path / "decay.h5")
    code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.1", "--set",
                              "analysis.hvd.components=1")
    assert code == 0, err
    with h5py.File(path, "r") as handle:
        assert json.loads(handle["analysis"].attrs["overrides"]) == [
            "analysis.hvd.components=1", "--mass-per-length=0.1"]
    code, out, err = run_main("show", str(path))
    assert code == 0 and "analysed with:    analysis.hvd.components=1 --mass-per-length=0.1 " \
        "(beyond the run's own settings)" in out, out
    code, out, err = run_main("show", str(path), "--json")
    assert json.loads(out)["analysis_overrides"] == ["analysis.hvd.components=1",
                                                     "--mass-per-length=0.1"]
    # analysed again with the run's own settings: the --set is gone, the mass (of the beam,
    # not a choice of the analysis) is kept
    code, out, err = run_main("analyze", str(path))
    with h5py.File(path, "r") as handle:
        assert json.loads(handle["analysis"].attrs["overrides"]) == ["--mass-per-length=0.1"]
    code, out, err = run_main("show", str(path))
    assert code == 0 and "analysed with:    --mass-per-length=0.1 (beyond" in out, out


@pytest.mark.parametrize("out, problem", [
    ("ok.csv", "ok.csv: is not a directory; expected the directory of the run file (--out)"),
    ("ok.csv/runs", "ok.csv/runs: is not a directory ({tmp}/ok.csv is a file); expected the "
                    "directory of the run file (--out)"),
])
def test_run_refuses_an_out_that_is_not_a_directory_before_anything_is_driven(
        sim_profile, tmp_path, out, problem):
    from support import run_main

    existing = tmp_path / "ok.csv"
    existing.write_text("a,b\n1,2\n")
    code, text, err = run_main("run", str(sim_profile(duration=0.5)), "--out",
                               str(tmp_path / out))
    assert code == 2, err
    assert err.strip() == f"fsi-lab: error: {tmp_path}/{problem.format(tmp=tmp_path)}", err
    assert "safety check passed" not in err and "configuring" not in err
    assert text == "" and existing.read_text() == "a,b\n1,2\n"
