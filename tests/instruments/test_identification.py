"""Done when: the paper's workflow on the simulated benches recovers the true damping.

- wet: ``fsi-lab run profiles/wet-beam-sim.toml --json`` (ramp-derivative excitation, HVD, the
  component at the second wet mode near 17 Hz) identifies C_i and C_f within 15 % of the values
  the bench simulates (the profile's [model]);
- dry: ``fsi-lab run profiles/dry-beam-sim.toml --json`` recovers the configured modal damping
  ratios within 10 %.

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


def _run(profile, tmp_path):
    data, proc = cli_json("run", str(profile), "--out", str(tmp_path), "--set", "bench.fast=true",
                          timeout=300)
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


def test_dry_profile_recovers_the_modal_damping_ratios(tmp_path):
    ratios = tomllib.loads(DRY.read_text())["model"]["damping_ratios"]
    summary = _run(DRY, tmp_path)
    components = sorted(summary["components"], key=lambda c: c["frequency_hz"])
    assert len(components) >= len(ratios)
    for component, ratio in zip(components, ratios):
        zeta = np.asarray(component["damping"]["zeta"], dtype=float)
        assert np.nanmedian(zeta) == pytest.approx(ratio, rel=0.10), component["frequency_hz"]
