"""The exact bytes each lab driver exchanges with its instrument.

A scripted loopback peer (TCP for the VISA drivers, a pseudo-terminal for the serial
vibrometer) reads exactly the bytes the script expects and answers its replies; the tests assert
that the driver sent those bytes and nothing else, and what it made of the replies.
"""

import struct

import numpy as np
import pytest
from benchkit import ScriptedPeer, pty_peer, settings, tcp_peer

from fsi_lab.errors import InstrumentError
from fsi_lab.instruments import keysight33500, polytec, scpi_daq, shaker_amplifier

NO_ERROR = (b"SYST:ERR?\n", b'+0,"No error"\n')
IDN = b"Keysight Technologies,33521B,MY00000001,4.00\n"


def checked(*commands: bytes) -> list:
    """Each command followed by the error-queue check that finds nothing."""
    script = []
    for command in commands:
        script += [(command + b"\n", None), NO_ERROR]
    return script


# --------------------------------------------------------------------------- Keysight 33500B
KEYSIGHT_OPEN = [(b"OUTP1?\n", b"0\n"), (b"OUTP1 OFF\n", None), (b"*IDN?\n", IDN),
                 (b"*CLS\n", None)] \
    + checked(b"OUTP1 OFF")


def _keysight(peer: ScriptedPeer, **values):
    return keysight33500.PLUGIN.open(peer.address, settings(keysight33500, **values), {})


def test_keysight_output_goes_off_even_when_the_identity_is_unexpected(tcp_peer):
    peer = tcp_peer([(b"OUTP1?\n", b"1\n"), (b"OUTP1 OFF\n", None), (b"*IDN?\n", b"33521B\n")])
    with pytest.raises(InstrumentError, match="unexpected identity '33521B'; expected "
                                              r"<maker>,<model>,<serial>,<firmware> \(OUTP OFF "
                                              r"was sent first\)"):
        _keysight(peer)
    peer.expect_all()


def test_keysight_uploads_a_float32_block_and_checks_each_step(tcp_peer):
    wave = np.array([0.0, 0.25, 0.5, -0.5, 0.0, 0.0, 0.0, 0.0])
    payload = struct.pack("<8f", 0.0, 0.5, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0)
    script = KEYSIGHT_OPEN + checked(b"OUTP1 OFF", b"FORM:BORD SWAP", b"SOUR1:DATA:VOL:CLE")
    script += [(b"SOUR1:DATA:ARB FSILAB,#232" + payload + b"\n", None), NO_ERROR]
    script += checked(b"SOUR1:FUNC ARB", b"SOUR1:FUNC:ARB FSILAB", b"SOUR1:FUNC:ARB:SRAT 1000",
                      b"SOUR1:FUNC:ARB:FILT STEP", b"OUTP1:LOAD INF", b"SOUR1:VOLT:UNIT VPP",
                      b"SOUR1:VOLT:OFFS 0", b"SOUR1:VOLT 1", b"SOUR1:BURS:MODE TRIG",
                      b"SOUR1:BURS:NCYC 1", b"TRIG1:SOUR BUS", b"SOUR1:BURS:STAT ON",
                      b"OUTP:TRIG ON", b"OUTP:TRIG:SOUR CH1")
    script += [(b"SOUR1:FUNC:ARB:SRAT?\n", b"+1.000000000000000E+03\n"),
               (b"SOUR1:VOLT?\n", b"+1.000000000000000E+00\n"),
               (b"SOUR1:VOLT:OFFS?\n", b"+0.000000000000000E+00\n")]
    script += checked(b"OUTP1 ON", b"*TRG")
    script += [(b"OUTP1 OFF\n", None), (b"ABOR\n", None), (b"SOUR1:VOLT:OFFS 0\n", None),
               (b"OUTP1?\n", b"0\n"),
               (b"OUTP1?\n", b"0\n"), (b"SOUR1:VOLT:OFFS?\n", b"+0.0E+00\n")]
    peer = tcp_peer(script)
    source = _keysight(peer)
    try:
        assert source.identify() == IDN.decode().strip()
        source.load_waveform(wave, 1000.0)
        source.start()
        source.safe_state()
        assert source.read_state() == {"output_enabled": False, "level_v": 0.0, "offset_v": 0.0}
        assert source.settings()["amplitude_vpp"] == 1.0
    finally:
        source.close()
    peer.expect_all()


