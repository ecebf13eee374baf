"""The analysis plugins: hook discovery, contract, and the chain run by the core's runner."""

from __future__ import annotations

import importlib
import json
import math

import numpy as np
import pluggy
import pytest
from _analysis_sims import linear_decay, noisy, quadratic_record

from fsi_lab import hookspecs
from fsi_lab.chain import run_chain
from fsi_lab.contract import AnalysisContext, ChannelData, check_descriptor
from fsi_lab.errors import AnalysisError
from fsi_lab.params import validate
from fsi_lab.registry import Registry
from fsi_lab.specimen import Specimen

MODULES = {
    "hvd": "hvd", "instantaneous": "instantaneous", "integrate": "integrate",
    "backbone": "backbone", "damping": "damping", "equivalent-damping": "equivalent_damping",
    "spectrum": "spectrum", "frf": "frf",
}

#: The built-ins' default chain (fsi_lab.chain.default_chain orders it so, or equivalently).
DEFAULT_CHAIN = ("spectrum", "hvd", "integrate", "instantaneous", "backbone", "damping",
                 "equivalent-damping")



def load_registry() -> Registry:
    """What the core does with the entry points, for our modules only."""
    manager = pluggy.PluginManager(hookspecs.PROJECT)
    manager.add_hookspecs(hookspecs)
    registry = Registry()
    for name, module_name in MODULES.items():
        module = importlib.import_module(f"fsi_lab.plugins.analysis.{module_name}")
        manager.register(module, name=name)
        impls = [i for i in manager.hook.fsi_lab_analyses.get_hookimpls() if i.plugin is module]
        assert len(impls) == 1
        (descriptor,) = impls[0].function()
        registry.descriptors["analysis"][descriptor.name] = descriptor
    return registry


def test_each_module_provides_exactly_its_plugin():
    registry = load_registry()
    assert sorted(registry.descriptors["analysis"]) == sorted(MODULES)
    for name, descriptor in registry.descriptors["analysis"].items():
        check_descriptor("analysis", descriptor)
        assert descriptor.name == name
        assert descriptor.help
        assert all(p.help for p in descriptor.params)
        validate(descriptor.params, {}, f"analysis.{name}")      # defaults are valid


def two_mode_velocity(noise=0.0, seed=0):
    """Velocity of the linear + quadratic damping decay plus a weaker second mode (32 Hz)."""
    q = quadratic_record()
    _, v2 = linear_decay(q["t"], 2e-4, 32.0, 0.004, 0.7)
    v = q["v"] + v2
    if noise:
        v = noisy(v, noise, seed)
    return q, ChannelData(name="tip", data=v, sample_rate=q["fs"], quantity="velocity",
                          unit="m/s")


def run(channels, chain, registry=None, params=None, **kwargs):
    registry = registry or load_registry()
    params = {name: validate(registry.get("analysis", name).params, (params or {}).get(name, {}),
                             f"analysis.{name}") for name in chain}
    return run_chain(channels, {"chain": list(chain), **kwargs.pop("analysis", {})}, params,
                     registry, **kwargs)


