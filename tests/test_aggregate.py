"""Aggregation across runs (fsi_lab.aggregate, fsi-lab aggregate): modes grouped by frequency,
C_i and C_f fitted to the union of the runs' free decays with intervals that hold the truth,
widened when the runs disagree, the runs' curves on one amplitude axis, the spread between runs
next to the within-run intervals, the amplitude range covered.

The runs are free decays with known damping (support.write_decay_run): with mu + M = 0.05 kg/m
and no beam model (amplitudes as measured), C_i = 2 m a = 0.05 kg/(m s) and C_f = m beta =
0.1 kg/m^2."""

import json
import math
import re

import numpy as np
import pytest
from support import ode_path, run_main, write_decay_run

from fsi_lab.aggregate import aggregate_extracts, format_aggregate, group_modes
from fsi_lab.aggregate_extract import ExtractTask, extract_run

MASS = 0.05
C_I, C_F = 2 * MASS * 0.5, MASS * 2.0
STARTS = (0.1, 0.2, 0.3)  # m/s: three excitation levels


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("runs")
    out = {f"level{k}": write_decay_run(folder / f"level{k}.h5", start=start, seed=k)
           for k, start in enumerate(STARTS)}
    # the same mode with twice the fluid damping (another fluid), and another beam (30 Hz)
    out["thicker"] = write_decay_run(folder / "thicker.h5", beta=4.0, start=0.2, seed=7)
    out["stiffer"] = write_decay_run(folder / "stiffer.h5", frequency=30.0, start=0.2, seed=8)
    return out


@pytest.fixture(scope="module")
def extracts(files):
    return {name: extract_run(ExtractTask(str(path), (), MASS, name))
            for name, path in files.items()}


def covers(bounds, value):
    return bounds[0] <= value <= bounds[1]


def test_c_i_and_c_f_fitted_to_the_union_of_the_runs_hold_the_truth(extracts):
    runs = [extracts[f"level{k}"] for k in range(3)]
    agg = aggregate_extracts(runs)
    assert agg["exit_code"] == 0 and agg["runs_with_modes"] == 3
    (mode,) = agg["modes"]
    assert mode["runs"] == 3 and mode["decays"] == 3
    assert mode["extrema"] == sum(sum(d.amplitude.size for d in r.modes[0].decays) for r in runs)
    assert mode["c_i"] == pytest.approx(C_I, rel=0.01) and covers(mode["c_i_ci95"], C_I)
    assert mode["c_f"] == pytest.approx(C_F, rel=0.03) and covers(mode["c_f_ci95"], C_F)
    assert mode["preferred_law"] == "quadratic" and mode["delta_aicc"]["viscous"] > 10
    assert mode["frequency_hz"] == pytest.approx(20.0, rel=1e-4)
    # pooling: the union's interval is narrower than the median run's own
    width = mode["c_f_ci95"][1] - mode["c_f_ci95"][0]
    own = sorted(r["c_f_ci95"][1] - r["c_f_ci95"][0] for r in mode["per_run"])
    assert width < own[1]
    # the spread between runs next to the median within-run interval
    spread = mode["between_runs"]["c_f"]
    values = [r["c_f"] for r in mode["per_run"]]
    assert spread["sd"] == pytest.approx(np.std(values, ddof=1))
    assert spread["mean"] == pytest.approx(np.mean(values))
    assert spread["median_half_width"] == pytest.approx(own[1] / 2)
    assert spread["runs"] == 3
    # each run's own numbers are its analysis's (fsi-lab analyze gives the same)
    for entry, run in zip(mode["per_run"], runs):
        assert entry["label"] == run.label and entry["component"] == 0
        assert entry["c_f"] == pytest.approx(run.modes[0].coefficients()["c_f"])
    # the amplitude range covered: from the smallest run's smallest extremum to the largest's
    # largest (velocity / omega; the largest run starts at 0.3 m/s)
    low, high = mode["amplitude_range_m"]
    assert high == pytest.approx(0.3 / (2 * math.pi * 20), rel=0.05)
    assert low == min(r["amplitude_range_m"][0] for r in mode["per_run"])
    assert agg["amplitude_range_m"] == [low, high]