def test_keysight_waits_for_a_big_upload_in_proportion_to_its_size(tcp_peer):
    points = 500_000  # 2 MB: the instrument takes 1 s to check it, 5 times the reply timeout
    wave = np.zeros(points)
    wave[1] = 0.5
    payload = np.zeros(points, "<f4")
    payload[1] = 1.0
    script = KEYSIGHT_OPEN + checked(b"OUTP1 OFF", b"FORM:BORD SWAP", b"SOUR1:DATA:VOL:CLE")
    script += [(b"SOUR1:DATA:ARB FSILAB,#7" + str(points * 4).encode() + payload.tobytes()
                + b"\n", None),
               (b"SYST:ERR?\n", (1.0, b'-223,"Too much data"\n')), NO_ERROR]
    peer = tcp_peer(script)
    source = _keysight(peer, timeout_s=0.2)
    assert keysight33500.upload_timeout(0.2, points * 4) > 8.0
    try:
        with pytest.raises(InstrumentError, match=r"the upload of 500000 points .* was refused: "
                                                  r"-223,\"Too much data\""):
            source.load_waveform(wave, 1000.0)
    finally:
        source.close()
    peer.expect_all()


def test_keysight_on_channel_2_routes_the_trigger_output_and_needs_it(tcp_peer):
    wave = np.array([0.0, 0.25, 0.5, -0.5, 0.0, 0.0, 0.0, 0.0])
    payload = struct.pack("<8f", 0.0, 0.5, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0)
    script = [(b"OUTP2?\n", b"0\n"), (b"OUTP2 OFF\n", None), (b"*IDN?\n", IDN),
              (b"*CLS\n", None)]
    script += checked(b"OUTP2 OFF", b"OUTP2 OFF", b"FORM:BORD SWAP", b"SOUR2:DATA:VOL:CLE")
    script += [(b"SOUR2:DATA:ARB FSILAB,#232" + payload + b"\n", None), NO_ERROR]
    script += checked(b"SOUR2:FUNC ARB", b"SOUR2:FUNC:ARB FSILAB", b"SOUR2:FUNC:ARB:SRAT 1000",
                      b"SOUR2:FUNC:ARB:FILT STEP", b"OUTP2:LOAD INF", b"SOUR2:VOLT:UNIT VPP",
                      b"SOUR2:VOLT:OFFS 0", b"SOUR2:VOLT 1", b"SOUR2:BURS:MODE TRIG",
                      b"SOUR2:BURS:NCYC 1", b"TRIG2:SOUR BUS", b"SOUR2:BURS:STAT ON",
                      b"OUTP:TRIG ON")
    script += [(b"OUTP:TRIG:SOUR CH2\n", None),
               (b"SYST:ERR?\n", b'-113,"Undefined header"\n'), NO_ERROR]
    peer = tcp_peer(script)
    source = _keysight(peer, channel=2)
    try:
        with pytest.raises(InstrumentError, match=r"routing the trigger output to channel 2 "
                                                  r"\(OUTP:TRIG:SOUR CH2\) was refused"):
            source.load_waveform(wave, 1000.0)
    finally:
        source.close()
    peer.expect_all()


def test_keysight_reports_a_refused_step_with_the_instruments_error(tcp_peer):
    wave = np.full(8, 0.5)
    payload = struct.pack("<9f", 0.0, *[1.0] * 8)  # a 0 V point first: the burst rests there
    script = KEYSIGHT_OPEN + checked(b"OUTP1 OFF", b"FORM:BORD SWAP", b"SOUR1:DATA:VOL:CLE")
    script += [(b"SOUR1:DATA:ARB FSILAB,#236" + payload + b"\n", None), NO_ERROR]
    script += checked(b"SOUR1:FUNC ARB", b"SOUR1:FUNC:ARB FSILAB")
    # within the declared 160 MSa/s, refused by this (slower) model
    script += [(b"SOUR1:FUNC:ARB:SRAT 100000000\n", None),
               (b"SYST:ERR?\n", b'-222,"Data out of range"\n'), NO_ERROR]
    peer = tcp_peer(script)
    source = _keysight(peer)
    try:
        with pytest.raises(InstrumentError) as info:
            source.load_waveform(wave, 1e8)
    finally:
        source.close()
    peer.expect_all()
    message = str(info.value)
    assert "keysight33500 at TCPIP0::127.0.0.1::" in message
    assert "'SOUR1:FUNC:ARB:SRAT 100000000' was refused: -222,\"Data out of range\"" in message
    assert "between 1 uSa/s and 160 MSa/s" in message


