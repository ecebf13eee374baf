"""The instrument contract: role classes declare the settings the runner reads, output roles
give a typed state, and the bench context is a typed object that still reads like the dict it
replaced."""

import dataclasses

import pytest

from fsi_lab.bench_access import safe_and_close, unsafe_roles
from fsi_lab.contract import (
    ROLE_INTERFACES,
    Amplifier,
    BenchContext,
    InstrumentPlugin,
    OutputState,
    RunPlan,
    SignalSource,
    check_descriptor,
)
from fsi_lab.params import Param

GAIN = Param("gain", "float", "V/V", 1.0, minimum=0.0, maximum=10.0)


def _amplifier(*params):
    return InstrumentPlugin(name="third-party-amp", role="amplifier", params=params,
                            open=lambda address, settings, bench: None)


def test_the_roles_declare_what_the_runner_reads():
    assert [s.name for s in SignalSource.run_settings] == ["sample_rate", "arb_filter"]
    assert [(s.name, s.unit, s.required) for s in Amplifier.run_settings] == \
        [("gain", "V/V", True)]
    assert {r for r, cls in ROLE_INTERFACES.items() if cls.has_output} == {"source", "amplifier"}
    with pytest.raises(ValueError, match="Amplifier declares no run setting 'gains'; it "
                                         "declares gain"):
        Amplifier.run_setting("gains")


@pytest.mark.parametrize("params, message", [
    ((), ("third-party-amp \\(amplifier\\): declares no 'gain' parameter \\(float in V/V\\), "
         "which every plugin of this role must")),
    ((Param("gain", "float", "dB", 1.0),), ("parameter 'gain' is declared as float in dB; the "
                                           "runner reads it as float in V/V")),
    ((Param("gain", "int", "V/V", 1),), "declared as int in V/V"),
])
def test_a_driver_that_misdeclares_a_run_setting_is_refused_at_loading(params, message):
    with pytest.raises(ValueError, match=message):
        check_descriptor("instrument", _amplifier(*params))
    check_descriptor("instrument", _amplifier(GAIN))


def test_a_source_filter_must_take_values_the_safety_check_knows():
    source = InstrumentPlugin(name="gen", role="source", open=lambda *a: None, params=(
        Param("arb_filter", "str", "", "sinc", choices=("sinc", "off")),))
    with pytest.raises(ValueError, match="gen \\(source\\): parameter 'arb_filter' must take "
                                         "its values among 'normal', 'step', 'off' \\(got "
                                         "'sinc'\\)"):
        check_descriptor("instrument", source)


def test_an_output_state_needs_a_boolean_output():
    state = OutputState(False, level_v=0.0)
    assert state == {"output_enabled": False, "level_v": 0.0} and dict(state)["level_v"] == 0.0
    assert state.output_enabled is False
    for bad in ("OFF", 0, None):
        with pytest.raises(TypeError, match="output_enabled must be a bool"):
            OutputState(bad)


class _Forgetful:
    def safe_state(self):
        pass

    def read_state(self):
        return {"gain": 0.0}

    def close(self):
        pass


def test_a_state_without_output_names_the_driver():
    states = safe_and_close({"amplifier": _Forgetful()}, [], plugins={"amplifier": "acme-pa"})
    why = unsafe_roles(states, {"amplifier": "acme-pa"})["amplifier"]
    assert "driver 'acme-pa': its state read back does not say that the output is off" in why
    assert "returns fsi_lab.contract.OutputState(output_enabled=" in why


def test_the_bench_context_is_typed_and_still_a_mapping():
    cleanup = []
    context = BenchContext(bench={"embedded": True}, cleanup=cleanup, purpose="outside-run")
    assert context.purpose == context["purpose"] == "outside-run"
    assert context.get("bench") == {"embedded": True} and context["cleanup"] is cleanup
    context["sim_bench"] = "a bench"  # what a driver stores for the others
    assert context.extras == {"sim_bench": "a bench"} and "sim_bench" in context
    assert context.setdefault("inprocess", {"x": 1}) == {"x": 1}
    context["purpose"] = "run"
    assert context.purpose == "run"
    assert {**context}["sim_bench"] == "a bench" and set(dict(context)) == {
        "specimen", "model", "shaker", "bench", "cleanup", "purpose", "sim_bench", "inprocess"}
    with pytest.raises(KeyError):
        del context["purpose"]
    with pytest.raises(ValueError, match="purpose 'idle'; expected one of run, outside-run"):
        BenchContext(purpose="idle")


def test_a_run_plan_is_the_context_and_the_record():
    plan = RunPlan(inputs={"drive": 1}, sample_rate=1000.0, duration=2.0, waveform_points=10,
                   waveform_rate=500.0)
    assert plan["inputs"] == {"drive": 1} and plan.get("bench") == {}
    assert {f.name for f in dataclasses.fields(RunPlan)} >= {"purpose", "waveform_rate"}
