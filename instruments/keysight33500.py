"""Keysight 33500B-series arbitrary waveform generator (signal source) over VISA, SCPI.

The drive waveform is uploaded as an arbitrary waveform: the samples divided by their peak, as
an IEEE 488.2 definite-length block of float32 in little-endian order (``FORM:BORD SWAP``),
played at ``FUNC:ARB:SRAT`` with an amplitude of twice the peak (Vpp, high-impedance load; a peak
below 1 mV is played at the smallest amplitude, 2 mVpp, with the points scaled down) and no
offset, as one triggered burst. Between bursts a 33500 holds the arb's first point, so a waveform
that does not start at 0 V gets one 0 V point in front of it (one sample later; the settings say
so): the output rests at 0 V before and after the burst. The upload and the error check after it
are given the reply timeout plus the payload's transfer time (:func:`upload_timeout`). The trigger
output follows the channel in use (``OUTP:TRIG:SOUR CH<n>``; a one-channel model that does not
know the command is accepted on channel 1). ``start`` switches the output on and sends a bus trigger
(``*TRG``); the generator's trigger output marks t = 0 for a digitiser waiting for it.
``SYST:ERR?`` is read after every configuration step and any error stops the run with the
instrument's own message. The settings are declared once with the instrument kit
(:mod:`fsi_lab.instruments.kit`), which also gives the profile's ``sample_rate`` and
``arb_filter``, the take-over, the confirmed safe state and the state read back.

The generator has no watchdog of its own: the 33500B offers no communication timeout that
switches its output off, so a run that dies leaves it to the amplifier's watchdog (see
:mod:`~fsi_lab.instruments.shaker_amplifier`), which removes the shaker's drive whatever the
source plays, and to the burst resting at 0 V between triggers; the next command that opens
the bench reports an output it finds on.

Address: a VISA resource, e.g. ``TCPIP0::192.168.1.10::5025::SOCKET`` (or ``embedded`` for the
simulated bench).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from fsi_lab.contract import InstrumentPlugin, SignalSource
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.kit import ScpiOutput, Setting, connect
from fsi_lab.params import Param

NAME = "keysight33500"
ARB_NAME = "FSILAB"
MIN_POINTS = 8
MAX_POINTS = 1_000_000
MIN_VPP = 0.002
FILTERS = {"normal": "NORM", "step": "STEP", "off": "OFF"}
#: Slowest rate at which a 33500B takes in arb data (LAN, memory write), bytes/s: the time
#: allowed for an upload and its error check grows by the payload's size over this.
UPLOAD_BYTES_PER_S = 250e3


def upload_timeout(timeout_s: float, payload_bytes: int) -> float:
    """Time allowed for an arb upload and the ``SYST:ERR?`` after it, s: the reply timeout
    plus the payload's transfer at :data:`UPLOAD_BYTES_PER_S`."""
    return float(timeout_s) + payload_bytes / UPLOAD_BYTES_PER_S


def arb_points(wave: np.ndarray) -> tuple[np.ndarray, float]:
    """Arb points (float32, in -1..1) and the amplitude (Vpp) that play ``wave`` (V).

    The points are the samples divided by their peak, played at twice the peak in Vpp. A peak
    below half the instrument's smallest amplitude :data:`MIN_VPP` is played at ``MIN_VPP``
    with the points scaled down by ``2 peak / MIN_VPP``, so that the output still peaks at the
    requested voltage.
    """
    peak = float(np.max(np.abs(wave)))
    if 2.0 * peak >= MIN_VPP:
        points, amplitude = wave / peak, 2.0 * peak
    else:
        points, amplitude = wave * (2.0 / MIN_VPP), MIN_VPP
    points = points.astype("<f4")
    np.clip(points, -1.0, 1.0, out=points)
    return points, amplitude