def test_a_pooled_mode_says_which_warnings_its_runs_carry(extracts):
    """Pooling narrows the interval by what differs between runs, not by a bias they share:
    the pooled mode said only "N of M runs carry warnings" and quoted the first; it names each
    distinct warning (its first clause, numbers as ranges) with how many runs carry it, and
    says plainly that a shared bias is not narrowed (JSON and text); clean runs give none."""
    import dataclasses

    runs = [extracts[f"level{k}"] for k in range(3)]
    (clean,) = aggregate_extracts(runs)["modes"]
    assert clean["warnings"] == [] and all(not r["warnings"] for r in clean["per_run"])
    halves = ("the larger and the smaller half of the cycles give C_i and C_f that differ by "
              "up to {} standard errors: the damping is not one law over this amplitude range "
              "(coupling with other modes, an amplitude-dependent drag); their intervals are "
              "widened {}-fold")
    poor = "C_f is poorly determined: its 95 % interval is +-{} % of the value"
    said = [[halves.format(2.1, 1.1), poor.format(12)], [halves.format(2.8, 1.4)],
            [poor.format(20)]]
    warned = [dataclasses.replace(run, modes=[dataclasses.replace(run.modes[0], warnings=w)])
              for run, w in zip(runs, said)]
    agg = aggregate_extracts(warned)
    (mode,) = agg["modes"]
    assert mode["warnings"] == [
        "3 of 3 runs carry warnings on this mode: the larger and the smaller half of the "
        "cycles give C_i and C_f that differ by up to 2.8 standard errors (2 runs); C_f is "
        "poorly determined (2 runs). Pooling narrows the runs' noise and scatter, not a bias "
        "they share: where these warnings name one (a damping law that misfits, decays whose "
        "start is not free, a smear corrected with a model), every run carries it, and the "
        "pooled interval, narrower than each run's own, may miss the true value that the "
        "runs' own intervals hold; read each run's warnings and interval beside the pooled "
        "numbers"]
    assert [r["warnings"] for r in mode["per_run"]] == said
    assert "\n  warning: 3 of 3 runs carry warnings on this mode: the larger" \
        in format_aggregate(agg)
    # numbers not after "up to" are given as their range
    spread = [dataclasses.replace(run, modes=[dataclasses.replace(
        run.modes[0], warnings=[f"only {c} cycles above the noise floor: too few"])])
        for run, c in zip(runs, (3.5, 4.5, 4.5))]
    (mode,) = aggregate_extracts(spread)["modes"]
    assert mode["warnings"][0].startswith(
        "3 of 3 runs carry warnings on this mode: only 3.5 to 4.5 cycles above the noise "
        "floor (3 runs). Pooling")


def _with_power(run, power, seed):
    """``run`` with its mode's extrema replaced by those of a drag growing as |v|^power (as
    large as a quadratic one with beta = 4 /m at 0.2 m/s, and a viscous a = 0.1 /s), released
    at the speed of its first extremum, as many extrema, with independent errors of 1 mm/s
    (the decays' times and signs, which the whitening uses, are kept), and its own quadratic
    law refitted to them."""
    import dataclasses

    from fsi_lab.dsp.laws import fit_law

    mode = run.modes[0]
    w0, a = mode.w0, 0.1
    k = 4.0 * 0.2 ** (2.0 - power)
    rng = np.random.default_rng(seed)
    decays = []
    for d in mode.decays:
        # 400 samples a cycle: a parabola through the three about each extremum gives its
        # value to 1e-8 of it, far below the 1 mm/s errors added
        t = np.arange(0.0, (d.amplitude.size + 2) * math.pi / w0, 2.0 * math.pi / w0 / 400.0)
        v = ode_path(lambda _, y: (y[1], -2 * a * y[1] - k * abs(y[1]) ** (power - 1) * y[1]
                                   - w0 * w0 * y[0]), (0.0, float(d.amplitude[0])), t)[:, 1]
        turn = np.flatnonzero(np.diff(np.sign(np.diff(v))) != 0) + 1   # after the release
        before, at, after = np.abs(v[turn - 1]), np.abs(v[turn]), np.abs(v[turn + 1])
        extrema = (at + (before - after) ** 2 / (8.0 * (2.0 * at - before - after)))[
            :d.amplitude.size]
        assert extrema.size == d.amplitude.size
        amplitude = np.abs(extrema + 1e-3 * rng.standard_normal(extrema.size))
        decays.append(dataclasses.replace(d, amplitude=amplitude,
                                          values=np.sign(d.values) * amplitude))
    own = fit_law("quadratic", [d.amplitude for d in decays], w0)
    return dataclasses.replace(run, modes=[dataclasses.replace(
        mode, decays=decays, params=own.params, cov=own.cov, widening=1.0)])


