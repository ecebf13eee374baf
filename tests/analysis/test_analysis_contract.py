"""The analysis contract: what an analysis requires, uses and provides, checked when the profile
is; typed results handed to the later analyses; plugins written before typed results.

Ground truth: the declarations themselves (a chain either gives what is required or is refused
naming it), the identity of the objects handed between analyses, and the numbers of runs that
must agree exactly (equivalent-damping with damping's declared defaults, with or without
damping in the chain).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from test_analysis_plugins import load_registry, run, two_mode_velocity
from test_modal_model import SPECIMEN, bench_record
from test_modal_model import registry as registry_with_modal_model

from fsi_lab import hookspecs
from fsi_lab.chain import check_chain, default_chain, run_chain
from fsi_lab.contract import (
    ERROR_GIST,
    AnalysisContext,
    AnalysisPlugin,
    AnalysisResult,
    ChannelData,
    Result,
    check_descriptor,
    error_gist,
)
from fsi_lab.errors import ParameterError, ProfileError
from fsi_lab.params import validate
from fsi_lab.plugins.analysis.results import Components, DampingCurves
from fsi_lab.registry import Registry, add_plugin
from fsi_lab.registry import load_registry as load_installed

#: The chain the built-ins put in the default chain, in an order check_chain accepts.
DEFAULT_CHAIN = ("spectrum", "hvd", "integrate", "instantaneous", "backbone", "damping",
                 "equivalent-damping")

ROOT = Path(__file__).resolve().parents[2]


def with_plugins(*plugins: AnalysisPlugin, base: Registry | None = None) -> Registry:
    """The built-in analyses (or ``base``) plus ``plugins``."""
    registry = base or load_registry()
    for plugin in plugins:
        check_descriptor("analysis", plugin)
        registry.descriptors["analysis"][plugin.name] = plugin
    return registry


# ----------------------------------------------------------------------------- declarations
def test_every_kind_a_built_in_reads_is_provided_by_a_built_in():
    registry = registry_with_modal_model()
    plugins = [registry.get("analysis", n) for n in registry.names("analysis")]
    provided = {p.provides for p in plugins if p.provides}
    assert provided == {"spectrum", "components", "integrated", "instantaneous", "backbone",
                        "damping-curve", "damping-coefficients", "modal-comparison"}
    for p in plugins:
        assert set(p.requires + p.uses) <= provided, p.name
    check_chain(DEFAULT_CHAIN, registry)
    check_chain(DEFAULT_CHAIN + ("modal-model",), registry)
    check_chain(default_chain(load_installed()), load_installed())
    for name in registry.names("analysis"):          # each alone, except what requires
        if not registry.get("analysis", name).requires:
            check_chain([name], registry)


@pytest.mark.parametrize("chain, message", [
    (["modal-model"], "analysis.chain: modal-model requires the 'components' result, which no "
                      "analysis before it in the chain provides; add hvd before modal-model "
                      "(chain: modal-model)"),
    (["modal-model", "hvd"], "analysis.chain: modal-model requires the 'components' result, "
                             "which no analysis before it in the chain provides; hvd provides it "
                             "after modal-model: move hvd before it"),
    (["integrate", "hvd", "backbone"], "analysis.chain: integrate uses the 'components' result "
                                       "of hvd, which runs after it; move hvd before integrate"),
    (["hvd", "backbone", "damping", "equivalent-damping", "integrate"],
     "analysis.chain: backbone uses the 'integrated' result of integrate, which runs after it; "
     "move integrate before backbone"),
])
def test_a_chain_that_misses_what_an_analysis_needs_is_refused_naming_it(chain, message):
    with pytest.raises(ParameterError) as error:
        check_chain(chain, registry_with_modal_model())
    assert str(error.value).startswith(message), str(error.value)


def test_the_profile_check_refuses_such_a_chain(registry):
    from support import cli_here

    from fsi_lab.profile import load_profile

    profile = ROOT / "profiles" / "wet-beam-sim.toml"
    load_profile(profile, registry)                                  # as shipped: valid
    # (named with the --set that gave the chain)
    message = (f"{profile}: --set analysis.chain=spectrum,modal-model: analysis.chain: "
               "modal-model requires the 'components' result, which no analysis before it in "
               "the chain provides; add hvd before modal-model")
    with pytest.raises(ProfileError, match=re.escape(message)):
        load_profile(profile, registry, ["analysis.chain=spectrum,modal-model"])
    proc = cli_here("profile", "check", str(profile), "--set",
                    "analysis.chain=spectrum,modal-model")
    assert proc.returncode == 2 and message in proc.stderr, proc.stderr


def test_a_requirement_no_installed_analysis_provides_says_so():
    lonely = AnalysisPlugin("lonely", (), lambda c, p: AnalysisResult(), requires=("wavelets",))
    with pytest.raises(ParameterError, match=r"lonely requires the 'wavelets' result, which no "
                                             r"analysis before it in the chain provides; no "
                                             r"installed analysis provides it"):
        check_chain(["hvd", "lonely"], with_plugins(lonely))


@pytest.mark.parametrize("declaration, message", [
    ({"requires": "components"}, ("analysis 'x': requires must be a tuple of result kinds; got "
                                  "'components': write requires=('components',)",)),
    ({"uses": Components}, ("analysis 'x': uses must be a tuple of result kinds; got <class",
                            "Components'>: write uses=('components',)")),
    ({"provides": ("a", "b")}, ("analysis 'x': provides names one result kind",)),
    ({"requires": ("",)}, ("analysis 'x': requires: '' is not a result kind",)),
    ({"provides": 3}, ("analysis 'x': provides: 3 is not a result kind",)),
])
def test_a_declaration_that_is_not_kinds_is_refused_saying_what_to_write(declaration, message):
    with pytest.raises(TypeError) as error:
        AnalysisPlugin("x", (), lambda c, p: None, **declaration)
    assert all(part in str(error.value) for part in message), str(error.value)


def test_a_plugin_that_declares_wrongly_is_refused_when_it_is_loaded():
    """Through the plugin manager, as the entry points are loaded: listed invalid with the
    reason, and not usable."""
    module = ModuleType("declares_wrongly")

    @hookspecs.hookimpl
    def fsi_lab_analyses():
        return [AnalysisPlugin("bad", (), lambda c, p: None, requires="hvd")]

    module.fsi_lab_analyses = fsi_lab_analyses
    registry = Registry()
    add_plugin(registry, module, "declares-wrongly")
    ((name, kind, status, error),) = [(r.name, r.kind, r.status, r.error)
                                       for r in registry.records]
    assert (name, kind, status) == ("declares-wrongly", "analysis", "invalid")
    assert "write requires=('hvd',)" in error
    assert not registry.descriptors["analysis"]
    with pytest.raises(ValueError, match="provides 'x' and also requires or uses it"):
        check_descriptor("analysis", AnalysisPlugin("y", (), print, uses=("x",), provides="x"))


# ----------------------------------------------------------------------------- typed results
@dataclass
class Energy(Result):
    """Energy of each component (a kind of a third party)."""

    kind = "energy"
    values: np.ndarray
    components: Components

    def record(self) -> AnalysisResult:
        return AnalysisResult(datasets={"energy": self.values}, units={"energy": "m^2/s"},
                              summary={"energy_total": float(self.values.sum())})


def test_typed_results_are_handed_to_the_later_analyses_as_objects():
    seen = {}

    def energy(context, params):
        found = context.result(Components)
        return Energy(np.sum(found.decomposition.components ** 2, axis=1)
                      / context.channel.sample_rate, found)

    def share(context, params):
        seen["energy"] = context.result("energy")
        seen["components"] = context.result(Components)
        seen["damping"] = context.result(DampingCurves)       # used, not in this chain
        return AnalysisResult(summary={"share": (seen["energy"].values
                                                 / seen["energy"].values.sum()).tolist()})

    registry = with_plugins(
        AnalysisPlugin("energy", (), energy, requires=(Components,), provides=Energy),
        AnalysisPlugin("share", (), share, requires=("energy", Components),
                       uses=(DampingCurves,)))
    q, ch = two_mode_velocity()
    groups, summary = run({"tip": ch}, ("hvd", "energy", "share"), registry=registry)
    s = summary["tip"]
    assert "errors" not in s, s.get("errors")
    assert seen["energy"].components is seen["components"]      # the very objects
    assert seen["damping"] is None
    rows = groups["tip/hvd"]["datasets"]["components"]
    np.testing.assert_allclose(groups["tip/energy"]["datasets"]["energy"],
                               np.sum(rows ** 2, axis=1) / ch.sample_rate, rtol=1e-12)
    assert groups["tip/energy"]["units"]["energy"] == "m^2/s"
    assert s["energy_total"] == pytest.approx(float(np.sum(rows ** 2)) / ch.sample_rate)
    assert sum(s["share"]) == pytest.approx(1.0) and s["share"][0] > 0.9   # mode 1 dominates


def test_a_failed_provider_stops_what_requires_it_with_the_reason():
    def energy(context, params):
        raise AssertionError("not reached: hvd failed")

    registry = with_plugins(
        AnalysisPlugin("energy", (), energy, requires=(Components,), provides=Energy),
        AnalysisPlugin("total", (), lambda c, p: AnalysisResult(), requires=("energy",)))
    q, ch = two_mode_velocity()
    _, summary = run({"tip": ch}, ("hvd", "energy", "total"), registry=registry,
                     params={"hvd": {"band_hz": [400.0, 450.0]}})     # no mode there
    errors = {e["plugin"]: e["message"] for e in summary["tip"]["errors"]}
    assert errors["energy"].startswith("energy on channel 'tip': needs the 'components' result, "
                                       "which hvd failed to give on this channel (identify: "
                                       "band 400 to 450 Hz")
    assert errors["total"].startswith("total on channel 'tip': needs the 'energy' result, which "
                                      "energy failed to give on this channel (needs the "
                                      "'components' result, which hvd failed")
    assert errors["hvd"] not in errors["energy"]


@pytest.mark.parametrize("message, gist", [
    ("hvd on channel 'tip': identify: the base keeps moving; end the excitation earlier",
     "identify: the base keeps moving; end the excitation earlier"),
    ("identify: " + "word " * 60, "identify: " + " ".join(["word"] * 30) + " ..."),
])
def test_an_analysis_that_needed_a_failed_result_repeats_only_the_gist_of_its_error(message,
                                                                                     gist):
    """The whole error stands in the channel's errors once; those of the analyses that needed
    its result say which failed and why in a line, not all of it again."""
    assert error_gist(message) == gist
    assert len(error_gist(message)) <= ERROR_GIST + 4


@pytest.mark.parametrize("declared, returned, message", [
    ({"provides": "energy"}, lambda c: AnalysisResult(),
     "returned an AnalysisResult but declares provides='energy'; return the typed result of "
     "that kind"),
    ({}, lambda c: Energy(np.ones(1), None),
     "returned a result of kind 'energy' but declares no provides; declare provides='energy'"),
    ({"provides": "power"}, lambda c: Energy(np.ones(1), None),
     "returned a result of kind 'energy' but declares provides='power'; declare "
     "provides='energy'"),
    ({}, lambda c: {"rms": 1.0}, "returned dict, expected an AnalysisResult"),
    ({}, lambda c: c.result(Components),
     "reads the 'components' result but declares it in neither requires nor uses"),
])
def test_what_a_plugin_returns_or_reads_must_match_its_declaration(declared, returned, message):
    registry = with_plugins(AnalysisPlugin("odd", (), lambda c, p: returned(c), **declared))
    ch = ChannelData("tip", np.sin(np.arange(2000) * 0.1), 1000.0, "velocity", "m/s")
    _, summary = run({"tip": ch}, ("odd",), registry=registry)
    (error,) = summary["tip"]["errors"]
    assert error["plugin"] == "odd" and message in error["message"], error["message"]


def test_equivalent_damping_takes_damping_s_declared_defaults_or_its_curves():
    """The paper's regression without damping in the chain fits the curves damping gives with
    its declared defaults: the very numbers of a chain with damping at its defaults. With
    damping's own parameters in the chain, its typed curves are the ones fitted."""
    q, ch = two_mode_velocity(noise=0.003, seed=5)
    params = {"equivalent-damping": {"method": "regression"}}
    fits = {}
    for name, chain, extra in (
            ("without", ("hvd", "integrate", "equivalent-damping"), {}),
            ("defaults", ("hvd", "integrate", "damping", "equivalent-damping"), {}),
            ("eq5", ("hvd", "integrate", "damping", "equivalent-damping"),
             {"damping": {"method": "eq5", "smooth_points": 5}})):
        _, summary = run({"tip": ch}, chain, mass_per_length=q["m"], params={**params, **extra})
        fits[name] = summary["tip"]["components"][0]["equivalent_damping"]
    assert fits["without"]["c_i"] == fits["defaults"]["c_i"]
    assert fits["without"]["c_f"] == fits["defaults"]["c_f"]
    assert fits["without"]["damping_method"] == "decrement"
    assert fits["eq5"]["damping_method"] == "eq5" and fits["eq5"]["c_f"] != fits["defaults"]["c_f"]
    for fit in fits.values():                                           # ground truth
        assert fit["c_f"] == pytest.approx(q["c2"], rel=0.1)