class Keysight33500(ScpiOutput, SignalSource):
    """An open 33500B-class generator. Use :func:`open_source`."""

    NAME = NAME
    output = Setting("OUTP{channel}", "bool", help="Output relay of the channel closed.")
    byte_order = Setting("FORM:BORD", "str", choices=("NORM", "SWAP"),
                         help="Byte order of binary blocks (SWAP: little-endian).")
    function = Setting("SOUR{channel}:FUNC", "str",
                       choices=("SIN", "SQU", "TRI", "RAMP", "PULS", "PRBS", "NOIS", "ARB", "DC"),
                       help="Waveform function.")
    arb = Setting("SOUR{channel}:FUNC:ARB", "str", help="Name of the arb played.")
    sample_rate = Setting("SOUR{channel}:FUNC:ARB:SRAT", "float", "Hz", minimum=1e-6,
                          maximum=160e6, accepted="the arb sample rate must lie between "
                                                  "1 uSa/s and 160 MSa/s",
                          help="Arb sample rate the excitation is generated at (unset: the "
                               "run's rate).")
    arb_filter = Setting("SOUR{channel}:FUNC:ARB:FILT", "str", choices=FILTERS,
                         help="Arb output filter: 'normal' (band-limited), 'step' (smoothed "
                              "steps) or 'off' (sample and hold).")
    load = Setting("OUTP{channel}:LOAD", "str", choices=("INF",),
                   help="Load the amplitude refers to (INF: high impedance).")
    voltage_unit = Setting("SOUR{channel}:VOLT:UNIT", "str", choices=("VPP", "VRMS", "DBM"),
                           help="Unit of the amplitude.")
    offset = Setting("SOUR{channel}:VOLT:OFFS", "float", "V", minimum=-10.0, maximum=10.0,
                     help="DC offset.")
    amplitude = Setting("SOUR{channel}:VOLT", "float", "V", minimum=MIN_VPP, maximum=20.0,
                        accepted="the peak drive must stay within +-10 V into a "
                                 "high-impedance load",
                        help="Amplitude, peak to peak (VOLT:UNIT VPP).")
    burst_mode = Setting("SOUR{channel}:BURS:MODE", "str", choices=("TRIG", "GAT"),
                         help="Burst mode (TRIG: a burst per trigger).")
    burst_cycles = Setting("SOUR{channel}:BURS:NCYC", "int", minimum=1,
                           help="Cycles (arb plays) per burst.")
    trigger_source = Setting("TRIG{channel}:SOUR", "str", choices=("BUS", "IMM", "EXT", "TIM"),
                             help="What triggers a burst (BUS: *TRG).")
    burst = Setting("SOUR{channel}:BURS:STAT", "bool", help="Burst mode on.")
    trigger_output = Setting("OUTP:TRIG", "bool", help="Trigger output (sync) on.")
    trigger_output_source = Setting("OUTP:TRIG:SOUR", "str", choices=("CH1", "CH2"),
                                    help="Channel whose bursts the trigger output marks.")

    def __init__(self, link, settings: dict[str, Any], identity: str,
                 found_on: bool | None = None) -> None:
        super().__init__(link, identity)
        #: Whether the output was on when the generator was opened (None: it could not be read).
        self.found_on = found_on
        self.channel = int(settings["channel"])
        self._filter = settings["arb_filter"]
        self.filter = FILTERS[self._filter]
        self._loaded: dict[str, Any] = {}

    @property
    def _src(self) -> str:
        return f"SOUR{self.channel}:"

    def settings(self) -> dict[str, Any]:
        return {"visa_address": self.link.address, "arb_name": ARB_NAME, "channel": self.channel,
                "arb_filter": self.filter, "output_found_on": self.found_on, **self._loaded}

    def load_waveform(self, samples: np.ndarray, sample_rate: float) -> None:
        """Upload ``samples`` (V) to play once at ``sample_rate`` (Sa/s) per trigger."""
        wave = np.asarray(samples, dtype=float).ravel()
        where = self.where
        if not np.all(np.isfinite(wave)):
            raise InstrumentError(f"{where}: the waveform holds NaN or infinite samples")
        if wave.size > MAX_POINTS:
            raise InstrumentError(
                f"{where}: {wave.size:,} samples; the arb memory holds {MIN_POINTS} to "
                f"{MAX_POINTS:,} points: lower the source sample_rate or the excitation duration")
        lead = 1 if wave[0] != 0.0 else 0
        if lead:  # the burst rests at the first point: make it 0 V
            wave = np.concatenate([[0.0], wave])
        if wave.size > MAX_POINTS:
            raise InstrumentError(
                f"{where}: {wave.size:,} samples with the 0 V point the burst rests at; the arb "
                f"memory holds {MIN_POINTS} to {MAX_POINTS:,} points: lower the source "
                "sample_rate or the excitation duration")
        if wave.size < MIN_POINTS:
            wave = np.concatenate([wave, np.zeros(MIN_POINTS - wave.size)])
        points, amplitude = arb_points(wave)
        src, ch, link = self._src, self.channel, self.link
        self.output = False
        self.byte_order = "SWAP"
        link.send_checked(f"{src}DATA:VOL:CLE")
        payload = points.tobytes()
        length = str(len(payload))
        header = f"{src}DATA:ARB {ARB_NAME},#{len(length)}{length}"
        with link.timeout(upload_timeout(link.timeout_s, len(payload))):
            link.write_raw(header, header.encode("ascii") + payload + b"\n")
            link.check(f"the upload of {points.size} points ({header[:40]}...)",
                       f"the arb memory takes {MIN_POINTS} to {MAX_POINTS:,} points in -1..1")
        for name, value in (("function", "ARB"), ("arb", ARB_NAME), ("sample_rate", sample_rate),
                            ("arb_filter", self._filter), ("load", "INF"),
                            ("voltage_unit", "VPP"), ("offset", 0.0), ("amplitude", amplitude),
                            ("burst_mode", "TRIG"), ("burst_cycles", 1),
                            ("trigger_source", "BUS"), ("burst", True), ("trigger_output", True)):
            self.set(name, value)
        self.set("trigger_output_source", f"CH{ch}", check=False)
        refused = link.errors()
        if refused and not (ch == 1 and all(e.startswith("-113") for e in refused)):
            raise InstrumentError(f"{where}: routing the trigger output to channel {ch} "
                                  f"(OUTP:TRIG:SOUR CH{ch}) was refused: {'; '.join(refused)}")
        self._loaded = {
            "arb_points": int(points.size),
            "leading_zero_points": lead,
            "arb_sample_rate": self.sample_rate,
            "amplitude_vpp": self.amplitude,
            "offset_v": self.offset,
        }

    def start(self) -> None:
        """Output on, then a bus trigger: the burst plays once."""
        if not self._loaded:
            raise InstrumentError(f"{self.where}: start before load_waveform")
        self.output = True
        self.link.send_checked("*TRG", "a bus trigger needs BURS:STAT ON and TRIG:SOUR BUS")

    def monitor(self) -> None:
        """During the record: the output must still answer ``OUTP<n>?`` with on."""
        if not self.output:
            raise InstrumentError(f"{self.where}: the output went off during the record (front "
                                  "panel, or a reset?)")

    def switch_off(self) -> None:
        """Output relay open, burst aborted, offset 0 V (the kit's safe state confirms it by
        reading ``OUTP<n>?`` back)."""
        super().switch_off()
        self.link.write("ABOR")
        self.set("offset", 0.0, check=False)

    def state_details(self, output_enabled: bool) -> dict[str, Any]:
        """The offset (V) and the level at the output (V: the offset while the output is on)."""
        offset = self.offset
        return {"level_v": offset if output_enabled else 0.0, "offset_v": offset}