def test_the_union_tests_the_power_of_the_fluid_term(extracts):
    """Three runs whose drag grows as |v|^1.5: the union's many decays find that power and
    warn that C_f describes a drag that is not quadratic; the runs of the quadratic law find
    2 within the interval and say nothing."""
    runs = [extracts[f"level{k}"] for k in range(3)]
    (quadratic,) = aggregate_extracts(runs)["modes"]
    low, high = quadratic["fluid_power_ci95"]
    assert low < 2.0 < high and quadratic["warnings"] == []
    faster = aggregate_extracts([_with_power(run, 1.5, k) for k, run in enumerate(runs)])
    (other,) = faster["modes"]
    low, high = other["fluid_power_ci95"]
    assert low < 1.5 < high < 1.9, other["fluid_power_ci95"]
    assert other["warnings"][0].startswith(
        f"the fluid damping grows as the velocity to the power {other['fluid_power']:.2f}")
    text = format_aggregate(faster)
    assert (f"preferred law: {other['preferred_law']}, fluid term as "
            f"|v|^{other['fluid_power']:.2f} (95 %: {low:.2f} to {high:.2f})") in text


def test_the_runs_curves_on_one_amplitude_axis(extracts):
    agg = aggregate_extracts([extracts[f"level{k}"] for k in range(3)])
    (mode,) = agg["modes"]
    curves, axis = mode["curves"], mode["axis"]
    assert set(np.unique(curves["backbone"]["run"])) == {0, 1, 2}
    assert set(np.unique(curves["damping"]["run"])) == {0, 1, 2}
    # the backbone of a linear oscillator: the damped frequency, flat in amplitude
    assert np.nanmedian(curves["backbone"]["frequency_hz"]) == pytest.approx(20.0, rel=0.01)
    amplitudes = np.asarray(axis["amplitude_m"])
    assert len(amplitudes) == 16 and np.all(np.diff(amplitudes) > 0)
    assert mode["amplitude_range_m"][0] < amplitudes[0] < amplitudes[-1] \
        < mode["amplitude_range_m"][1]
    # where several runs give C_q points, their median follows the fitted line
    # C_q = C_i + 8 C_f omega W / (3 pi): a one-period decrement at the smallest amplitudes
    # is as uncertain as the damping is small (0.1 % noise, zeta ~ 0.005), so each bin's
    # median is within 25 %, their middle within 3 %
    ratios = [c_q / fit for c_q, fit, runs in zip(axis["c_q"], axis["c_q_fit"],
                                                   axis["c_q_runs"])
              if runs >= 2 and c_q is not None]
    assert len(ratios) >= 8
    assert all(0.75 < r < 1.25 for r in ratios), ratios
    assert np.median(ratios) == pytest.approx(1.0, abs=0.03)


def test_runs_that_disagree_widen_the_interval(extracts):
    agg = aggregate_extracts([extracts["level0"], extracts["level1"], extracts["level2"],
                              extracts["thicker"]])
    (mode,) = agg["modes"]
    assert mode["runs"] == 4
    # twice the fluid damping in one run: far beyond the runs' own intervals
    assert mode["widened"]["spread"]["c_f"] > 5
    assert mode["between_runs"]["c_f"]["sd_pct"] > 30
    # the interval says the runs do not give one C_f: it holds both runs' values
    assert covers(mode["c_f_ci95"], C_F) and covers(mode["c_f_ci95"], 2 * C_F)
    assert "by the spread between runs" in format_aggregate(agg)


