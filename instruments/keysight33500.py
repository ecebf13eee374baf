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
instrument's own message.

Address: a VISA resource, e.g. ``TCPIP0::192.168.1.10::5025::SOCKET`` (or ``embedded`` for the
simulated bench).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from fsi_lab.contract import InstrumentPlugin, SignalSource
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.kit import SAFE_TIMEOUT_S, confirmed_safe_state
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


class Keysight33500(SignalSource):
    """An open 33500B-class generator. Use :func:`open_source`."""

    def __init__(self, link, settings: dict[str, Any], identity: str,
                 found_on: bool | None = None) -> None:
        self.link = link
        #: Whether the output was on when the generator was opened (None: it could not be read).
        self.found_on = found_on
        self.channel = int(settings["channel"])
        self.filter = FILTERS[settings["arb_filter"]]
        self.identity = identity
        self._loaded: dict[str, Any] = {}

    @property
    def _src(self) -> str:
        return f"SOUR{self.channel}:"

    def identify(self) -> str:
        return self.identity

    def settings(self) -> dict[str, Any]:
        return {"visa_address": self.link.address, "arb_name": ARB_NAME, "channel": self.channel,
                "arb_filter": self.filter, "output_found_on": self.found_on, **self._loaded}

    def load_waveform(self, samples: np.ndarray, sample_rate: float) -> None:
        """Upload ``samples`` (V) to play once at ``sample_rate`` (Sa/s) per trigger."""
        wave = np.asarray(samples, dtype=float).ravel()
        where = f"{NAME} at {self.link.address}"
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
        link.send_checked(f"OUTP{ch} OFF")
        link.send_checked("FORM:BORD SWAP")
        link.send_checked(f"{src}DATA:VOL:CLE")
        payload = points.tobytes()
        length = str(len(payload))
        header = f"{src}DATA:ARB {ARB_NAME},#{len(length)}{length}"
        with link.timeout(upload_timeout(link.timeout_s, len(payload))):
            link.write_raw(header, header.encode("ascii") + payload + b"\n")
            link.check(f"the upload of {points.size} points ({header[:40]}...)",
                       f"the arb memory takes {MIN_POINTS} to {MAX_POINTS:,} points in -1..1")
        for command, accepted in (
                (f"{src}FUNC ARB", ""),
                (f"{src}FUNC:ARB {ARB_NAME}", ""),
                (f"{src}FUNC:ARB:SRAT {sample_rate:.10g}", "the arb sample rate must lie "
                                                           "between 1 uSa/s and 160 MSa/s"),
                (f"{src}FUNC:ARB:FILT {self.filter}", ""),
                (f"OUTP{ch}:LOAD INF", ""),
                (f"{src}VOLT:UNIT VPP", ""),
                (f"{src}VOLT:OFFS 0", ""),
                (f"{src}VOLT {amplitude:.10g}", "the peak drive must stay within +-10 V into a "
                                                "high-impedance load"),
                (f"{src}BURS:MODE TRIG", ""),
                (f"{src}BURS:NCYC 1", ""),
                (f"TRIG{ch}:SOUR BUS", ""),
                (f"{src}BURS:STAT ON", ""),
                ("OUTP:TRIG ON", "")):
            link.send_checked(command, accepted)
        link.write(f"OUTP:TRIG:SOUR CH{ch}")
        refused = link.errors()
        if refused and not (ch == 1 and all(e.startswith("-113") for e in refused)):
            raise InstrumentError(f"{where}: routing the trigger output to channel {ch} "
                                  f"(OUTP:TRIG:SOUR CH{ch}) was refused: {'; '.join(refused)}")
        self._loaded = {
            "arb_points": int(points.size),
            "leading_zero_points": lead,
            "arb_sample_rate": link.query_float(f"{src}FUNC:ARB:SRAT?"),
            "amplitude_vpp": link.query_float(f"{src}VOLT?"),
            "offset_v": link.query_float(f"{src}VOLT:OFFS?"),
        }

    def start(self) -> None:
        """Output on, then a bus trigger: the burst plays once."""
        if not self._loaded:
            raise InstrumentError(f"{NAME} at {self.link.address}: start before load_waveform")
        self.link.send_checked(f"OUTP{self.channel} ON")
        self.link.send_checked("*TRG", "a bus trigger needs BURS:STAT ON and TRIG:SOUR BUS")

    def monitor(self) -> None:
        """During the record: the output must still answer ``OUTP<n>?`` with on."""
        if not self.link.query_bool(f"OUTP{self.channel}?"):
            raise InstrumentError(f"{NAME} at {self.link.address}: the output went off during "
                                  "the record (front panel, or a reset?)")

    def safe_state(self) -> None:
        """Output relay open, burst aborted, offset 0 V; confirmed by reading ``OUTP?`` back.

        Works on a link that misbehaved: it reconnects first, with a short timeout, and tries
        twice before reporting failure.
        """
        link, channel = self.link, self.channel

        def switch_off() -> None:
            link.write(f"OUTP{channel} OFF")
            link.write("ABOR")
            link.write(f"{self._src}VOLT:OFFS 0")

        confirmed_safe_state(NAME, f"{NAME} at {link.address}", link, switch_off,
                             lambda: link.query_bool(f"OUTP{channel}?"), timeout_s=SAFE_TIMEOUT_S)

    def read_state(self) -> dict[str, Any]:
        with self.link.timeout(SAFE_TIMEOUT_S):
            self.link.recover(SAFE_TIMEOUT_S)
            on = self.link.query_bool(f"OUTP{self.channel}?")
            offset = self.link.query_float(f"{self._src}VOLT:OFFS?")
        return {"output_enabled": on, "level_v": offset if on else 0.0, "offset_v": offset}

    def close(self) -> None:
        self.link.close()


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

    if check_embedded(address, plan):
        if settings["channel"] != 1:
            raise ValueError(f"channel: {settings['channel']}; the embedded simulated "
                             "generator's channel 1 is wired to the amplifier")


