"""The lab drivers against the simulated bench, over pyvisa-py (TCPIP SOCKET, ASRL on a
pseudo-terminal) and pyserial (pseudo-terminal): protocol behaviour and physics."""

import socket
import time

import numpy as np
import pytest
from benchkit import (  # sim_bench: benchkit's fixture, named by the tests below
    ACCELEROMETER,
    bench_profile,
    bench_threads,
    lab_registry,
    run_profile,
    settings,
    sim_bench,
)
from scipy import signal

from fsi_lab.errors import InstrumentError
from fsi_lab.instruments import keysight33500, polytec, scpi_daq, shaker_amplifier
from fsi_lab.instruments._visa import VisaLink
from fsi_lab.instruments.sim.bench import BenchOptions, SimBench
from fsi_lab.instruments.sim.frontends import IEPE_HIGHPASS_HZ
from fsi_lab.instruments.sim.keysight import resample_arb
from fsi_lab.modelling import BenchPhysics, beam_model
from fsi_lab.runfile import read_run


class Bench:
    """The four drivers opened on a simulated bench; closes them at the end."""

    def __init__(self, bench: SimBench, **overrides):
        self.bench = bench
        self.opened = []
        a = bench.addresses
        self.amplifier = self._open(shaker_amplifier, a["amplifier"], overrides.get("amplifier"))
        self.source = self._open(keysight33500, a["source"], overrides.get("source"))
        self.vibrometer = self._open(polytec, a["vibrometer"], overrides.get("vibrometer"))
        self.daq = self._open(scpi_daq, a["acquisition"], overrides.get("acquisition"))

    def _open(self, module, address, values):
        instrument = module.PLUGIN.open(address, settings(module, **(values or {})), {})
        self.opened.append(instrument)
        return instrument

    def record(self, wave, rate, inputs, duration, gain=2.0, enable=True):
        """Play ``wave`` and record ``inputs`` for ``duration`` s; channel -> volts."""
        self.source.load_waveform(wave, rate)
        self.amplifier.set_gain(gain)
        self.daq.configure(inputs, rate, duration)
        self.daq.arm()
        if enable:
            self.amplifier.enable_output(True)
        self.source.start()
        blocks = []
        while (block := self.daq.read_block(5.0)) is not None:
            blocks.append(block)
        return {name: np.concatenate([b[name] for b in blocks]) for name in inputs}

    def close(self):
        for instrument in self.opened:
            instrument.safe_state()
            instrument.close()


@pytest.fixture
def drivers(sim_bench):
    opened = []

    def make(bench=None, **overrides):
        lab = Bench(bench or sim_bench(), **overrides)
        opened.append(lab)
        return lab

    yield make
    for lab in opened:
        lab.close()


def _pulse(rate, duration=1.0, level=0.5, start=0.1, width=0.02):
    t = np.arange(int(duration * rate)) / rate
    return np.where((t >= start) & (t < start + width), level, 0.0)


def test_each_driver_identifies_itself_over_its_wire(drivers):
    lab = drivers()
    assert "33522B,SIMULATED" in lab.source.identify()
    assert "PA25E-SIM" in lab.amplifier.identify()
    assert lab.vibrometer.identify() == "Polytec PDV-100, velocity decoder VD-PDV (VeloDec,0)"
    assert "DSA4-SIM" in lab.daq.identify()
    assert lab.bench.addresses["source"].startswith("TCPIP0::127.0.0.1::")
    assert lab.bench.addresses["vibrometer"].startswith("/dev/pts/")


def test_servers_listen_on_loopback_only(sim_bench):
    bench = sim_bench()
    for role in ("source", "amplifier", "acquisition"):
        host, port = bench._endpoints[role]._server.sockets[0].getsockname()
        assert host == "127.0.0.1" and port > 0


def test_amplifier_answers_on_a_serial_port_through_pyvisa(sim_bench):
    bench = sim_bench()
    amplifier = shaker_amplifier.PLUGIN.open(bench.addresses["amplifier_serial"],
                                             settings(shaker_amplifier), {})
    try:
        assert "PA25E-SIM" in amplifier.identify()
        amplifier.set_gain(3.0)
        assert amplifier.read_state()["gain"] == 3.0
    finally:
        amplifier.safe_state()
        amplifier.close()


