"""Done when: the paper's workflow on the simulated benches recovers the true damping.

- wet: ``fsi-lab run profiles/wet-beam-sim.toml --json`` (ramp-derivative excitation, HVD, the
  component at the second wet mode near 17 Hz) identifies C_i and C_f within 15 % of the values
  the bench simulates (the profile's [model]);
- dry: ``fsi-lab run profiles/dry-beam-sim.toml --json`` recovers the configured modal damping
  ratios within 10 %;
- wet, impulse train: the wet profile with a descending impulse-train excitation (one record,
  several free decays) identifies C_i and C_f within 15 % too, from one free decay per impulse;
- wet, impulse train of the excitation's default (shorter) impulses: the 47 Hz mode's envelope
  crosses the 17 Hz one's in every decay; the default mode bands separate the two (C_i and C_f
  within 15 %), while Feldman's HVD (``analysis.hvd.method=hvd``) follows the larger and its
  components switch mode - reported as a per-component error, no C_i or C_f; with
  ``analysis.hvd.band_hz`` around 17 Hz, that mode is decomposed alone and C_i is identified
  within 15 %.

Both run through the ``fsi-lab`` command on the embedded simulated bench (the lab drivers over
loopback TCP and a pseudo-terminal), fast.
"""

import re
import tomllib

import numpy as np
import pytest
from support import PROFILES, cli_json

from fsi_lab.runfile import read_run

WET = PROFILES / "wet-beam-sim.toml"
DRY = PROFILES / "dry-beam-sim.toml"