def test_keysight_refuses_a_value_beyond_its_declared_bounds_before_sending_it(tcp_peer):
    wave = np.full(8, 0.5)
    payload = struct.pack("<9f", 0.0, *[1.0] * 8)
    script = KEYSIGHT_OPEN + checked(b"OUTP1 OFF", b"FORM:BORD SWAP", b"SOUR1:DATA:VOL:CLE")
    script += [(b"SOUR1:DATA:ARB FSILAB,#236" + payload + b"\n", None), NO_ERROR]
    script += checked(b"SOUR1:FUNC ARB", b"SOUR1:FUNC:ARB FSILAB")
    peer = tcp_peer(script)
    source = _keysight(peer)
    try:
        with pytest.raises(InstrumentError, match=r"keysight33500 at TCPIP0::127\.0\.0\.1::\d+::"
                                                  r"SOCKET: sample_rate = 500000000\.0: accepted "
                                                  r"a number >= 1e-06 Hz and <= 1\.6e\+08 Hz"):
            source.load_waveform(wave, 5e8)
    finally:
        source.close()
    peer.expect_all()  # SOUR1:FUNC:ARB:SRAT 500000000 was never sent


def test_keysight_refuses_more_points_than_its_memory_before_sending(tcp_peer):
    peer = tcp_peer(KEYSIGHT_OPEN)
    source = _keysight(peer)
    try:
        with pytest.raises(InstrumentError, match="1,000,001 samples; the arb memory holds 8 to "
                                                  "1,000,000 points"):
            source.load_waveform(np.zeros(1_000_001), 1e5)
    finally:
        source.close()
    peer.expect_all()


# --------------------------------------------------------------------------- amplifier
AMP_IDN = b"fsi-lab,PA25E,0001,1.0\n"
# the output state is read and the output goes off first, before the identity is known, and
# again once the queue is clear
AMP_OPEN = [(b"OUTP?\n", b"0\n"), (b"OUTP 0\n", None), (b"*IDN?\n", AMP_IDN),
            (b"*CLS\n", None)] + checked(b"OUTP 0")


def _amplifier(peer, context=None, **values):
    return shaker_amplifier.PLUGIN.open(peer.address, settings(shaker_amplifier, **values),
                                        {} if context is None else context)


def test_amplifier_output_goes_off_even_when_the_identity_is_unexpected(tcp_peer):
    peer = tcp_peer([(b"OUTP?\n", b"1\n"), (b"OUTP 0\n", None),
                     (b"*IDN?\n", b"PA25E amplifier v2\n")])
    with pytest.raises(InstrumentError, match="unexpected identity 'PA25E amplifier v2'; "
                                              "expected <maker>,<model>,<serial>,<firmware> "
                                              r"\(OUTP 0 was sent first\)"):
        _amplifier(peer)
    peer.expect_all()


@pytest.mark.parametrize("context, resets", [({}, True), ({"purpose": "run"}, True),
                                             ({"purpose": "outside-run"}, False)])
def test_amplifier_clears_interlocks_only_when_opened_for_a_run(tcp_peer, context, resets):
    peer = tcp_peer(AMP_OPEN + (checked(b"INTL:RES") if resets else []))
    _amplifier(peer, context, reset_interlocks=True).close()
    peer.expect_all()


def test_amplifier_gain_output_and_safe_state(tcp_peer):
    script = AMP_OPEN + checked(b"GAIN 2.5") + [(b"GAIN?\n", b"2.5\n")]
    script += [(b"STAT:INTL?\n", b"0\n"), (b"SYST:WDOG:TIM 60\n", None),
               (b"SYST:WDOG ON\n", None), NO_ERROR]  # fed every 15 s: not within this test
    script += checked(b"OUTP 1") + [(b"OUTP?\n", b"1\n")]
    script += [(b"OUTP 0\n", None), (b"SYST:WDOG OFF\n", None), (b"OUTP?\n", b"0\n")]
    script += [(b"OUTP?\n", b"0\n"), (b"GAIN?\n", b"2.5\n"), (b"STAT:INTL?\n", b"0\n"),
               (b"MEAS:CURR?\n", b"0.000000E+00\n")]
    peer = tcp_peer(script)
    amplifier = _amplifier(peer, watchdog_s=60.0)
    try:
        amplifier.set_gain(2.5)
        amplifier.enable_output(True)
        assert amplifier.settings()["watchdog"] == "armed"
        amplifier.safe_state()
        assert amplifier.read_state() == {"output_enabled": False, "gain": 2.5,
                                          "interlocks": {}, "current_a": 0.0}
    finally:
        amplifier.close()
    peer.expect_all()