def test_modes_are_grouped_across_runs_by_frequency(extracts):
    runs = [extracts["level0"], extracts["stiffer"], extracts["level1"]]
    groups = group_modes(runs)
    assert [[position for position, _ in group] for group in groups] == [[0, 2], [1]]
    agg = aggregate_extracts(runs)
    assert [m["runs"] for m in agg["modes"]] == [2, 1]
    assert [round(m["frequency_hz"]) for m in agg["modes"]] == [20, 30]
    assert covers(agg["modes"][1]["c_f_ci95"], C_F)
    assert "spread" not in agg["modes"][1]["widened"] or \
        agg["modes"][1]["widened"]["spread"] == {"c_i": 1.0, "c_f": 1.0}


def test_fsi_lab_aggregate_files_and_directories(files, tmp_path):
    paths = [str(files[f"level{k}"]) for k in range(3)]
    bad = tmp_path / "bad.h5"
    bad.write_text("not a run")
    code, out, err = run_main("aggregate", *paths, str(bad), "--mass-per-length", str(MASS),
                              "--json")
    assert code == 2, err  # the bad file is refused; the others are aggregated
    data = json.loads(out)
    assert data["executor"] == {"kind": "in-process", "workers": 1}
    assert [r["label"] for r in data["runs"]] == ["level0.h5", "level1.h5", "level2.h5",
                                                  "bad.h5"]
    assert data["runs"][3]["errors"][0].startswith(f"{bad}: not a readable HDF5 file")
    assert f"[error] bad.h5: {bad}: not a readable HDF5 file" in err
    (mode,) = data["modes"]
    assert mode["runs"] == 3 and covers(mode["c_f_ci95"], C_F)
    assert len(mode["curves"]["damping"]["c_q"]) == len(mode["curves"]["damping"]["run"])
    # a directory of run files: each of them; the text form
    folder = files["level0"].parent
    code, text, _ = run_main("aggregate", str(folder), "--mass-per-length", str(MASS))
    assert code == 0
    # (no beam model: the amplitudes are those measured)
    assert text.startswith("aggregate of 5 runs: 5 with modes; displacement amplitude at the "
                           "measuring point ")
    assert "mode at 20 Hz, channel tip: 4 runs, 4 decays" in text
    assert re.search(r"4 decays, \d+ extrema, displacement amplitude at the measuring point "
                     r"[0-9.e-]+ to [0-9.e-]+ mm\n", text), text
    assert "mode at 30 Hz, channel tip: 1 run, 1 decays" in text
    # each run's own frequency: the mode is at 20 Hz
    thicker = re.search(r"\n    thicker\.h5: ([0-9.]+) Hz", text)
    assert thicker and float(thicker.group(1)) == pytest.approx(20.0, rel=1e-4), text


def test_copies_of_one_run_are_refused_not_pooled_as_independent_runs(files, tmp_path):
    """Two copies of one run file (the same uuid) were pooled as two runs: "2 runs", a
    spread between them of exactly 0 and a narrower interval, with no word."""
    import shutil

    copy = tmp_path / "copy.h5"
    shutil.copy(files["level0"], copy)
    code, out, err = run_main("aggregate", str(files["level0"]), str(files["level1"]),
                              str(copy), "--mass-per-length", str(MASS))
    assert code == 2 and out == ""
    assert f"{copy}: a copy of {files['level0']} (both hold run " in err
    assert "each run counts once in an aggregate: give one of them" in err
    # one file under two names is one run, aggregated once
    again = f"{files['level0'].parent}/./{files['level0'].name}"
    code, out, err = run_main("aggregate", str(files["level0"]), again, "--mass-per-length",
                              str(MASS), "--json")
    assert code == 0, err
    assert json.loads(out)["modes"][0]["runs"] == 1
    folder = tmp_path / "folder"
    folder.mkdir()
    shutil.copy(files["level0"], folder / "a.h5")
    shutil.copy(files["level0"], folder / "b.h5")
    code, _, err = run_main("aggregate", str(folder), "--mass-per-length", str(MASS))
    assert code == 2 and f"{folder / 'b.h5'}: a copy of {folder / 'a.h5'}" in err