def _output_found_on(link, channel: int) -> bool | None:
    """``OUTP<n>?`` before anything else is sent: whether the output was left on; None when
    the reply could not be read (the link is reopened then, so that ``OUTP<n> OFF`` still goes
    out)."""
    try:
        with link.timeout(SAFE_TIMEOUT_S):
            return link.query_bool(f"OUTP{channel}?")
    except InstrumentError:
        link.recover(SAFE_TIMEOUT_S)
        return None


def open_source(address: str, settings: dict[str, Any], context: dict[str, Any]) -> Keysight33500:
    """Connect, read whether the output was left on, switch it off, identify, clear the status
    and confirm the output off (``OUTP<n>?`` and the first ``OUTP<n> OFF`` go out before the
    identity is known, so that the output goes off even when the reply to ``*IDN?`` is
    unexpected, and an output found on is reported: :attr:`Keysight33500.found_on`)."""
    from fsi_lab.instruments._visa import VisaLink

    if address.strip() in ("", "embedded"):
        from fsi_lab.instruments.sim.embedded import resolve_address

        address = resolve_address("source", NAME, address, context)
    link = VisaLink(NAME, address, settings["timeout_s"])
    try:
        found_on = _output_found_on(link, settings["channel"])
        link.write(f"OUTP{settings['channel']} OFF")
        identity = link.query("*IDN?")
        if identity.count(",") < 3:
            raise InstrumentError(f"{NAME} at {address}: unexpected identity {identity!r}; "
                                  "expected <maker>,<model>,<serial>,<firmware> (OUTP OFF was "
                                  "sent first)")
        link.write("*CLS")
        link.send_checked(f"OUTP{settings['channel']} OFF")
    except BaseException:
        link.close()
        raise
    return Keysight33500(link, settings, identity, found_on)


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="source",
    params=(
        Param("sample_rate", "float", "Hz", None, minimum=1e-6, maximum=160e6,
              help="Arb sample rate the excitation is generated at (unset: the run's rate)."),
        Param("channel", "int", "", 1, minimum=1, maximum=2,
              help="Output channel wired to the amplifier."),
        Param("arb_filter", "str", "", "step", choices=tuple(FILTERS),
              help="Arb output filter: 'normal' (band-limited), 'step' (smoothed steps) or "
                   "'off' (sample and hold)."),
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