def _run(profile, tmp_path, *overrides):
    """Run ``profile`` on the simulated bench with ``--set`` ``overrides`` ("key=value");
    returns the analysis summary of the tip velocity channel."""
    sets = [arg for item in ("bench.fast=true", *overrides) for arg in ("--set", item)]
    data, proc = cli_json("run", str(profile), "--out", str(tmp_path), *sets, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert data["exit_status"] == "completed", data["error"]
    identity = read_run(data["run"]).instruments["vibrometer"]["identity"]
    assert "PDV-100" in identity, f"{profile.name} does not run on the simulated bench: {identity}"
    return data["analysis"]["channels"]["tip_velocity"]


def test_wet_profile_identifies_c_i_and_c_f_on_the_simulated_bench(tmp_path):
    model = tomllib.loads(WET.read_text())["model"]
    summary = _run(WET, tmp_path)
    component = min(summary["components"], key=lambda c: abs(c["frequency_hz"] - 17.0))
    assert 16.0 < component["frequency_hz"] < 18.0
    found = component["equivalent_damping"]
    assert found["c_i"] == pytest.approx(model["c_i"], rel=0.15)
    assert found["c_f"] == pytest.approx(model["c_f"], rel=0.15)


#: A descending train of half-sine impulses on the wet profile (within its safety limits). Each
#: impulse lasts 1.5 / 47 s, which puts the first zero of its spectrum on the 47 Hz mode: the
#: 17 Hz mode then dominates every decay (HVD extracts the largest component at each instant;
#: with 20 ms impulses the 47 Hz response outgrows the 17 Hz one after each impulse and the
#: first component switches mode at every impulse).
IMPULSES = {"count": 4, "max_amplitude": 1.0, "min_amplitude": 0.3, "spacing": 2.0,
            "width": 0.032, "order": "descending", "delay": 0.1}


def test_wet_impulse_train_identifies_c_i_and_c_f_on_the_simulated_bench(tmp_path):
    model = tomllib.loads(WET.read_text())["model"]
    duration = IMPULSES["delay"] + IMPULSES["count"] * IMPULSES["spacing"]
    summary = _run(WET, tmp_path, "excitation.plugin=impulse-train", f"run.duration={duration}",
                   *(f"excitation.{key}={value}" for key, value in IMPULSES.items()))
    component = min(summary["components"], key=lambda c: abs(c["frequency_hz"] - 17.0))
    assert 16.0 < component["frequency_hz"] < 18.0
    found = component["equivalent_damping"]
    assert found["decays"] == IMPULSES["count"]
    assert found["c_i"] == pytest.approx(model["c_i"], rel=0.15)
    assert found["c_f"] == pytest.approx(model["c_f"], rel=0.15)


#: The impulse-train excitation with its default 20 ms impulses on the wet profile.
SHORT_IMPULSES = ("excitation.plugin=impulse-train", "run.duration=14")


def test_wet_short_impulses_give_both_modes_with_the_default_bands(tmp_path):
    """With one band per mode nothing can switch: the 17 Hz mode gives C_i and C_f, the
    47 Hz one its own."""
    model = tomllib.loads(WET.read_text())["model"]
    summary = _run(WET, tmp_path, *SHORT_IMPULSES)
    near = {round(c["frequency_hz"] / 10): c for c in summary["components"]}
    assert 16.0 < near[2]["frequency_hz"] < 18.0 and 46.0 < near[5]["frequency_hz"] < 49.0
    found = near[2]["equivalent_damping"]
    assert found["decays"] > 1
    assert found["c_i"] == pytest.approx(model["c_i"], rel=0.15)
    assert found["c_f"] == pytest.approx(model["c_f"], rel=0.15)


def test_wet_short_impulses_report_the_mode_switch_instead_of_numbers(tmp_path):
    summary = _run(WET, tmp_path, *SHORT_IMPULSES, "analysis.hvd.method=hvd")
    assert summary["components"]
    for component in summary["components"]:
        assert "equivalent_damping" not in component, component["equivalent_damping"]
        message = component["hvd"]["error"]
        modes = re.search(r"switches between the modes near ([\d.]+) Hz and ([\d.]+) Hz",
                          message).groups()
        low, high = sorted(float(f) for f in modes)
        assert 16.0 < low < 18.0 and 46.0 < high < 49.0, message
        assert "band_hz" in message
    failed = {e["plugin"] for e in summary["errors"]}
    assert "equivalent-damping" in failed


def test_wet_short_impulses_with_a_band_around_17_hz(tmp_path):
    """One component in [10, 25] Hz. C_i is within 15 % (measured: 0.653, +0.5 %; 0.629 to
    0.667 for low edges 8 to 13 Hz). C_f is resolved but not asserted: each decay's free part
    spans only about 2.5-fold in amplitude on this bench (the 17 Hz decays fall 20-fold in
    1.5 s, less the settling and guard times), and the fit follows which early points of each
    decay are kept - measured 32.1 (-2.8 %) with [10, 25] Hz, but 23 to 49 for low edges 8 to
    13 Hz, against 33.0."""
    model = tomllib.loads(WET.read_text())["model"]
    summary = _run(WET, tmp_path, *SHORT_IMPULSES, "analysis.hvd.band_hz=[10,25]",
                   "analysis.hvd.components=1", "analysis.hvd.method=hvd")
    (component,) = summary["components"]
    assert "hvd" not in component
    assert 16.0 < component["frequency_hz"] < 18.0
    found = component["equivalent_damping"]
    assert found["c_i"] == pytest.approx(model["c_i"], rel=0.15)
    assert found["c_f_ci95"][0] > 0.0


def test_dry_profile_recovers_the_modal_damping_ratios(tmp_path):
    """The damping curves' median within 10 %, and the viscous law, which the record prefers
    in air, gives the configured ratio within 1 % (measured: within 0.05 %) with an interval
    of its own."""
    ratios = tomllib.loads(DRY.read_text())["model"]["damping_ratios"]
    summary = _run(DRY, tmp_path)
    components = sorted(summary["components"], key=lambda c: c["frequency_hz"])
    assert len(components) >= len(ratios)
    for component, ratio in zip(components, ratios):
        zeta = np.asarray(component["damping"]["zeta"], dtype=float)
        assert np.nanmedian(zeta) == pytest.approx(ratio, rel=0.10), component["frequency_hz"]
        eq = component["equivalent_damping"]
        assert eq["preferred_law"] == "viscous"
        viscous = eq["laws"]["viscous"]
        assert viscous["damping_ratio"] == pytest.approx(ratio, rel=0.01)
        low, high = viscous["damping_ratio_ci95"]
        assert low < viscous["damping_ratio"] < high and high - low < 0.1 * ratio
        assert viscous["c_i"] == pytest.approx(
            2.0 * eq["mass_per_length"] * viscous["damping_ratio"]
            * 2.0 * np.pi * component["frequency_hz"], rel=1e-9)