def test_vibrometer_range_and_delay_come_from_the_controller(drivers):
    lab = drivers(vibrometer={"range": "5mm/s/V"})
    assert lab.vibrometer.sensitivity() == pytest.approx(200.0)
    assert lab.vibrometer.delay() == pytest.approx(1.1e-3)
    assert lab.bench.vibrometer.state.range_name == "5mm/s/V"
    assert lab.bench.vibrometer.state.remote == "LLO"


def test_vibrometer_in_echo_and_acknowledge_modes_is_quietened_and_given_back(sim_bench):
    bench = sim_bench(vibrometer_echo=True, vibrometer_acknowledge=True)
    vibrometer = polytec.PLUGIN.open(bench.addresses["vibrometer"],
                                     settings(polytec, range="25mm/s/V"), {})
    state = bench.vibrometer.state
    try:
        assert (state.echo, state.acknowledge, state.remote) == (False, False, "LLO")
        assert state.range_name == "25mm/s/V"
        assert vibrometer.read_state() == {"range": "25mm/s/V"}
    finally:
        vibrometer.close()
    deadline = time.monotonic() + 5.0  # the pseudo-terminal delivers "Local" asynchronously
    while state.remote != "Local" and time.monotonic() < deadline:
        time.sleep(0.01)
    assert state.remote == "Local"


def test_the_source_on_channel_2_routes_its_trigger_output(sim_bench, drivers):
    lab = drivers(sim_bench(source_channel=2), source={"channel": 2})
    rate = 10000.0
    out = lab.record(_pulse(rate, duration=0.3, start=0.05), rate, {"drive": 1}, 0.3)
    assert lab.bench.source.trigger_out_channel == 2
    assert np.argmax(out["drive"] > 0.25) == pytest.approx(0.05 * rate, abs=3)


def test_a_waveform_not_starting_at_0_v_rests_at_0_v_around_its_burst(drivers):
    lab = drivers()
    rate = 10000.0
    wave = np.full(int(0.05 * rate), 0.4)  # starts (and ends) at 0.4 V
    lab.source.load_waveform(wave, rate)
    assert lab.source.settings()["leading_zero_points"] == 1
    lab.source.link.send_checked("OUTP1 ON")  # armed, not triggered: the resting level
    assert np.allclose(lab.bench.source.output_volts(0, 100, rate), 0.0)
    lab.source.link.send_checked("OUTP1 OFF")
    out = lab.record(wave, rate, {"drive": 1}, 0.2)
    drive = out["drive"]
    assert np.median(drive[100:400]) == pytest.approx(0.4, abs=0.01)
    assert np.abs(drive[int(0.1 * rate):]).max() < 0.01  # after the burst: 0 V, not 0.4 V


def test_vibrometer_at_the_wrong_baud_rate_gets_garbage(sim_bench):
    bench = sim_bench()
    with pytest.raises(InstrumentError, match=r"garbled reply .*115200 baud 8N1"):
        polytec.PLUGIN.open(bench.addresses["vibrometer"], settings(polytec, baud_rate=9600), {})


def test_vibrometer_offers_only_its_ranges(sim_bench):
    bench = sim_bench()
    with pytest.raises(InstrumentError, match="range '1000mm/s/V' is not offered by VD-PDV; "
                                              "it offers 5mm/s/V, 25mm/s/V, 125mm/s/V"):
        polytec.PLUGIN.open(bench.addresses["vibrometer"],
                            settings(polytec, range="1000mm/s/V"), {})


def test_generator_refuses_too_few_points_through_its_error_queue(sim_bench):
    bench = sim_bench()
    link = VisaLink("keysight33500", bench.addresses["source"], 2.0)
    try:
        link.send_checked("FORM:BORD SWAP")
        payload = np.zeros(4, "<f4").tobytes()
        link.write_raw("DATA:ARB", b"DATA:ARB X,#216" + payload + b"\n")
        assert link.errors() == ['-222,"Data out of range; 4 points; at least 8"']
    finally:
        link.close()