def test_a_run_s_own_numbers_in_the_aggregate_are_those_of_its_analysis(tmp_path):
    """`fsi-lab aggregate RUN.h5` identified the whole record where `fsi-lab run` and
    `fsi-lab analyze` read it to its quiet tail: on the wet bench's record the third mode's
    C_f came out 30.2 in the aggregate against 35.7 in the file's own analysis."""
    from support import PROFILES, cli_json

    data, proc = cli_json("run", str(PROFILES / "wet-beam-sim.toml"), "--out", str(tmp_path),
                          "--set", "run.duration=8", timeout=300)
    assert proc.returncode == 0, proc.stderr
    channel = data["analysis"]["channels"]["tip_velocity"]
    assert any("are a quiet tail" in note for note in channel["notes"])
    own = {round(c["frequency_hz"], 2): c["equivalent_damping"] for c in channel["components"]}
    code, out, err = run_main("aggregate", data["run"], "--json")
    assert code == 0, err
    pooled = {round(m["frequency_hz"], 2): m["per_run"][0] for m in json.loads(out)["modes"]}
    assert sorted(pooled) == sorted(own)
    for frequency, run in pooled.items():
        for key in ("c_i", "c_f"):
            assert run[key] == pytest.approx(own[frequency][key], rel=1e-9), (frequency, key)


def test_a_run_analysed_with_overrides_the_aggregate_lacks_is_noted(tmp_path):
    """`fsi-lab analyze RUN --mass-per-length M` stores numbers the aggregate, given another
    mass, does not reproduce: a note names the run and what its stored analysis used; given
    the same, no note."""
    run = write_decay_run(tmp_path / "analysed.h5", seed=3)
    code, _, err = run_main("analyze", str(run), "--mass-per-length", "0.2")
    assert code == 0, err
    code, out, err = run_main("aggregate", str(run), "--mass-per-length", str(MASS), "--json")
    assert code == 0, err
    notes = json.loads(out)["notes"]
    assert notes == [f"{run.name}: its stored analysis (what fsi-lab show prints) was computed "
                     "with --mass-per-length=0.2 beyond the run's own settings, and this "
                     "aggregate identifies the modes without it: give the same to aggregate "
                     "(--set KEY=VALUE, --mass-per-length) to pool that analysis"], notes
    code, out, err = run_main("aggregate", str(run), "--mass-per-length", "0.2", "--json")
    assert code == 0, err
    assert json.loads(out)["notes"] == []


def test_runs_without_a_mass_per_length_are_refused_naming_them(files):
    code, out, err = run_main("aggregate", str(files["level0"]), "--json")
    assert code == 2
    (run,) = json.loads(out)["runs"]
    assert run["errors"] == [f"{files['level0']}: C_i and C_f need mu + M, the mass per length "
                             "of beam plus added fluid mass: the run has no [specimen]; pass "
                             "--mass-per-length KG_PER_M"]
    code, _, err = run_main("aggregate", str(files["level0"]), "--mass-per-length", "-1")
    assert code == 2 and "--mass-per-length -1.0: expected kg/m > 0" in err


def test_a_runs_decays_as_identify_exposes_them_give_back_its_own_fit(extracts):
    """The union fit rests on this: each decay's extrema, their relative errors (scale) and the
    band's noise correlation, refitted with fsi_lab.dsp.laws.fit_law, are the run's own fit."""
    from fsi_lab.aggregate_fit import _whiteners
    from fsi_lab.dsp.laws import fit_law

    for name in ("level0", "stiffer"):
        mode = extracts[name].modes[0]
        assert all(d.scale is not None and d.scale.shape == d.amplitude.shape
                   for d in mode.decays)
        run = mode.run_decays()
        refit = fit_law("quadratic", [d.amplitude for d in mode.decays], run.w0,
                        alpha=run.alpha, whiteners=_whiteners(run, 1.0))
        np.testing.assert_allclose(refit.params, mode.params, rtol=1e-5)
        assert mode.widening >= 1.0