def check_source(address: str, settings: dict[str, Any], plan: Mapping[str, Any]) -> None:
    """The instrument check of :class:`~fsi_lab.contract.InstrumentPlugin` (ValueError): the
    waveform must fit the arb memory, and the embedded bench's generator has one channel."""
    points = plan["waveform_points"]
    if points > MAX_POINTS:
        raise ValueError(
            f"the excitation has {points:,} samples at {plan['waveform_rate']:g} Sa/s; the arb "
            f"memory holds {MIN_POINTS} to {MAX_POINTS:,} points: lower the source sample_rate "
            "or the excitation duration")
    from fsi_lab.instruments.sim.embedded import check_embedded

    if check_embedded(address, plan) and settings["channel"] != 1:
        raise ValueError(f"channel: {settings['channel']}; the embedded simulated "
                         "generator's channel 1 is wired to the amplifier")


def open_source(address: str, settings: dict[str, Any],
                context: Mapping[str, Any]) -> Keysight33500:
    """Connect, read whether the output was left on, switch it off, identify, clear the status
    and confirm the output off (``OUTP<n>?`` and the first ``OUTP<n> OFF`` go out before the
    identity is known, so that the output goes off even when the reply to ``*IDN?`` is
    unexpected, and an output found on is reported: :attr:`Keysight33500.found_on`; the kit's
    :meth:`~fsi_lab.instruments.kit.ScpiOutput.take_over`)."""
    link = connect(NAME, "source", address, settings, context)
    try:
        identity, found_on = Keysight33500.take_over(link, channel=settings["channel"])
    except BaseException:
        link.close()
        raise
    return Keysight33500(link, settings, identity, found_on)


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="source",
    params=(
        Keysight33500.sample_rate.param(None),
        Param("channel", "int", "", 1, minimum=1, maximum=2,
              help="Output channel wired to the amplifier."),
        Keysight33500.arb_filter.param("step"),
        Param("timeout_s", "float", "s", 2.0, minimum=0.05, maximum=60.0,
              help="Time allowed for each reply."),
    ),
    open=open_source,
    check=check_source,
    help="Keysight 33500B-series arbitrary waveform generator over VISA (SCPI).",
)


@hookimpl
def fsi_lab_instruments():
    return [PLUGIN]