def test_default_chain_on_a_two_mode_velocity_record():
    q, ch = two_mode_velocity(noise=0.005, seed=3)
    groups, summary = run({"tip": ch}, DEFAULT_CHAIN, mass_per_length=q["m"])
    s = summary["tip"]
    assert "errors" not in s, s.get("errors")
    json.dumps(s, allow_nan=False)
    assert s["spectrum_peaks_hz"][:2] == pytest.approx([5.0, 32.0], rel=0.02)
    comps = {c["index"]: c for c in s["components"]}
    c0 = comps[0]
    assert c0["frequency_hz"] == pytest.approx(5.0, rel=0.01)
    # Backbone in metres of displacement: from about 1 cm down.
    amp = np.array(c0["backbone"]["amplitude"])
    assert 5e-3 < amp.max() < 1.01e-2 and amp.min() < 1e-3
    assert len(c0["backbone"]["frequency_hz"]) == amp.size
    assert len(c0["damping"]["zeta"]) == len(c0["damping"]["amplitude"])
    eq = c0["equivalent_damping"]
    assert eq["c_i"] == pytest.approx(q["c1"], rel=0.10)
    assert eq["c_f"] == pytest.approx(q["c2"], rel=0.10)
    assert eq["c_i_ci95"][0] <= q["c1"] <= eq["c_i_ci95"][1]
    assert eq["c_f_ci95"][0] <= q["c2"] <= eq["c_f_ci95"][1]
    assert eq["amplitude_convention"].startswith("measured")
    assert eq["preferred_law"] == "quadratic"
    # The fluid term's power is quadratic's, within its interval (which is not a point).
    low, high = eq["fluid_power_ci95"]
    assert low < eq["fluid_power"] < high and low <= 2.0 <= high and high - low > 0.01
    # Read straight, the crests carry no third harmonic beyond the model's (within 3 of its
    # standard errors, and under the warning's 0.3 %).
    assert abs(eq["crest_harmonic"]) < max(3.0 * eq["crest_harmonic_se"], 0.003)
    assert 0.0 < eq["crest_harmonic_se"] < 0.003
    assert comps[1]["frequency_hz"] == pytest.approx(32.0, rel=0.01)
    # The weak 32 Hz mode is linear: quadratic damping is not resolved there, and says so.
    assert comps[1]["equivalent_damping"]["preferred_law"] == "viscous"
    assert "fluid_power" not in comps[1]["equivalent_damping"]      # (no fluid term to test)
    assert any("linear + quadratic" in w for w in comps[1]["warnings"])
    # One component per mode (automatic), over the whole record, components x samples.
    hvd_group = groups["tip/hvd"]
    assert hvd_group["attrs"]["method"] == "bands" and hvd_group["attrs"]["start_s"] == 0.0
    assert hvd_group["datasets"]["components"].shape == (2, ch.data.size)
    assert hvd_group["units"]["frequencies"] == "Hz"
    assert groups["tip/integrate"]["units"]["signals"] == "m"


def test_envelope_method_and_the_paper_options():
    q, ch = two_mode_velocity()
    chain = ("hvd", "integrate", "damping", "equivalent-damping")
    _, summary = run({"tip": ch}, chain, mass_per_length=q["m"],
                     params={"equivalent-damping": {"method": "envelope"},
                             "damping": {"method": "eq5", "smooth_points": 5}})
    c0 = summary["tip"]["components"][0]
    assert c0["damping"]["method"] == "eq5"
    assert c0["equivalent_damping"]["c_i"] == pytest.approx(q["c1"], rel=0.02)
    assert c0["equivalent_damping"]["c_f"] == pytest.approx(q["c2"], rel=0.02)


def test_without_hvd_the_channel_is_one_component():
    q, ch = two_mode_velocity()
    ch = ChannelData("tip", q["v"], q["fs"], "velocity", "m/s")
    _, summary = run({"tip": ch}, ("integrate", "backbone", "damping", "equivalent-damping"),
                     mass_per_length=q["m"],
                     params={"equivalent-damping": {"method": "regression"}})
    comps = summary["tip"]["components"]
    assert [c["index"] for c in comps] == [0]
    assert comps[0]["equivalent_damping"]["c_f"] == pytest.approx(q["c2"], rel=0.02)


def test_equivalent_damping_needs_mu_plus_m():
    q, ch = two_mode_velocity()
    groups, summary = run({"tip": ch}, ("hvd", "equivalent-damping"))
    (error,) = summary["tip"]["errors"]
    assert error["plugin"] == "equivalent-damping"
    assert "--mass-per-length KG_PER_M" in error["message"]
    assert "[specimen]" in error["message"] and "'tip'" in error["message"]
    assert groups["tip/hvd"]["attrs"]["status"] == "ok"        # the chain went on


def test_specimen_gives_mass_and_modal_amplitudes():
    q, ch = two_mode_velocity()
    specimen = Specimen.from_mapping({})
    chain = ("hvd", "integrate", "damping", "equivalent-damping")
    _, with_beam = run({"tip": ch}, chain, specimen=specimen)
    eq = with_beam["tip"]["components"][0]["equivalent_damping"]
    mu_m = 7200.0 * 12.75e-3 * 0.08e-3 + 997.0 * math.pi * (12.75e-3 / 2) ** 2
    assert eq["mass_per_length"] == pytest.approx(mu_m, rel=1e-12)
    assert eq["amplitude_convention"].startswith("modal")
    # Measured at the tip (x = L) where |W_n| = 2: modal amplitudes are half the measured
    # ones, so C_f doubles and C_i is unchanged (both scale with mu + M here).
    _, measured = run({"tip": ch}, chain, mass_per_length=mu_m)
    eq_m = measured["tip"]["components"][0]["equivalent_damping"]
    assert eq["c_i"] == pytest.approx(eq_m["c_i"], rel=1e-9)
    assert eq["c_f"] == pytest.approx(2.0 * eq_m["c_f"], rel=1e-6)


