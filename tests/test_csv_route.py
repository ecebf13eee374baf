"""The CSV route gives the run's results: a run's channels exported to CSV and imported with
the reference channel and the vibrometer's delay (which a CSV cannot carry) are analysed as the
run file was; without them the analysis differs."""

import json

import numpy as np
import pytest
from support import GOOD_PROFILE, run_main

from fsi_lab.chain import default_chain
from fsi_lab.registry import load_registry
from fsi_lab.runfile import read_run


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """A wet-beam run analysed with the chain imported data gets, and its channels as a CSV
    (one time column: the digitiser's sample clock)."""
    folder = tmp_path_factory.mktemp("route")
    code, out, err = run_main("run", str(GOOD_PROFILE), "--out", str(folder), "--json",
                              "--set", "run.duration=2",
                              "--set", "analysis.chain=" + ",".join(default_chain(load_registry())),
                              "--set", "analysis.hvd.components=auto")
    assert code == 0, err
    data = json.loads(out)
    run = read_run(data["run"])
    names = list(run.channels)
    rate = run.channels["drive"].sample_rate
    lines = ["time [s]," + ",".join(f"{n} [{run.channels[n].unit}]" for n in names)]
    for i in range(run.channel_samples["drive"]):
        lines.append(",".join([repr(i / rate)]
                              + [repr(float(run.channels[n].data[i])) for n in names]))
    csv_path = folder / "exported.csv"
    csv_path.write_text("\n".join(lines) + "\n")
    return data["analysis"], run, csv_path


def _components(summary):
    return [(c["frequency_hz"], c["equivalent_damping"]["c_i"], c["equivalent_damping"]["c_f"])
            for c in summary["channels"]["tip_velocity"]["components"]]


def _import_and_analyse(csv_path, out, *options):
    code, _, err = run_main("import", str(csv_path), "-o", str(out), *options)
    assert code == 0, err
    code, text, err = run_main("analyze", str(out), "--json", "--set", "specimen.fluid=water")
    assert code == 0, err
    return json.loads(text)


def test_exported_data_imported_with_reference_and_delay_gives_the_runs_results(exported,
                                                                                  tmp_path):
    summary, run, csv_path = exported
    delay = -run.channels["tip_velocity"].t0
    assert delay > 0  # the simulated vibrometer's signal delay, recorded by the run
    imported = _import_and_analyse(csv_path, tmp_path / "imported.h5",
                                   "--reference", "base_acceleration",
                                   "--delay", f"tip_velocity={delay!r}")
    expected, found = _components(summary), _components(imported)
    assert len(found) == len(expected) >= 2
    np.testing.assert_allclose(found, expected, rtol=1e-6)
    stored = read_run(tmp_path / "imported.h5", load_data=False)
    assert stored.reference == "base_acceleration"
    assert stored.channels["tip_velocity"].t0 == pytest.approx(-delay)
    assert stored.channel_attrs["tip_velocity"]["sensor_delay_s"] == pytest.approx(delay)
    code, out, _ = run_main("show", str(tmp_path / "imported.h5"))
    assert f"t0 = {-delay:g} s" in out and "reference:        base_acceleration" in out


def test_without_reference_and_delay_the_analysis_differs(exported, tmp_path):
    summary, _, csv_path = exported
    plain = _import_and_analyse(csv_path, tmp_path / "plain.h5")
    assert plain["channels"]["tip_velocity"] != summary["channels"]["tip_velocity"]


@pytest.mark.parametrize("options, fragment", [
    (["--reference", "tip"], "--reference tip: a velocity column; expected the base "
                             "acceleration column (columns: tip, base)"),
    (["--reference", "nope"], "--reference nope: not a data column of"),
    (["--delay", "nope=0.001"], "--delay nope=0.001: 'nope' is not a data column of"),
    (["--delay", "tip=-0.001"], "--delay tip=-0.001: expected a sensor delay from 0 to 1 s"),
    (["--delay", "tip=soon"], "--delay tip=soon: expected NAME=SECONDS"),
    (["--delay", "tip"], "--delay tip: expected NAME=SECONDS"),
])
def test_bad_reference_or_delay_is_refused(tmp_path, options, fragment):
    csv_path = tmp_path / "rec.csv"
    csv_path.write_text("tip [m/s],base [g]\n0.1,0.2\n0.3,0.4\n")
    out = tmp_path / "rec.h5"
    code, _, err = run_main("import", str(csv_path), "--rate", "100", "-o", str(out), *options)
    assert code == 2 and err.count("fsi-lab: error:") == 1 and fragment in err, err
    assert not out.exists()


def test_specimen_keys_an_import_does_not_give_are_named_in_the_output(tmp_path):
    """Imported data has no profile: ``--set specimen.fluid=water`` alone describes the beam,
    and the other keys silently came from the paper's beam (a beam 0.2 m long analysed as
    0.08 m long converts to another mode shape: C_f 10.3 against 32.7). The output now names
    the keys taken from the paper's beam, with their values; none when every key is given, or
    with --mass-per-length (no specimen)."""
    from fsi_lab.specimen import SPECIMEN_PARAMS

    fs = 2000.0
    t = np.arange(int(3 * fs)) / fs
    v = 0.05 * np.exp(-1.5 * t) * np.cos(2 * np.pi * 17.0 * t) \
        + 1e-4 * np.random.default_rng(0).standard_normal(t.size)
    csv_path = tmp_path / "decay.csv"
    csv_path.write_text("tip [m/s]\n" + "\n".join(repr(float(x)) for x in v) + "\n")
    out = tmp_path / "decay.h5"
    code, _, err = run_main("import", str(csv_path), "--rate", "2000", "-o", str(out))
    assert code == 0, err

    def notes(*options):
        code, text, err = run_main("analyze", str(out), "--json", *options)
        assert code == 0, err
        return [n for n in json.loads(text)["channels"]["tip"].get("notes", [])
                if "the paper's beam" in n]

    (note,) = notes("--set", "specimen.fluid=water", "--set", "specimen.length=0.08")
    assert "length" not in note.split(":")[1] and "fluid" not in note.split(":")[1]
    assert "width 0.01275 m" in note and "drag_coefficient 1.8" in note
    every = [f"specimen.{p.name}={p.default}" for p in SPECIMEN_PARAMS]
    assert notes(*[x for key in every for x in ("--set", key)]) == []
    assert notes("--mass-per-length", "0.1346") == []