def test_amplifier_decodes_the_interlock_bitfield_and_refuses_output(tcp_peer):
    script = AMP_OPEN + checked(b"INTL:RES")
    script += [(b"STAT:INTL?\n", b"17\n"), (b"STAT:INTL?\n", b"32\n")]
    peer = tcp_peer(script)
    amplifier = _amplifier(peer, reset_interlocks=True)
    try:
        assert amplifier.interlocks() == {
            "over_travel": True, "supply_fault": False, "over_temperature": False,
            "over_current": False, "e_stop": True, "input_clip": False, "watchdog": False}
        with pytest.raises(InstrumentError, match="output on refused: interlock input_clip is "
                                                  "active; remove its cause, then clear it "
                                                  "with INTL:RES"):
            amplifier.enable_output(True)
    finally:
        amplifier.close()
    peer.expect_all()  # no OUTP 1 was sent


def test_amplifier_reports_an_output_found_on_and_works_without_a_watchdog(tcp_peer):
    script = [(b"OUTP?\n", b"1\n"), (b"OUTP 0\n", None), (b"*IDN?\n", AMP_IDN),
              (b"*CLS\n", None)] + checked(b"OUTP 0")
    script += [(b"STAT:INTL?\n", b"0\n"), (b"SYST:WDOG:TIM 1\n", None),
               (b"SYST:WDOG ON\n", None), (b"SYST:ERR?\n", b'-113,"Undefined header"\n'),
               (b"SYST:ERR?\n", b'-113,"Undefined header"\n'), NO_ERROR]
    script += checked(b"OUTP 1") + [(b"OUTP?\n", b"1\n")]
    script += [(b"OUTP 0\n", None), (b"OUTP?\n", b"0\n")]
    peer = tcp_peer(script)
    amplifier = _amplifier(peer)
    try:
        assert amplifier.found_on is True
        amplifier.enable_output(True)
        assert amplifier.settings()["watchdog"] == "not offered"
        amplifier.safe_state()
    finally:
        amplifier.close()
    peer.expect_all()


def test_amplifier_rejects_a_gain_that_reads_back_differently(tcp_peer):
    peer = tcp_peer(AMP_OPEN + checked(b"GAIN 3") + [(b"GAIN?\n", b"1.5\n")])
    amplifier = _amplifier(peer)
    try:
        with pytest.raises(InstrumentError, match="gain reads back 1.5 after GAIN 3"):
            amplifier.set_gain(3.0)
    finally:
        amplifier.close()
    peer.expect_all()


def test_amplifier_flags_a_garbled_bitfield(tcp_peer):
    peer = tcp_peer(AMP_OPEN + [(b"STAT:INTL?\n", b"\xb1\x37\n")])
    amplifier = _amplifier(peer)
    try:
        with pytest.raises(InstrumentError, match=r"garbled reply b'\\xb17"):
            amplifier.interlocks()
    finally:
        amplifier.close()
    peer.expect_all()


# --------------------------------------------------------------------------- digitiser
DAQ_OPEN = [(b"*IDN?\n", b"fsi-lab,DSA4,0002,1.0\n"), (b"*RST\n", None), (b"*CLS\n", None)]
DAQ_OPEN += checked(b"FORM:BORD SWAP")


def daq_configure(rate: bytes = b"1000", points: bytes = b"4") -> list:
    """What configuring inputs 1 and 3 (10 V, no IEPE) at ``rate`` for ``points`` exchanges."""
    script = checked(b"INP1:STAT ON", b"INP2:STAT OFF", b"INP3:STAT ON", b"INP4:STAT OFF")
    for n in (b"1", b"3"):
        script += checked(b"INP" + n + b":RANG 10", b"INP" + n + b":IEPE OFF")
        script += [(b"INP" + n + b":RANG?\n", b"10\n"),
                   (b"INP" + n + b":SCAL?\n", b"1.192092896E-06\n")]
    script += checked(b"ACQ:SRAT " + rate) + [(b"ACQ:SRAT?\n", rate + b".000000\n")]
    return script + checked(b"ACQ:POIN " + points, b"TRIG:SOUR EXT")