def test_a_union_of_many_runs_is_never_more_precise_than_the_method(extracts, monkeypatch):
    """Pooling narrows the noise's part of the interval as one over the square root of the
    runs, not the method's own systematic error, which every run shares: the identification's
    accuracy on records of known truth (fsi_lab.accuracy: C_i 0.3 %, C_f 2 % of the value, as
    95 % half-widths) is added in quadrature. Thirty runs (the three levels ten times over):
    each half-width is the quadrature sum of the one without the floor (about 0.1 % on C_i and
    0.5 % on C_f) and the floor, to 1e-6; the factors are reported, the text says why."""
    import dataclasses

    import fsi_lab.aggregate_fit as aggregate_fit
    from fsi_lab.accuracy import ACCURACY

    # thirty records (each its own fingerprint: the same samples would be pooled once)
    runs = [dataclasses.replace(extracts[f"level{k}"], fingerprint=f"{i}-{k}")
            for i in range(10) for k in range(3)]
    agg = aggregate_extracts(runs)
    monkeypatch.setattr(aggregate_fit, "LAW_ACCURACY", {"a": 0.0, "beta": 0.0})
    (plain,) = aggregate_extracts(runs)["modes"]
    (mode,) = agg["modes"]
    for key in ("c_i", "c_f"):
        assert mode[key] == plain[key]
        half = (mode[f"{key}_ci95"][1] - mode[f"{key}_ci95"][0]) / 2
        noise = (plain[f"{key}_ci95"][1] - plain[f"{key}_ci95"][0]) / 2
        assert noise < ACCURACY[key] * mode[key]
        assert half == pytest.approx(math.hypot(noise, ACCURACY[key] * mode[key]), rel=1e-6)
        assert mode["widened"]["accuracy"][key] == pytest.approx(half / noise, rel=1e-6)
        assert plain["widened"]["accuracy"][key] == 1.0
        assert covers(mode[f"{key}_ci95"], C_I if key == "c_i" else C_F)
    text = format_aggregate(agg)
    assert "for the method's accuracy (+-0.3 % on C_i, +-2 % on C_f)" in text
    assert "method's accuracy" not in format_aggregate(
        {**agg, "modes": [plain]})


def test_runs_whose_modes_were_fitted_jointly_are_averaged_not_refitted(extracts):
    """A run whose mode was fitted together with a close mode to its samples carries C_i and
    C_f its smeared extrema do not give: the union then averages the runs' own (a, beta) with
    their inverse covariances (its value, to 1e-9, and covariance before widening), and says
    so in ``pooled``; runs fitted from their extrema keep the union fit."""
    import dataclasses

    from fsi_lab.aggregate_fit import fit_union

    runs = [extracts[f"level{k}"].modes[0].run_decays() for k in range(3)]
    assert fit_union(runs).pooled == "union"
    shifted = [dataclasses.replace(r, joint=(k == 1), params=r.params * (1.0 + 0.02 * k),
                                   cov=r.cov * (1.0 + k)) for k, r in enumerate(runs)]
    pooled = fit_union(shifted)
    assert pooled.pooled == "weighted mean"
    precision = sum(np.linalg.inv(r.cov) for r in shifted)
    mean = np.linalg.solve(precision, sum(np.linalg.inv(r.cov) @ r.params for r in shifted))
    np.testing.assert_allclose(pooled.fit.params, mean, rtol=1e-9)
    np.testing.assert_allclose(pooled.fit.cov, np.linalg.inv(precision), rtol=1e-9)
    assert pooled.noise_factor == 1.0
    assert abs(pooled.value("beta") / fit_union(runs).value("beta") - 1.0) > 0.005
    # The laws are ranked by the runs' own AICc gaps, summed: two runs that each found the
    # viscous law 1.5 below the quadratic one make it preferred by 3 (a tie, 2, per run).
    ranked = [dataclasses.replace(r, delta_aicc={"quadratic": 1.5 * (k > 0), "viscous": 0.0,
                                                 "coulomb": 9.0})
              for k, r in enumerate(shifted)]
    comparison = fit_union(ranked).comparison
    assert comparison.preferred == "viscous"
    assert comparison.delta == pytest.approx({"quadratic": 3.0, "viscous": 0.0})