def test_tip_velocity_agrees_with_the_bench_physics(tmp_path):
    """The record through every driver equals BenchPhysics driven by the same waveform, to the
    noise of the vibrometer (0.5 um/s/sqrt(Hz) at 125 mm/s/V) and of the digitiser."""
    registry = lab_registry()
    outcome = run_profile(bench_profile(tmp_path / "wet.toml", duration=2.0), registry,
                          tmp_path / "runs")
    assert outcome.exit_status == "completed", outcome.error
    run = read_run(outcome.path)
    rate = 10000.0
    waveform = run.excitation["waveform"]
    drive = np.zeros(int(2.0 * rate))
    drive[:waveform.size] = waveform
    profile_model = {"modes": 4, "c_i": 0.65, "c_f": 33.0, "damping_ratios": None,
                     "rayleigh": False, "projection": "per-mode"}
    from fsi_lab.specimen import Specimen

    specimen = Specimen.from_mapping({"fluid": "water"})
    physics = BenchPhysics(beam_model(specimen, profile_model),
                           {"suspension_hz": 30.0, "damping_ratio": 0.08, "mm_per_volt": 0.5},
                           rate, specimen.measurement_point)
    expected = physics.advance(2.0 * drive)
    velocity = run.channels["tip_velocity"]
    delay = int(round(-velocity.t0 * rate))
    assert delay == 11  # 1.1 ms, compensated through t0
    error = velocity.data[delay:] - expected["tip_velocity"][:-delay]
    noise = 0.5e-6 * np.sqrt(rate / 2)
    assert np.abs(expected["tip_velocity"]).max() > 0.1
    assert np.std(error) < 1.3 * noise
    assert abs(np.mean(error)) < 0.1 * noise
    # the drive channel is the waveform (16-bit DAC, 24-bit ADC)
    assert np.abs(run.channels["drive"].data - drive).max() < 2e-4
    # the accelerometer through its AC-coupled IEPE input
    b, a = signal.butter(1, IEPE_HIGHPASS_HZ, "highpass", fs=rate)
    coupled = signal.lfilter(b, a, expected["base_acceleration"])
    acc_error = run.channels["base_acceleration"].data - coupled
    assert np.std(acc_error) < 1.3 * 10.0 * 2.0 ** -19 / ACCELEROMETER


def test_oversampled_world_matches_the_physics_at_the_higher_rate(drivers, sim_bench):
    """At 2 kHz the dry beam's fourth mode (397 Hz) needs smaller steps: the bench simulates at
    6 kHz and its anti-aliasing filter decimates without delay or passband loss."""
    from fsi_lab.specimen import Specimen

    dry = {"modes": 4, "c_i": None, "c_f": 0.0, "damping_ratios": [0.002, 0.001],
           "rayleigh": True, "projection": "per-mode"}
    specimen = Specimen.from_mapping({"fluid": "air"})
    lab = drivers(sim_bench(specimen=specimen, model=dry))
    rate = 2000.0
    record = lab.record(_pulse(rate), rate, {"vel": 3}, 1.0)
    assert lab.bench.last_overloads == {}
    physics = BenchPhysics(beam_model(specimen, dry), lab.bench.shaker, 3 * rate, 0.08)
    # the generator plays its 2 kSa/s points band-limited (arb filter "step"), seen at 6 kHz
    played = resample_arb(_pulse(rate), rate, 3 * rate, "STEP")
    expected = physics.advance(2.0 * played)["tip_velocity"][::3]
    delay = lab.vibrometer.delay() * rate
    shifted = np.interp(np.arange(expected.size) - delay, np.arange(expected.size), expected)
    velocity = record["vel"] / lab.vibrometer.sensitivity()
    assert np.abs(velocity - shifted).max() < 2e-3 * np.abs(expected).max()


def test_antialiasing_removes_a_tone_above_the_nyquist_frequency(drivers):
    lab = drivers()
    arb_rate, rate = 40000.0, 2000.0
    t = np.arange(int(0.5 * arb_rate)) / arb_rate
    tone = 0.5 * np.sin(2 * np.pi * 1700.0 * t)  # aliases to 300 Hz at 2 kS/s
    record = lab.record(tone, arb_rate, {"drive": 1}, 0.5, enable=False)["drive"]
    spectrum = np.abs(np.fft.rfft(record)) * 2 / record.size
    frequencies = np.fft.rfftfreq(record.size, 1 / rate)
    assert spectrum[np.argmin(np.abs(frequencies - 300.0))] < 0.005 * 0.5
    naive = tone[::20]  # what sampling without the filter would see
    assert np.abs(np.fft.rfft(naive)).max() * 2 / naive.size > 0.4


def test_iepe_supply_powers_the_accelerometer(drivers):
    powered = drivers()
    unpowered = drivers(acquisition={"iepe_inputs": []})
    rate = 5000.0
    on = powered.record(_pulse(rate, 0.4), rate, {"acc": 2}, 0.4)["acc"]
    off = unpowered.record(_pulse(rate, 0.4), rate, {"acc": 2}, 0.4)["acc"]
    assert np.abs(on).max() > 0.1
    assert np.abs(off).max() < 1e-4