DAQ_CONFIGURE = daq_configure()


def _daq(peer):
    return scpi_daq.PLUGIN.open(peer.address, settings(scpi_daq, block_duration=0.002), {})


def _block(codes) -> bytes:
    payload = np.asarray(codes, dtype="<i4").tobytes()
    length = str(len(payload)).encode()
    return b"#" + str(len(length)).encode() + length + payload + b"\n"


def test_daq_configures_arms_and_streams_int32_blocks(tcp_peer):
    first, second = [[100, -200], [300, 400]], [[-5, 6], [7, -8]]
    script = DAQ_OPEN + DAQ_CONFIGURE + checked(b"INIT")
    script += [(b"ACQ:STAT?\n", b"WTRG,0,0\n"), (b"ACQ:STAT?\n", b"RUN,2,0\n"),
               (b"FETC? 2\n", _block(first)), (b"ACQ:STAT?\n", b"RUN,0,0\n"),
               (b"ACQ:STAT?\n", b"DONE,2,0\n"), (b"FETC? 2\n", _block(second)),
               (b"ACQ:STAT?\n", b"DONE,0,0\n")]
    script += [(b"ABOR\n", None), (b"ACQ:STAT?\n", b"IDLE,0,0\n")]
    peer = tcp_peer(script)
    daq = _daq(peer)
    try:
        assert daq.configure({"drive": 1, "vel": 3}, 1000.0, 0.004) == 1000.0
        daq.arm()
        scale = 1.192092896e-06
        block = daq.read_block(2.0)
        np.testing.assert_allclose(block["drive"], [100 * scale, 300 * scale])
        np.testing.assert_allclose(block["vel"], [-200 * scale, 400 * scale])
        block = daq.read_block(2.0)
        np.testing.assert_allclose(block["vel"], [6 * scale, -8 * scale])
        assert daq.read_block(2.0) is None  # complete: nothing more is asked
        daq.safe_state()
        assert daq.read_state() == {"state": "IDLE", "samples_fetched": 4,
                                    "overloaded_inputs": []}
        assert daq.settings()["volts_per_code"] == {"1": scale, "3": scale}
    finally:
        daq.close()
    peer.expect_all()


def test_daq_stops_at_an_overloaded_input_and_names_it(tcp_peer):
    script = DAQ_OPEN + DAQ_CONFIGURE + checked(b"INIT")
    script += [(b"ACQ:STAT?\n", b"RUN,2,0\n"), (b"FETC? 2\n", _block([[1, 2], [3, 4]])),
               (b"ACQ:STAT?\n", b"RUN,0,4\n")]
    peer = tcp_peer(script)
    daq = _daq(peer)
    try:
        daq.configure({"drive": 1, "vel": 3}, 1000.0, 0.004)
        daq.arm()
        with pytest.raises(InstrumentError, match=r"overload on input 3 \(vel, range 10.0 V\) "
                                                  "after 0 samples"):
            daq.read_block(2.0)
    finally:
        daq.close()
    peer.expect_all()


@pytest.mark.parametrize("reply, message", [
    (b"\xa32" + _block([[1, 2]])[2:],
     r"garbled reply: reply starts with b'\\xa32', not an IEEE 488.2 block"),
    (_block([[1, 2], [3, 4]])[:-1] + b";",
     r"garbled reply: block not followed by a newline but by b';'"),
], ids=["header", "terminator"])
def test_daq_rejects_a_garbled_block(tcp_peer, reply, message):
    script = DAQ_OPEN + DAQ_CONFIGURE + checked(b"INIT")
    script += [(b"ACQ:STAT?\n", b"RUN,2,0\n"), (b"FETC? 2\n", reply)]
    peer = tcp_peer(script)
    daq = _daq(peer)
    try:
        daq.configure({"drive": 1, "vel": 3}, 1000.0, 0.004)
        daq.arm()
        with pytest.raises(InstrumentError, match=message):
            daq.read_block(2.0)
    finally:
        daq.close()
    peer.expect_all()


