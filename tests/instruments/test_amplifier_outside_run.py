"""``reset_interlocks`` clears latched interlocks only when the amplifier is opened for a run.

``fsi-lab safe`` and ``fsi-lab identify`` open the bench ``"outside-run"``: a latched interlock
must stay latched there, for the operator to find its cause. The simulated amplifier latches an
e-stop that was pressed and released; the real driver opens it over loopback TCP.
"""

import pytest
from benchkit import settings, sim_bench

from fsi_lab.instruments import shaker_amplifier


def _open(bench, context):
    return shaker_amplifier.PLUGIN.open(
        bench.addresses["amplifier"], settings(shaker_amplifier, reset_interlocks=True), context)


@pytest.fixture
def latched(sim_bench):
    """A bench whose amplifier holds a latched e-stop whose cause is gone."""
    bench = sim_bench()
    bench.amplifier.set_cause("e_stop", True)
    bench.amplifier.set_cause("e_stop", False)
    assert bench.amplifier.state.latched == {"e_stop"}
    return bench


def test_opening_outside_a_run_leaves_a_latched_interlock_latched(latched):
    amplifier = _open(latched, {"purpose": "outside-run"})
    try:
        assert amplifier.interlocks()["e_stop"] is True
        assert amplifier.read_state()["interlocks"] == {"e_stop": True}
    finally:
        amplifier.close()
    assert latched.amplifier.state.latched == {"e_stop"}


@pytest.mark.parametrize("context", [{"purpose": "run"}, {}], ids=["run", "no purpose"])
def test_opening_for_a_run_clears_it(latched, context):
    amplifier = _open(latched, context)
    try:
        assert not any(amplifier.interlocks().values())
    finally:
        amplifier.close()
    assert latched.amplifier.state.latched == set()
    assert latched.amplifier.state.output_on is False
