"""The simulated instruments' SCPI against the standards: byte-exact binary blocks, framing in
linear time, capped error texts, a bounded error queue and the IEEE 488.2 mandatory common
commands with their status model, on every simulated SCPI instrument, through pyvisa-py."""

import numpy as np
import pytest
from benchkit import sim_bench

from fsi_lab.instruments.sim import scpi
from fsi_lab.instruments.sim.scpi import MAX_ERROR_TEXT, ErrorQueue, Framer

SCPI_ROLES = ("source", "amplifier", "acquisition")


@pytest.mark.parametrize("last", [0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x20])
def test_a_block_ending_in_white_space_keeps_every_byte(last):
    payload = bytes(range(0x30, 0x37)) + bytes([last])
    message = b"DATA:ARB X,#18" + payload
    framer = Framer()
    assert framer.feed(message + b"\r\n") == [message]
    errors = ErrorQueue()
    commands = scpi.CommandSet(errors)
    seen = []
    commands.add("DATA:ARBitrary", lambda a, s: seen.append(a))
    assert commands.run(message + b"  ") is None
    assert seen == [b"X,#18" + payload] and len(errors) == 0


def test_a_carriage_return_outside_a_block_is_dropped():
    assert Framer().feed(b"*IDN?\r\nOUTP 1\r\n") == [b"*IDN?", b"OUTP 1"]


class _CountingPattern:
    """A regular expression that counts the bytes its searches may look at."""

    def __init__(self, pattern):
        self.pattern = pattern
        self.examined = 0

    def search(self, buffer, pos):
        match = self.pattern.search(buffer, pos)
        self.examined += (match.end() if match else len(buffer)) - pos
        return match


def test_a_long_line_read_in_pieces_is_examined_once(monkeypatch):
    counting = _CountingPattern(scpi._FRAME_SPECIAL)
    monkeypatch.setattr(scpi, "_FRAME_SPECIAL", counting)
    line = b"DATA:ARB:DAC X," + b"12345," * 400_000 + b"1\n"  # 2.4 MB, as PyMeasure sends it
    framer = Framer()
    messages = []
    for start in range(0, len(line), 1 << 16):
        messages += framer.feed(line[start:start + (1 << 16)])
    assert messages == [line[:-1]]
    assert counting.examined <= len(line)  # a rescan per read would make it ~19 times that


def test_a_block_payload_is_skipped_not_examined(monkeypatch):
    counting = _CountingPattern(scpi._FRAME_SPECIAL)
    monkeypatch.setattr(scpi, "_FRAME_SPECIAL", counting)
    payload = b"#\n;'\"" * 200_000
    message = b"DATA:ARB X,#7" + str(len(payload)).encode() + payload
    framer = Framer()
    out, reads = [], 0
    for start in range(0, len(message) + 1, 4096):
        out += framer.feed((message + b"\n")[start:start + 4096])
        reads += 1
    assert out == [message]
    assert counting.examined < 2 * reads + 100  # the '#' looked at once per read, not the bytes


def test_error_texts_are_capped_and_the_queue_is_bounded():
    errors = ErrorQueue()
    commands = scpi.CommandSet(errors)
    commands.add("SYSTem:ERRor?", lambda a, s: errors.pop())
    commands.run(b"X" * 300_000 + b" 1")
    reply = commands.run(b"SYST:ERR?").decode()
    assert reply.startswith('-113,"Undefined header; XXX')
    assert len(reply.split(",", 1)[1].strip().strip('"')) <= MAX_ERROR_TEXT
    for k in range(ErrorQueue.LIMIT + 5):
        commands.run(f"NOPE{k}".encode())
    replies = [commands.run(b"SYST:ERR?").decode().strip() for _ in range(ErrorQueue.LIMIT + 1)]
    assert replies[0].startswith('-113,"Undefined header; NOPE0"')
    assert replies[ErrorQueue.LIMIT - 2].startswith("-113")
    assert replies[ErrorQueue.LIMIT - 1] == '-350,"Queue overflow"'
    assert replies[ErrorQueue.LIMIT] == '+0,"No error"'


def test_numbers_take_unit_suffixes_and_limit_words():
    assert scpi.number(b"100 mV", unit="V") == pytest.approx(0.1)
    assert scpi.number(b"1.5KHZ", unit="HZ") == pytest.approx(1500.0)
    assert scpi.number(b"2 MHz", unit="HZ") == pytest.approx(2e6)
    assert scpi.number(b"MAX", 0, 10, words=scpi.limits(0, 10, 1)) == 10
    with pytest.raises(scpi.ScpiError) as info:
        scpi.number(b"3 A", unit="V")
    assert info.value.code == -131


@pytest.fixture
def visa():
    import pyvisa

    manager = pyvisa.ResourceManager("@py")
    opened = []

    def open_(address):
        resource = manager.open_resource(address, open_timeout=2000)
        resource.timeout = 2000
        resource.read_termination = resource.write_termination = "\n"
        opened.append(resource)
        return resource

    yield open_
    for resource in opened:
        resource.close()


@pytest.mark.parametrize("role", SCPI_ROLES)
def test_every_scpi_instrument_has_the_ieee_488_2_common_commands(sim_bench, visa, role):
    bench = sim_bench()
    inst = visa(bench.addresses[role])
    assert inst.query("*ESR?") == "128"  # power on
    assert inst.query("*ESR?") == "0"  # cleared by the reading
    assert inst.query("*TST?") == "0"
    assert inst.query("*OPC?") == "1"
    inst.write("*OPC")
    assert inst.query("*ESR?") == "1"
    inst.write("*WAI")
    assert inst.query("*STB?") == "0"
    inst.write("NO:SUCH:COMMAND")
    assert int(inst.query("*STB?")) == 4  # error queue not empty
    inst.write("*ESE 32;*SRE 32")
    assert (inst.query("*ESE?"), inst.query("*SRE?")) == ("32", "32")
    assert int(inst.query("*STB?")) == 4 | 32 | 64  # event summary, then master summary
    assert int(inst.query("*ESR?")) == 32  # command error
    assert inst.query("SYST:ERR?").startswith('-113,"Undefined header')
    assert inst.query("*STB?") == "0"
    inst.write("*ESE 300")
    assert inst.query("SYST:ERR?").startswith("-222")
    assert int(inst.query("*ESR?")) == 16  # execution error
    inst.write("BAD:ONE;*CLS")
    assert inst.query("SYST:ERR?") == '+0,"No error"' and inst.query("*ESR?") == "0"
    assert inst.query("*ESE?") == "32"  # *CLS keeps the enables
    assert inst.query("*IDN?;*OPC?").endswith(";1")


def test_a_block_upload_ending_in_white_space_reaches_the_generator_exactly(sim_bench, visa):
    bench = sim_bench()
    inst = visa(bench.addresses["source"])
    points = np.linspace(-1, 1, 64).astype("<f4")
    points[-1] = np.frombuffer(b"\x00\x00\x20\x0d", "<f4")[0]  # tiny, ends in CR
    payload = points.tobytes()
    assert payload[-1:] == b"\r"
    inst.write("FORM:BORD SWAP")
    inst.write_raw(b"DATA:ARB WS,#3" + str(len(payload)).encode() + payload + b"\n")
    assert inst.query("SYST:ERR?") == '+0,"No error"'
    stored = bench.source.state.arbs["WS"]
    assert stored.size == 64