def test_fsi_lab_aggregate_of_runs_with_close_modes_averages_their_joint_fits(tmp_path):
    """Two runs of a 20 Hz mode beside a 26 Hz one: each run's identification fits the two
    together to its samples, and the aggregate averages those fits (``pooled_by``), C_i and
    C_f within 3 and 6 % and inside their intervals."""
    others = ((0.8, 0.0, 26.0, 0.15),)
    paths = [write_decay_run(tmp_path / f"close{k}.h5", start=0.2 + 0.1 * k, seed=20 + k,
                             others=others) for k in range(2)]
    runs = [extract_run(ExtractTask(str(p), (), MASS, p.stem)) for p in paths]
    assert all(any(m.joint for m in r.modes) for r in runs)
    agg = aggregate_extracts(runs)
    (mode,) = [m for m in agg["modes"] if abs(m["frequency_hz"] - 20.0) < 1.0]
    assert mode["pooled_by"] == "weighted mean"
    own = [m.delta_aicc["viscous"] for r in runs for m in r.modes
           if abs(m.frequency_hz - 20.0) < 1.0]
    assert mode["preferred_law"] == "quadratic"
    assert mode["delta_aicc"]["viscous"] == pytest.approx(sum(own), rel=1e-9)
    assert mode["c_i"] == pytest.approx(C_I, rel=0.03) and covers(mode["c_i_ci95"], C_I)
    assert mode["c_f"] == pytest.approx(C_F, rel=0.06) and covers(mode["c_f_ci95"], C_F)
    assert "averaged with their inverse covariances" in format_aggregate(agg)