def test_modal_model_reads_the_decomposition_s_coordinate_not_a_sentence():
    """Relative to the base when hvd subtracted it, absolute when it did not: read from the
    typed components, whatever the stored attribute says."""
    registry = registry_with_modal_model()
    channels = bench_record()
    for relative, coordinate in (("auto", "relative"), ("no", "absolute")):
        params = {"hvd": {"relative": relative}, "modal-model": {"c_i": 0.65, "c_f": 33.0}}
        validated = {n: validate(registry.get("analysis", n).params, params.get(n, {}), n)
                     for n in ("hvd", "modal-model")}
        groups, summary = run_chain(channels, {"chain": ["hvd", "modal-model"],
                                               "channels": ["tip"], "reference": "base"},
                                    validated, registry, specimen=SPECIMEN)
        assert summary["tip"]["modal_model"]["coordinate"] == coordinate, summary["tip"]
        assert groups["tip/hvd"]["attrs"]["relative_to"] == (
            "base" if relative == "auto" else "none (the channel as measured)")


def test_a_plugin_can_be_called_directly_with_typed_results():
    from fsi_lab.plugins.analysis.hvd import PLUGIN as HVD
    from fsi_lab.plugins.analysis.integrate import PLUGIN as INTEGRATE

    q, ch = two_mode_velocity()
    context = AnalysisContext(channel=ch, channels={"tip": ch}, results={})
    components = HVD.run(context, validate(HVD.params, {}, "hvd"))
    assert isinstance(components, Components) and components.count == 2
    record = components.record()
    assert record.datasets["components"].shape == (2, ch.data.size)
    context = AnalysisContext(channel=ch, channels={"tip": ch}, results={},
                              provided={"components": components}, shared=context.shared)
    integrated = INTEGRATE.run(context, validate(INTEGRATE.params, {}, "integrate"))
    assert integrated.quantity == "displacement" and sorted(integrated.signals) == [0, 1]