def test_daq_reads_a_block_in_one_read_even_when_its_data_is_all_newline_bytes(tcp_peer,
                                                                               monkeypatch):
    """A 0.1 s block of two inputs at 204.8 kS/s (160 kB) whose codes are made of newline bytes,
    the read termination character: the driver asks the VISA library for the data in one read
    after the header, not one read per newline (pyvisa-py's socket session ends a read at each
    while the termination character is enabled), and the next query reads its line again."""
    codes = np.full((20480, 2), 0x0A0A0A0A, dtype="<i4")
    codes[::7, 1] = -0x0A0A0A0B
    script = DAQ_OPEN + daq_configure(b"204800", b"20480") + checked(b"INIT")
    script += [(b"ACQ:STAT?\n", b"RUN,20480,0\n"), (b"FETC? 20480\n", _block(codes)),
               (b"ACQ:STAT?\n", b"DONE,0,0\n")]
    peer = tcp_peer(script)
    daq = scpi_daq.PLUGIN.open(peer.address, settings(scpi_daq, block_duration=0.1), {})
    try:
        daq.configure({"drive": 1, "vel": 3}, 204800.0, 0.1)
        daq.arm()
        visalib = daq.link._resource.visalib
        asked = []

        def counted(session, count):
            asked.append(count)
            return read(session, count)

        read = visalib.read
        monkeypatch.setattr(visalib, "read", counted)
        block = daq.read_block(2.0)
    finally:
        daq.close()
    peer.expect_all()
    scale = 1.192092896e-06
    np.testing.assert_array_equal(block["drive"], codes[:, 0] * scale)
    np.testing.assert_array_equal(block["vel"], codes[:, 1] * scale)
    # the status reply, the block's "#6", "163840", its data with the newline; the status reply
    assert len(asked) == 5, asked
    assert asked[1:4] == [2, 6, 163841]


def test_daq_names_a_block_cut_short(tcp_peer):
    script = DAQ_OPEN + DAQ_CONFIGURE + checked(b"INIT")
    script += [(b"ACQ:STAT?\n", b"RUN,2,0\n"), (b"FETC? 2\n", _block([[1, 2], [3, 4]])[:12])]
    peer = tcp_peer(script)
    daq = scpi_daq.PLUGIN.open(peer.address, settings(scpi_daq, block_duration=0.002,
                                                      timeout_s=0.3), {})
    try:
        daq.configure({"drive": 1, "vel": 3}, 1000.0, 0.004)
        daq.arm()
        with pytest.raises(InstrumentError,
                           match=r"^scpi-daq at TCPIP0::127\.0\.0\.1::\d+::SOCKET: "
                                                  r"no reply within 0\.3 s \(after sending "
                                                  r"'FETC\? 2'\)$"):
            daq.read_block(2.0)
        assert daq.link.broken  # the safe state reconnects
    finally:
        daq.close()
    peer.expect_all()


def test_daq_refuses_an_input_it_does_not_have(tcp_peer):
    peer = tcp_peer(DAQ_OPEN)
    daq = _daq(peer)
    try:
        with pytest.raises(InstrumentError, match="channel 'x' uses input 7; this digitiser has "
                                                  "inputs 1 to 4"):
            daq.configure({"x": 7}, 1000.0, 1.0)
    finally:
        daq.close()
    peer.expect_all()


# --------------------------------------------------------------------------- Polytec
def _polytec_open(decoder_reply=b"VD-09\n", readback=b"25mm/s/V\n", delay=b"8.16 us\n"):
    script = [(b"Set,Interface,0,Echo,Off\n", None),
              (b"Set,Interface,0,Acknowledge,Off\n", None),
              (b"Get,Interface,0,Echo\n", b"Off\n"),
              (b"GetDevInfo,Controller,0,Name\n", b"OFV-5000\n"),
              (b"Set,Controller,0,Remote,LLO\n", None),
              (b"Get,Controller,0,Remote\n", b"LLO\n"),
              (b"GetDevInfo,VeloDec,0,Name\n", b"Not Installed\n"),
              (b"GetDevInfo,VeloDec,1,Name\n", decoder_reply),
              (b"GetDevInfo,VeloDec,2,Name\n", b"Not Installed\n"),
              (b"GetDevInfo,VeloDec,3,Name\n", b"Not Installed\n"),
              (b"GetDevInfo,VeloDec,1,Range\n", b"3,5mm/s/V,25mm/s/V,125mm/s/V\n"),
              (b"Set,VeloDec,1,Range,25mm/s/V\n", None),
              (b"Get,VeloDec,1,Range\n", readback)]
    if delay is not None:
        script.append((b"Get,VeloDec,1,SignalDelay\n", delay))
    return script


