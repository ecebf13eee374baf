"""SCPI on the simulated instruments' side: framing, header forms, errors, blocks."""

import pytest

from fsi_lab.instruments.sim import scpi
from fsi_lab.instruments.sim.faults import FaultPlan, garble
from fsi_lab.instruments.sim.scpi import CommandSet, ErrorQueue, ScpiError


def test_messages_end_at_newlines_outside_binary_blocks():
    block = b"#15a\nb;c"
    buffer = bytearray(b"*IDN?\r\nDATA:ARB X," + block + b"\nOUTP 1;OUTP?\nINCOMPL")
    assert scpi.take_messages(buffer) == [b"*IDN?", b"DATA:ARB X," + block, b"OUTP 1;OUTP?"]
    assert buffer == bytearray(b"INCOMPL")


def test_an_incomplete_block_waits_for_its_bytes():
    buffer = bytearray(b"DATA:ARB X,#210abc\n")
    assert scpi.take_messages(buffer) == []
    buffer += b"defghij\n"
    assert scpi.take_messages(buffer) == [b"DATA:ARB X,#210abc\ndefghij"]


def _commands():
    errors = ErrorQueue()
    commands = CommandSet(errors)
    seen = []
    commands.add("[SOURce#:]FUNCtion:ARBitrary:SRATe", lambda a, s: seen.append((a, s)))
    commands.add("[SOURce#:]FUNCtion:ARBitrary:SRATe?", lambda a, s: "1000")
    commands.add("SYSTem:ERRor[:NEXT]?", lambda a, s: errors.pop())
    commands.add("*IDN?", lambda a, s: "a,b,c,d")
    commands.add("VOLTage", lambda a, s: scpi.number(a, 0, 10))
    return commands, seen


@pytest.mark.parametrize("header, suffix", [
    ("SOUR1:FUNC:ARB:SRAT", 1), ("source2:function:arbitrary:srate", 2),
    ("FUNC:ARB:SRAT", None), (":SOURce:FUNCtion:ARBitrary:SRATe", None)])
def test_short_long_and_optional_header_forms(header, suffix):
    commands, seen = _commands()
    assert commands.run(header.encode() + b" 40000") is None
    assert seen == [(b"40000", [suffix, None, None, None])]


def test_queries_are_joined_and_unknown_headers_queue_an_error():
    commands, _ = _commands()
    assert commands.run(b"*IDN?;FUNC:ARB:SRAT?") == b"a,b,c,d;1000\n"
    assert commands.run(b"FUNC:ARBX:SRAT 1") is None
    assert commands.run(b"VOLT 11") is None
    assert commands.run(b"SYST:ERR?") == b'-113,"Undefined header; FUNC:ARBX:SRAT"\n'
    assert commands.run(b"SYST:ERR?") == b'-222,"Data out of range; 11 outside 0 to 10"\n'
    assert commands.run(b"SYST:ERR?") == b'+0,"No error"\n'


def test_block_payload_must_match_its_length():
    assert scpi.parse_ieee_block(b"#15abcde") == b"abcde"
    assert scpi.ieee_block(b"abcde") == b"#15abcde"
    with pytest.raises(ScpiError) as info:
        scpi.parse_ieee_block(b"#16abcde")
    assert info.value.code == -160


def test_link_faults_happen_at_their_record_time_and_one_shot_faults_once():
    plan = FaultPlan("drop", after_s=0.5, target="amplifier")
    assert plan.link_action("amplifier", None) is None
    assert plan.link_action("amplifier", 0.4) is None
    assert plan.link_action("source", 0.6) is None
    assert plan.link_action("amplifier", 0.6) == "drop"
    assert plan.link_action("amplifier", 0.7) is None
    plan = FaultPlan("timeout", after_s=0.5)
    assert plan.link_action("acquisition", 0.5) == "timeout"
    assert plan.link_action("acquisition", 0.9) == "timeout"
    plan = FaultPlan("garble", 0.0, "vibrometer")
    assert plan.garble_now("vibrometer", 0.0) and not plan.garble_now("vibrometer", 1.0)


def test_garbling_breaks_the_reply_but_keeps_the_line_end():
    assert garble(b"+0,\"No error\"\n") != b"+0,\"No error\"\n"
    assert garble(b"1\n").endswith(b"\n") and garble(b"1\n")[:1] == b"\xb1"


def test_a_fault_plan_refuses_unknown_faults_and_targets():
    with pytest.raises(ValueError, match="expected one of none, timeout"):
        FaultPlan("smoke")
    with pytest.raises(ValueError, match="fault target 'camera'"):
        FaultPlan("drop", 1.0, "camera")
