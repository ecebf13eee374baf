"""The example third-party driver (tests/example_plugin, ``example-amplifier``), written with the
instrument kit, against the simulated amplifier through pyvisa-py on a 127.0.0.1 socket: opened
as fsi-lab opens it, checked before anything is sent, made safe and read back; then in a whole
run on the embedded bench, installed through its entry point like any third-party plugin."""

import pytest
from benchkit import bench_profile, lab_registry, run_profile, settings, sim_bench

from fsi_lab.contract import BenchContext, OutputState
from fsi_lab.errors import InstrumentError
from fsi_lab.runfile import read_run


@pytest.fixture
def example(with_example_plugin):
    """The example driver's module, imported from the installed example distribution."""
    from fsi_lab_example import amplifier

    return amplifier


@pytest.fixture
def address(sim_bench):
    """The VISA address of a simulated amplifier (stopped at the end of the test)."""
    return sim_bench().addresses["amplifier"]


def test_the_example_driver_drives_the_simulated_amplifier(example, address):
    driver = example.PLUGIN.open(address, settings(example), BenchContext(purpose="outside-run"))
    try:
        assert driver.found_on is False
        assert driver.identify().count(",") == 3
        driver.set_gain(2.5)
        driver.enable_output(True)
        assert driver.read_state() == {"output_enabled": True, "gain": 2.5}
        with pytest.raises(InstrumentError, match=r"example-amplifier at TCPIP0::127\.0\.0\.1::"
                                                  r"\d+::SOCKET: gain = 50: accepted a number "
                                                  r">= 0 V/V and <= 20 V/V"):
            driver.set_gain(50)
        assert driver.gain == 2.5  # the refused value never reached the amplifier
        assert driver.link.errors() == []
        driver.safe_state()
        state = driver.read_state()
        assert isinstance(state, OutputState) and state.output_enabled is False
    finally:
        driver.close()


def test_an_output_left_on_is_switched_off_and_reported_when_opened(example, address):
    first = example.PLUGIN.open(address, settings(example), {})
    first.enable_output(True)
    first.link.close()  # a controller that died with the output on
    second = example.PLUGIN.open(address, settings(example), {})
    try:
        assert second.found_on is True
        assert second.read_state()["output_enabled"] is False
    finally:
        second.close()


def test_a_run_with_the_example_amplifier_completes_and_ends_safe(example, tmp_path):
    registry = lab_registry()
    assert registry.get("instrument", "example-amplifier").role == "amplifier"
    path = bench_profile(tmp_path / "bench.toml")
    path.write_text(path.read_text().replace('plugin = "shaker-amplifier"',
                                             'plugin = "example-amplifier"'))
    outcome = run_profile(path, registry, tmp_path / "runs")
    assert outcome.exit_status == "completed", outcome.error
    assert outcome.final_states["amplifier"] == {"output_enabled": False, "gain": 2.0}
    run = read_run(outcome.path)
    assert run.instruments["amplifier"]["plugin"] == "example-amplifier"
    assert run.instruments["amplifier"]["final_state"]["output_enabled"] is False
