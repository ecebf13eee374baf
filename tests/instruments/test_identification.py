"""Done when: the paper's workflow on the simulated benches recovers the true damping.

- wet: ``fsi-lab run profiles/wet-beam-sim.toml --json`` (ramp-derivative excitation, HVD, the
  component at the second wet mode near 17 Hz) identifies C_i and C_f within 15 % of the values
  the bench simulates (the profile's [model]);
- dry: ``fsi-lab run profiles/dry-beam-sim.toml --json`` recovers the configured modal damping
  ratios within 10 %;
- wet, impulse train: the wet profile with a descending impulse-train excitation (one record,
  several free decays) identifies C_i and C_f within 15 % too, from one free decay per impulse.

Both run through the ``fsi-lab`` command on the embedded simulated bench (the lab drivers over
loopback TCP and a pseudo-terminal), fast.
"""

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


def test_dry_profile_recovers_the_modal_damping_ratios(tmp_path):
    ratios = tomllib.loads(DRY.read_text())["model"]["damping_ratios"]
    summary = _run(DRY, tmp_path)
    components = sorted(summary["components"], key=lambda c: c["frequency_hz"])
    assert len(components) >= len(ratios)
    for component, ratio in zip(components, ratios):
        zeta = np.asarray(component["damping"]["zeta"], dtype=float)
        assert np.nanmedian(zeta) == pytest.approx(ratio, rel=0.10), component["frequency_hz"]
