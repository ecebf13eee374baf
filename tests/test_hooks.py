"""The hooks with arguments: summary text, default chain contributions, through the manager."""

from types import ModuleType

import pytest

from fsi_lab.chain import check_chain, default_chain
from fsi_lab.contract import AnalysisPlugin, AnalysisResult
from fsi_lab.hookspecs import hookimpl
from fsi_lab.presentation import SummaryText
from fsi_lab.registry import add_plugin, load_registry
from fsi_lab.summary import format_summary


def plugin(name: str, **hooks) -> ModuleType:
    """A plugin module implementing ``hooks`` (name -> function)."""
    module = ModuleType(name)
    for hook_name, function in hooks.items():
        setattr(module, hook_name, hookimpl(function))
    return module


def _run(context, params):
    return AnalysisResult()


def test_the_built_ins_default_chain_runs_each_analysis_after_what_it_needs():
    registry = load_registry()
    chain = default_chain(registry)
    assert set(chain) == {"spectrum", "hvd", "integrate", "instantaneous", "backbone", "damping",
                          "equivalent-damping"}
    check_chain(chain, registry)  # every provider before what requires or uses it
    assert chain.index("hvd") < chain.index("integrate") < chain.index("equivalent-damping")
    assert chain.index("damping") < chain.index("equivalent-damping")


def test_a_third_party_contribution_lands_after_its_providers_and_the_unmet_are_left_out():
    registry = load_registry()
    add_plugin(registry, plugin(
        "mine",
        fsi_lab_analyses=lambda: [
            AnalysisPlugin("after-hvd", (), _run, requires=("components",)),
            AnalysisPlugin("needs-nothing-there", (), _run, requires=("no-such-kind",))],
        fsi_lab_default_chain=lambda analyses: ["after-hvd", "needs-nothing-there",
                                                "not-installed"]), "mine")
    chain = default_chain(registry)
    assert chain.index("hvd") < chain.index("after-hvd")
    assert "needs-nothing-there" not in chain and "not-installed" not in chain
    check_chain(chain, registry)


def test_the_text_summary_shows_a_plugins_plain_values_without_code_that_knows_it():
    registry = load_registry()
    text = format_summary({"channels": {"tip": {
        "spectrum_peaks_hz": [17.1, 93.6], "spectrum_peak_amplitudes": [0.01, 0.002],
        "rms": 0.012345678, "fit": {"slope": 2.5, "law": "linear", "points": [1, 2]},
        "components": [{"index": 0, "frequency_hz": 17.06, "component_rms": 0.5,
                        "backbone": {"amplitude": [1e-3], "frequency_hz": [17.0], "decays": 1},
                        "damped_frequency_hz": 17.05}]}}}, registry)
    lines = text.splitlines()
    assert lines[0] == "channel tip: spectrum peaks 17.10, 93.60 Hz"       # spectrum's own
    assert "  rms: 0.01235" in lines                                        # generic
    assert "  fit.slope: 2.5" in lines and "  fit.law: linear" in lines     # one level down
    assert not any("points" in line for line in lines)                      # not plain
    assert "  component 0 at 17.060 Hz" in lines
    assert "    component_rms: 0.5" in lines
    # what the built-ins claim (backbone's curves, hvd's details) is not repeated
    assert "backbone" not in text and "damped_frequency" not in text
    assert "spectrum_peak" not in text


def test_a_failing_summary_hook_is_named_and_the_others_still_show():
    registry = load_registry()

    def broken(summary, component):
        raise KeyError("oops")

    def extra(component):
        if component is not None:
            return SummaryText(keys=("mine",), inline=", mine",
                               lines=(f"mine of {component['index']}",))
        return None

    add_plugin(registry, plugin("broken", fsi_lab_summary_lines=broken), "broken-lines")
    add_plugin(registry, plugin("extra", fsi_lab_summary_lines=extra), "extra-lines")
    text = format_summary({"channels": {"tip": {"components": [{"index": 0, "mine": 3.0}]}}},
                          registry)
    assert "  component 0, mine" in text.splitlines()
    assert "    mine of 0" in text.splitlines()
    assert "mine: 3" not in text
    assert "(plugin broken-lines: fsi_lab_summary_lines() failed: KeyError: 'oops'" in text


def test_summary_text_refuses_a_string_where_keys_belong():
    with pytest.raises(TypeError, match="tuples of strings"):
        SummaryText(keys="rms")