LOCAL = b"Set,Controller,0,Remote,Local\n"  # the front panel given back on closing


def test_polytec_tolerates_echo_and_acknowledge_and_reads_a_plain_range_list(pty_peer):
    echoed = [(b"Set,Interface,0,Echo,Off\n", b"Set,Interface,0,Echo,Off\nOK\n"),
              (b"Set,Interface,0,Acknowledge,Off\n", None),
              (b"Get,Interface,0,Echo\n", b"Off\n")]
    script = echoed + _polytec_open()[3:]
    script[10] = (b"GetDevInfo,VeloDec,1,Range\n", b"5mm/s/V,25mm/s/V,125mm/s/V\n")
    peer = pty_peer(script + [(LOCAL, None)])
    vibrometer = _vibrometer(peer)
    try:
        assert vibrometer.settings()["available_ranges"] == ["5mm/s/V", "25mm/s/V", "125mm/s/V"]
    finally:
        vibrometer.close()
    peer.expect_all()


def test_polytec_skips_an_echo_of_its_question(pty_peer):
    script = _polytec_open()
    script[3] = (b"GetDevInfo,Controller,0,Name\n", b"GetDevInfo,Controller,0,Name\nOFV-5000\n")
    peer = pty_peer(script + [(LOCAL, None)])
    vibrometer = _vibrometer(peer)
    try:
        assert vibrometer.controller == "OFV-5000"
    finally:
        vibrometer.close()
    peer.expect_all()


def _vibrometer(peer, **values):
    values.setdefault("range", "25mm/s/V")
    return polytec.PLUGIN.open(peer.address, settings(polytec, **values), {})


def test_polytec_discovers_the_decoder_sets_and_reads_back_the_range(pty_peer):
    peer = pty_peer(_polytec_open() + [(b"Get,VeloDec,1,Range\n", b"25mm/s/V\n"),
                                       (LOCAL, None)])
    vibrometer = _vibrometer(peer)
    try:
        assert vibrometer.identify() == "Polytec OFV-5000, velocity decoder VD-09 (VeloDec,1)"
        assert vibrometer.sensitivity() == pytest.approx(40.0)  # V per m/s at 25 mm/s/V
        assert vibrometer.delay() == pytest.approx(8.16e-6)
        vibrometer.safe_state()  # sends nothing
        assert vibrometer.read_state() == {"range": "25mm/s/V"}
        assert vibrometer.settings()["available_ranges"] == ["5mm/s/V", "25mm/s/V", "125mm/s/V"]
    finally:
        vibrometer.close()
    peer.expect_all()


def test_polytec_reports_a_set_that_did_not_take(pty_peer):
    peer = pty_peer(_polytec_open(readback=b"125mm/s/V\n", delay=None))
    with pytest.raises(InstrumentError, match="VeloDec,1,Range reads back '125mm/s/V' after "
                                              r"setting '25mm/s/V' \(is the controller in "
                                              "remote mode"):
        _vibrometer(peer)
    peer.expect_all()


def test_polytec_names_the_decoders_it_found(pty_peer):
    script = _polytec_open()[:10]
    peer = pty_peer(script)
    with pytest.raises(InstrumentError, match=r"no velocity decoder 'VD-07'; installed: VD-09 "
                                              r"\(VeloDec,1\)"):
        _vibrometer(peer, decoder="VD-07")
    peer.expect_all()


def test_polytec_takes_the_delay_from_the_profile_when_given(pty_peer):
    peer = pty_peer(_polytec_open(delay=None) + [(LOCAL, None)])
    vibrometer = _vibrometer(peer, delay_s=0.002)
    try:
        assert vibrometer.delay() == 0.002
        assert vibrometer.settings()["signal_delay_source"] == "profile"
    finally:
        vibrometer.close()
    peer.expect_all()


@pytest.mark.parametrize("text, seconds", [("8.16 us", 8.16e-6), ("1100.00us", 1.1e-3),
                                           ("1.1ms", 1.1e-3), ("0 s", 0.0)])
def test_polytec_delay_units(text, seconds):
    assert polytec.delay_seconds(text) == pytest.approx(seconds)


@pytest.mark.parametrize("text, value", [("125mm/s/V", 0.125), ("1m/s/V", 1.0),
                                         ("500um/s/V", 5e-4)])
def test_polytec_range_units(text, value):
    assert polytec.range_metres_per_volt(text) == pytest.approx(value)
