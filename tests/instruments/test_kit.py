"""The instrument kit: declared settings, and the bytes its SCPI output template exchanges
(through pyvisa-py with a scripted peer on 127.0.0.1)."""

import pytest
from benchkit import tcp_peer

from fsi_lab.contract import OutputState
from fsi_lab.errors import InstrumentError
from fsi_lab.instruments.kit import ScpiOutput, Setting, connect
from fsi_lab.params import REQUIRED

NO_ERROR = (b"SYST:ERR?\n", b'+0,"No error"\n')
IDN = b"Acme,PA-1,0001,1.0\n"


class Generator(ScpiOutput):
    NAME = "acme-gen"
    output = Setting("OUTP{channel}", "bool")
    level = Setting("SOUR{channel}:VOLT:OFFS", "float", "V", minimum=-5.0, maximum=5.0,
                    fmt="g", accepted="the offset stays within +-5 V", help="DC offset.")
    shape = Setting("SOUR{channel}:FUNC", "str", choices={"sine": "SIN", "dc": "DC"})
    name = Setting("SOUR{channel}:FUNC:ARB", "str")
    #: the same offset declared without bounds: the instrument has the last word
    unbounded = Setting("SOUR{channel}:VOLT:OFFS", "float", "V", fmt="g",
                        accepted="the offset stays within +-5 V")
    points = Setting("INP{input}:POIN", "int", minimum=1)

    def __init__(self, link, identity, channel=2):
        super().__init__(link, identity)
        self.channel = channel

    def switch_off(self):
        super().switch_off()
        self.set("level", 0.0, check=False)

    def state_details(self, output_enabled):
        return {"level_v": self.level}


def test_a_setting_writes_checks_and_reads_its_values():
    level = Generator.level
    assert level.command_for(1.25, channel=1) == "SOUR1:VOLT:OFFS 1.25"
    assert level.query_for(channel=2) == "SOUR2:VOLT:OFFS?"
    assert level.generic(0.0) == "SOUR:VOLT:OFFS 0" and level.fields == ("channel",)
    with pytest.raises(ValueError, match=r"level = 7: accepted a number >= -5 V and <= 5 V"):
        level.command_for(7, channel=1)
    with pytest.raises(ValueError, match="level = 'high': accepted a number"):
        level.check("high")
    assert Generator.output.command_for(True, channel=1) == "OUTP1 ON"
    assert Generator.output.parse("1") is True and Generator.output.parse("OFF") is False
    assert Generator.shape.command_for("sine", channel=1) == "SOUR1:FUNC SIN"
    assert Generator.shape.parse("dc") == "dc"
    with pytest.raises(ValueError, match="expected one of SIN, DC"):
        Generator.shape.parse("SQU")
    with pytest.raises(ValueError, match="accepted one word of printable ASCII"):
        Generator.name.check("two words")
    assert Generator.points.parse("+12") == 12
    with pytest.raises(ValueError, match="expected an integer"):
        Generator.points.parse("1.5")


def test_a_setting_is_the_profile_parameter_that_gives_it():
    param = Generator.level.param(REQUIRED)
    assert (param.name, param.type, param.unit, param.minimum, param.maximum, param.help) == \
        ("level", "float", "V", -5.0, 5.0, "DC offset.")
    assert Generator.shape.param("sine", name="waveform").choices == ("sine", "dc")


def test_the_output_template_exchanges_these_bytes(tcp_peer):
    script = [(b"OUTP2?\n", b"1\n"), (b"OUTP2 OFF\n", None), (b"*IDN?\n", IDN), (b"*CLS\n", None),
              (b"OUTP2 OFF\n", None), NO_ERROR,
              (b"SOUR2:VOLT:OFFS 1.5\n", None), NO_ERROR,
              (b"SOUR2:VOLT:OFFS 9\n", None), (b"SYST:ERR?\n", b'-222,"Data out of range"\n'),
              NO_ERROR,
              (b"OUTP2 OFF\n", None), (b"SOUR2:VOLT:OFFS 0\n", None), (b"OUTP2?\n", b"0\n"),
              (b"OUTP2?\n", b"0\n"), (b"SOUR2:VOLT:OFFS?\n", b"+0.0E+00\n")]
    peer = tcp_peer(script)
    link = connect("acme-gen", "source", peer.address, {"timeout_s": 2.0}, {})
    identity, found_on = Generator.take_over(link, channel=2)
    generator = Generator(link, identity)
    try:
        assert (identity, found_on) == (IDN.decode().strip(), True)
        generator.level = 1.5
        with pytest.raises(InstrumentError, match=r"acme-gen at .*'SOUR2:VOLT:OFFS 9' was "
                                                  r"refused: -222,\"Data out of range\"; "
                                                  "the offset stays within"):
            generator.unbounded = 9
        with pytest.raises(InstrumentError, match="acme-gen at .*: level = 6"):
            generator.level = 6  # refused before anything is sent
        with pytest.raises(InstrumentError, match=r"setting 'points' needs input= "
                                                  r"\(INP\{input\}:POIN\)"):
            generator.points = 3
        generator.safe_state()
        state = generator.read_state()
        assert isinstance(state, OutputState) and state == {"output_enabled": False,
                                                            "level_v": 0.0}
    finally:
        generator.close()
    peer.expect_all()


def test_an_identity_that_is_not_one_names_what_was_sent_first(tcp_peer):
    peer = tcp_peer([(b"OUTP1?\n", b"0\n"), (b"OUTP1 OFF\n", None), (b"*IDN?\n", b"PA-1\n")])
    link = connect("acme-gen", "source", peer.address, {"timeout_s": 2.0}, {})
    try:
        with pytest.raises(InstrumentError, match=r"acme-gen at .*: unexpected identity 'PA-1'; "
                                                  r"expected <maker>,<model>,<serial>,<firmware>"
                                                  r" \(OUTP OFF was sent first\)"):
            Generator.take_over(link, channel=1)
    finally:
        link.close()
    peer.expect_all()