def test_records_equal_sample_for_sample_are_pooled_once_naming_the_files(files, tmp_path):
    """Run files with different uuids but the same samples (two runs of the simulated bench
    with one bench.seed) were pooled as independent runs: "between runs sd 0" and an interval
    narrowed by a record counted three times."""
    import h5py

    same = [write_decay_run(tmp_path / f"same{k}.h5", start=0.2, seed=5) for k in range(3)]
    with h5py.File(same[0], "r") as a, h5py.File(same[1], "r") as b:
        assert a.attrs["uuid"] != b.attrs["uuid"]
    code, out, err = run_main("aggregate", *map(str, same), str(files["level0"]),
                              "--mass-per-length", str(MASS), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["runs_with_modes"] == 4 and data["distinct_records"] == 2
    assert [r["same_record_as"] for r in data["runs"]] == [None, "same0.h5", "same0.h5", None]
    assert data["notes"] == [
        "same1.h5, same2.h5: the same record as same0.h5, sample for sample (their analysed "
        "channels hold identical samples: a copy, or runs of the simulated bench with one "
        "bench.seed); pooled once, as same0.h5: 3 copies of one record are one measurement, "
        "not 3 independent runs"]
    (mode,) = data["modes"]
    assert mode["runs"] == 2
    assert [r["label"] for r in mode["per_run"]] == ["same0.h5", "level0.h5"]
    assert mode["between_runs"]["c_f"]["sd"] > 0
    # pooled once: the union of the two distinct records, as if the copies were not given
    code, out, _ = run_main("aggregate", str(same[0]), str(files["level0"]),
                            "--mass-per-length", str(MASS), "--json")
    (alone,) = json.loads(out)["modes"]
    assert mode["c_f_ci95"] == pytest.approx(alone["c_f_ci95"])
    code, text, _ = run_main("aggregate", *map(str, same), "--mass-per-length", str(MASS))
    assert code == 0
    assert text.startswith("aggregate of 3 runs: 3 with modes (1 distinct record); displacement "
                           "amplitude at the measuring point")
    assert "\n  note: same1.h5, same2.h5: the same record as same0.h5, sample for sample" in text
    assert "between runs" not in text  # one record: no spread between runs to give


def test_an_analysis_value_every_run_refuses_is_refused_once(files):
    """A bad value of an analysis parameter failed each run with the same error, one per
    run, blamed on the run file's profile; refused once, before any run is identified."""
    paths = [str(files[f"level{k}"]) for k in range(3)]
    code, out, err = run_main("aggregate", *paths, "--mass-per-length", str(MASS), "--set",
                              "analysis.hvd.components=nonsense")
    assert code == 2 and out == ""
    assert err.count("fsi-lab: error: ") == 1 and "identifying the modes" not in err
    assert ("--set analysis.hvd.components=nonsense: analysis.hvd.components: cannot read "
            "'nonsense'; expected an integer >= 1") in err
    # a batch analysis likewise
    code, out, err = run_main("analyze", *paths, "--mass-per-length", str(MASS), "--set",
                              "analysis.hvd.components=nonsense")
    assert code == 2 and err.count("fsi-lab: error: ") == 1 and "== " not in out


@pytest.mark.parametrize("item", ["specimen.fluid=air", "run.duration=3"])
def test_aggregate_sets_analysis_parameters_only_and_says_so_once(files, item, tmp_path):
    """`aggregate --set specimen.fluid=air` on water runs was accepted and gave an 18 times
    larger C_i that no run file explains; `--set run.duration=3` was refused once per run,
    after the runs were read. Both are refused once, before any run is read, saying what is
    accepted."""
    import hashlib

    paths = [str(files[f"level{k}"]) for k in range(3)]
    before = [hashlib.md5(open(p, "rb").read()).hexdigest() for p in paths]
    code, out, err = run_main("aggregate", *paths, "--mass-per-length", str(MASS), "--set",
                              item, "--json")
    assert code == 2
    assert json.loads(out) == {"error": json.loads(out)["error"], "exit_code": 2}
    assert err.count("fsi-lab: error: ") == 1 and err.count(f"--set {item!r}") == 1
    assert "identifying the modes" not in err and "level0.h5" not in err
    assert ("fsi-lab aggregate sets analysis parameters only: analysis.ANALYSIS.PARAMETER=VALUE "
            "(fsi-lab plugins -v lists them), analysis.chain, analysis.channels or "
            "analysis.reference") in err
    if item.startswith("specimen"):
        assert "the specimen (the beam, its fluid, the measuring point) is each run's own, " \
               "held by its run file" in err
        assert "--mass-per-length" in err
    else:
        assert "'run.duration' is not an analysis parameter" in err
    assert [hashlib.md5(open(p, "rb").read()).hexdigest() for p in paths] == before
    # an analysis parameter is accepted, and --help says what is
    code, out, err = run_main("aggregate", *paths, "--mass-per-length", str(MASS), "--set",
                              "analysis.hvd.components=1", "--json")
    assert code == 0, err
    code, text, _ = run_main("aggregate", "--help")
    assert "not the specimen, which each run file holds" in " ".join(text.split())


def test_fsi_lab_aggregate_takes_directories_and_run_files_together(files, tmp_path):
    """--help says RUN.h5|DIR [RUN.h5|DIR ...], but a directory was taken only alone: `fsi-lab
    aggregate DIR FILE.h5` refused the directory ("is a directory, not a regular file")."""
    folder = files["level0"].parent
    extra = write_decay_run(tmp_path / "extra.h5", start=0.25, seed=11)
    code, out, err = run_main("aggregate", str(folder), str(extra), str(files["level1"]),
                              "--mass-per-length", str(MASS), "--json")
    assert code == 0, err
    data = json.loads(out)
    # the folder's five runs and the extra one; level1.h5, also in the folder, counts once
    assert sorted(r["label"] for r in data["runs"]) == sorted(
        ["level0.h5", "level1.h5", "level2.h5", "thicker.h5", "stiffer.h5", "extra.h5"])
    assert [m["runs"] for m in data["modes"]] == [5, 1]
    code, _, err = run_main("aggregate", str(folder), str(tmp_path / "empty"),
                            "--mass-per-length", str(MASS))
    assert code == 2 and f"{tmp_path / 'empty'}: " in err


def test_the_numbers_of_pooled_warnings_keep_their_signs_and_exponents():
    """A pooled mode's warnings give each number's range across runs: a negative number keeps
    its sign, and one in exponent notation is one number, not a mantissa and an exponent."""
    from fsi_lab.aggregate import _warning_kinds

    runs = [{"warnings": ["the start moves C_f by -1.2 % at a noise of 2e-05 m/s"]},
            {"warnings": ["the start moves C_f by -7.35 % at a noise of 5.1e-06 m/s"]}]
    assert _warning_kinds(runs) == [
        ("the start moves C_f by -7.35 to -1.2 % at a noise of 5.1e-06 to 2e-05 m/s", 2)]