def test_bad_channel_gives_a_clear_error_per_plugin_and_the_chain_goes_on():
    q, ch = two_mode_velocity()
    bad = ChannelData("bad", np.where(np.arange(ch.data.size) == 100, np.nan, ch.data),
                      ch.sample_rate, "velocity", "m/s")
    _, summary = run({"tip": ch, "bad": bad}, ("spectrum", "hvd", "backbone"),
                     analysis={"channels": ["bad", "tip"]}, mass_per_length=1.0)
    errors = summary["bad"]["errors"]
    assert {e["plugin"] for e in errors} == {"spectrum", "hvd", "backbone"}
    for e in errors:
        assert f"{e['plugin']} on channel 'bad'" in e["message"]
    assert any("NaN" in e["message"] for e in errors)
    assert "errors" not in summary["tip"]


def test_more_components_than_modes_is_refused_with_the_modes_found():
    q, ch = two_mode_velocity()
    _, summary = run({"tip": ch}, ("hvd",), params={"hvd": {"components": 3}})
    (error,) = summary["tip"]["errors"]
    assert "3 component(s) asked for" in error["message"] and "2 usable" in error["message"]
    assert "components = 'auto'" in error["message"]


def test_a_failing_component_is_recorded_and_the_others_go_on():
    q, ch = two_mode_velocity()
    # The third HVD component of a two-mode record is numerical residue.
    groups, summary = run({"tip": ch}, ("hvd", "integrate", "damping"),
                          params={"hvd": {"components": 3, "method": "hvd"},
                                  "damping": {"method": "eq7"}})
    comps = {c["index"]: c for c in summary["tip"]["components"]}
    assert "zeta" in comps[0]["damping"]
    assert groups["tip/damping"]["attrs"]["status"] == "ok"


def test_voltage_channel_cannot_be_integrated():
    ch = ChannelData("drive", np.sin(np.arange(4000) * 0.05), 1000.0, "voltage", "V")
    _, summary = run({"drive": ch}, ("integrate", "spectrum"),
                     analysis={"channels": ["drive"]})
    (error,) = summary["drive"]["errors"]
    assert error["plugin"] == "integrate" and "'voltage'" in error["message"]
    assert summary["drive"]["spectrum_peaks_hz"] == pytest.approx([1000 * 0.05 / (2 * math.pi)],
                                                                   rel=0.01)
    # the peaks' amplitudes say their unit (the channel's): a peak of a 1 V sine
    assert summary["drive"]["spectrum_peak_amplitude_unit"] == "V"
    assert summary["drive"]["spectrum_peak_amplitudes"] == pytest.approx([1.0], rel=0.05)


def test_frf_plugin_with_and_without_reference():
    import scipy.signal as ssig
    fs = 500.0
    n = 2 ** 17
    w = 2 * math.pi * 18.67
    sys = ssig.StateSpace([[0.0, 1.0], [-w * w, -2 * 0.02 * w]], [[0.0], [-1.0]],
                          [[0.0, 1.0]], [[0.0]]).to_discrete(1 / fs, method="zoh")
    a_b = np.random.default_rng(2).standard_normal(n)
    v = ssig.dlsim(sys, a_b)[1][:, 0]
    channels = {"base": ChannelData("base", a_b, fs, "acceleration", "m/s^2"),
                "tip": ChannelData("tip", v, fs, "velocity", "m/s")}
    groups, summary = run(channels, ("frf",),
                          analysis={"channels": ["tip"], "reference": "base"})
    frf_summary = summary["tip"]["frf"]
    assert frf_summary["natural_frequencies_hz"][0] == pytest.approx(18.67, rel=0.01)
    assert frf_summary["damping_ratios"][0] == pytest.approx(0.02, rel=0.15)
    lo, hi = frf_summary["damping_ratio_ci95"][0]
    assert lo < frf_summary["damping_ratios"][0] < hi
    assert frf_summary["half_power_damping_ratios"][0] == pytest.approx(0.02, rel=0.15)
    assert frf_summary["resolution_hz"] == pytest.approx(fs / 2 ** 14)
    assert isinstance(frf_summary["warnings"], list)
    assert groups["tip/frf"]["datasets"]["damping_ratio_ci95"].shape == (
        len(frf_summary["damping_ratios"]), 2)
    assert groups["tip/frf"]["units"]["h1_magnitude"] == "m/s/(m/s^2)"
    _, summary = run(channels, ("frf",), analysis={"channels": ["tip"]})
    assert "reference" in summary["tip"]["errors"][0]["message"]