def test_real_time_pacing_follows_the_sample_clock(drivers, sim_bench):
    lab = drivers(sim_bench(fast=False))
    started = time.monotonic()
    lab.record(np.zeros(1000), 2000.0, {"drive": 1}, 0.5)
    # paced by the sample clock: never faster than the record (a loaded machine may be slower)
    assert time.monotonic() - started > 0.45


def test_over_travel_trips_when_the_base_exceeds_the_stroke(drivers):
    lab = drivers()
    rate = 5000.0
    t = np.arange(int(0.5 * rate)) / rate
    step = np.where(t >= 0.05, 2.0, 0.0)  # 2 V x gain 10 x 0.5 mm/V = 10 mm > 8.8 mm
    record = lab.record(step, rate, {"drive": 1, "vel": 3}, 0.5, gain=10.0)
    assert lab.amplifier.interlocks()["over_travel"]
    assert lab.amplifier.read_state()["output_enabled"] is False
    ((time_s, name),) = lab.bench.amplifier.state.trips
    assert name == "over_travel" and 0.05 < time_s < 0.1
    assert record["drive"][-1] == pytest.approx(2.0, abs=1e-3)  # the source still drives
    with pytest.raises(InstrumentError, match="interlock over_travel is active"):
        lab.amplifier.enable_output(True)


def test_interlocks_latch_until_cleared_and_their_cause_is_gone(drivers):
    lab = drivers()
    lab.bench.amplifier.set_cause("e_stop", True)
    assert lab.amplifier.interlocks()["e_stop"]
    link = lab.amplifier.link
    link.write("OUTP 1")
    assert link.errors() == ['-221,"Settings conflict; interlock active: e_stop"']
    link.send_checked("INTL:RES")
    assert lab.amplifier.interlocks()["e_stop"]  # still pressed
    lab.bench.amplifier.set_cause("e_stop", False)
    link.send_checked("INTL:RES")
    lab.amplifier.enable_output(True)
    assert lab.amplifier.read_state()["output_enabled"] is True


@pytest.mark.parametrize("fault", ["drop", "garble"])
def test_amplifier_safe_state_recovers_a_broken_link(drivers, fault):
    lab = drivers()
    lab.amplifier.enable_output(True)
    lab.bench.inject_fault(fault, "amplifier")
    with pytest.raises(InstrumentError):
        lab.amplifier.interlocks()
    lab.amplifier.safe_state()  # reconnects, switches off, confirms
    assert lab.bench.amplifier.state.output_on is False


def test_amplifier_safe_state_gives_up_after_two_short_waits_on_a_dead_link(drivers):
    # "quickly" without a clock: two attempts, each waiting at most the safe state's 1 s
    lab = drivers()
    link = lab.amplifier.link
    asked, query = [], link.query

    def query_noting_its_timeout(command, *args, **kwargs):
        asked.append((command, link._resource.timeout))
        return query(command, *args, **kwargs)

    link.query = query_noting_its_timeout
    lab.bench.inject_fault("timeout", "amplifier")
    with pytest.raises(InstrumentError, match="safe state not confirmed: .*no reply within 1 s"):
        lab.amplifier.safe_state()
    assert asked == [("OUTP?", 1000), ("OUTP?", 1000)]  # ms
    lab.bench.inject_fault("none")


def test_a_stopped_bench_closes_its_ports_and_thread():
    bench = SimBench(options=BenchOptions(fast=True)).start()
    port = bench._endpoints["source"].port
    bench.stop()
    bench.stop()  # idempotent
    assert not bench_threads()
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=1).close()


def test_a_vanished_serial_port_is_an_instrument_error_on_every_question(sim_bench):
    bench = sim_bench()
    vibrometer = polytec.PLUGIN.open(bench.addresses["vibrometer"],
                                     settings(polytec, timeout_s=0.5), {})
    try:
        bench.inject_fault("drop", "vibrometer")  # the port vanishes at the next line
        for _ in range(3):  # the read, then flushing a dead port (termios.error underneath)
            with pytest.raises(InstrumentError, match=r"polytec at /dev/pts/\d+: "):
                vibrometer.monitor()
    finally:
        vibrometer.close()