# ----------------------------------------------------------------------------- third parties
def test_the_example_distribution_s_analyses_work_both_ways(with_example_plugin):
    """Installed as a third party: ``component-rms`` (typed: requires hvd's components and
    provides its own kind), ``hvd-count`` (written before typed results: requires the analysis
    hvd by name, reads its stored attributes), ``rms`` (provides nothing), and
    ``bad-requires`` refused when loaded, saying what to write."""
    registry = load_installed()
    records = {r.name: r for r in registry.records}
    bad = records["example-bad-analysis"]
    assert bad.status == "invalid" and "write requires=('components',)" in bad.error
    rms = registry.get("analysis", "component-rms")
    assert (rms.requires, rms.provides) == (("components",), "component-rms")
    q, ch = two_mode_velocity()
    params = {n: validate(registry.get("analysis", n).params, {}, n)
              for n in ("hvd", "component-rms", "hvd-count", "rms")}
    chain = ["hvd", "component-rms", "hvd-count", "rms"]
    check_chain(chain, registry)
    groups, summary = run_chain({"tip": ch}, {"chain": chain}, params, registry)
    s = summary["tip"]
    assert "errors" not in s, s.get("errors")
    rows = groups["tip/hvd"]["datasets"]["components"]
    expected = np.sqrt(np.mean(rows ** 2, axis=1))
    got = {c["index"]: c["component_rms"] for c in s["components"] if "component_rms" in c}
    assert got == pytest.approx(dict(enumerate(expected)), rel=1e-12)
    np.testing.assert_allclose(groups["tip/component-rms"]["datasets"]["rms"], expected)
    assert groups["tip/component-rms"]["units"]["rms"] == "m/s"
    assert s["hvd_count"] == 2 and s["rms"] > 0
    for chain, needed in ((["component-rms"], "'components' result"),
                          (["hvd-count"], "'hvd' result")):
        with pytest.raises(ParameterError, match=re.escape(needed) + ".*add hvd before"):
            check_chain(chain, registry)