def test_plugin_run_directly_raises_analysis_error_with_plugin_and_channel():
    from fsi_lab.plugins.analysis.hvd import PLUGIN
    ch = ChannelData("tip", np.zeros(5000), 1000.0, "velocity", "m/s")
    ctx = AnalysisContext(channel=ch, channels={"tip": ch}, results={})
    with pytest.raises(AnalysisError,
                       match=r"^hvd on channel 'tip': identify: signal is constant"):
        PLUGIN.run(ctx, validate(PLUGIN.params, {}, "analysis.hvd"))
    with pytest.raises(AnalysisError, match=r"^hvd on channel 'tip': \w+: signal is constant"):
        PLUGIN.run(ctx, validate(PLUGIN.params, {"method": "hvd"}, "analysis.hvd"))


def test_simulated_wet_bench_gives_back_the_model_damping(tmp_path):
    """End to end: the project's wet-beam simulation (beam model of Eq. 20 with C_i = 0.65,
    C_f = 33 driven through the shaker) written as a run file by ``fsi-lab simulate``, then
    the chain with the specimen (mu + M and the modal conversion from the beam model) and the
    base acceleration as reference (relative motion). Component 0 is the second beam mode."""
    import subprocess
    import sys
    from pathlib import Path

    from fsi_lab.runfile import read_run

    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "wet.h5"
    subprocess.run([sys.executable, "-m", "fsi_lab.cli", "simulate",
                    str(root / "profiles" / "wet-beam-sim.toml"), "--duration", "10",
                    "--rate", "10000", "-o", str(out), "-q"], check=True, timeout=120,
                   capture_output=True)
    channels = read_run(out).channels
    specimen = Specimen.from_mapping({})
    chain = ("hvd", "integrate", "damping", "equivalent-damping")
    # Default settings (the damping law fitted from the first free cycle), the paper's
    # regression on the same components, and HVD with an explicit start.
    for method, hvd_params in (("law", {}), ("regression", {}),
                               ("envelope", {"components": 3, "start_s": 0.25,
                                             "method": "hvd"})):
        groups, summary = run(channels, chain, specimen=specimen,
                              analysis={"channels": ["tip_velocity"],
                                        "reference": "base_acceleration"},
                              params={"hvd": hvd_params,
                                      "equivalent-damping": {"method": method}})
        assert groups["tip_velocity/hvd"]["attrs"]["relative_to"] == "base_acceleration"
        # Mode 2 in water, near 17 Hz
        (c0,) = [c for c in summary["tip_velocity"]["components"]
                 if c.get("frequency_hz") and abs(c["frequency_hz"] / 17.0 - 1) < 0.05]
        eq = c0["equivalent_damping"]
        assert eq["amplitude_convention"].startswith("modal: q_2")
        assert eq["c_i"] == pytest.approx(0.65, rel=0.05), method
        assert eq["c_f"] == pytest.approx(33.0, rel=0.15), method


def test_a_failed_hvd_is_not_replaced_by_the_whole_channel():
    q, ch = two_mode_velocity()
    # a band with no spectral peak in it: hvd refuses it
    groups, summary = run({"tip": ch}, ("hvd", "integrate", "backbone", "equivalent-damping"),
                          params={"hvd": {"band_hz": [400.0, 450.0]}}, mass_per_length=q["m"])
    errors = {e["plugin"]: e["message"] for e in summary["tip"]["errors"]}
    assert set(errors) == {"hvd", "integrate", "backbone", "equivalent-damping"}
    for plugin in ("integrate", "backbone", "equivalent-damping"):
        assert errors[plugin].startswith(f"{plugin} on channel 'tip': hvd failed earlier in "
                                         "the chain on this channel"), errors[plugin]
        # hvd's reason, without repeating its "hvd on channel 'tip': " prefix
        assert errors["hvd"].split(": ", 1)[1] in errors[plugin]
    assert not any("equivalent_damping" in c for c in summary["tip"]["components"])
