"""Keysight 33500B-series arbitrary waveform generator (signal source) over VISA, SCPI.

The drive waveform is uploaded as an arbitrary waveform: the samples divided by their peak, as
an IEEE 488.2 definite-length block of float32 in little-endian order (``FORM:BORD SWAP``),
played at ``FUNC:ARB:SRAT`` with an amplitude of twice the peak (Vpp, high-impedance load; a peak
below 1 mV is played at the smallest amplitude, 2 mVpp, with the points scaled down) and no
offset, as one triggered burst. ``start`` switches the output on and sends a bus trigger
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
from fsi_lab.params import Param

NAME = "keysight33500"
ARB_NAME = "FSILAB"
MIN_POINTS = 8
MAX_POINTS = 1_000_000
MIN_VPP = 0.002
FILTERS = {"normal": "NORM", "step": "STEP", "off": "OFF"}
SAFE_TIMEOUT_S = 1.0


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

    def __init__(self, link, settings: dict[str, Any], identity: str) -> None:
        self.link = link
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
                "arb_filter": self.filter, **self._loaded}

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
        self._loaded = {
            "arb_points": int(points.size),
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

    def safe_state(self) -> None:
        """Output relay open, burst aborted, offset 0 V; confirmed by reading ``OUTP?`` back.

        Works on a link that misbehaved: it reconnects first, with a short timeout, and tries
        twice before reporting failure.
        """
        last: Exception | None = None
        for _ in range(2):
            try:
                with self.link.timeout(SAFE_TIMEOUT_S):
                    self.link.recover(SAFE_TIMEOUT_S)
                    self.link.write(f"OUTP{self.channel} OFF")
                    self.link.write("ABOR")
                    self.link.write(f"{self._src}VOLT:OFFS 0")
                    if not self.link.query_bool(f"OUTP{self.channel}?"):
                        return
                    last = InstrumentError(f"{NAME} at {self.link.address}: the output still "
                                           "reads on after OUTP OFF")
            except InstrumentError as exc:
                last = exc
                self.link.broken = self.link.broken or str(exc)
        raise InstrumentError(f"{NAME}: safe state not confirmed: {last}")

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
        from fsi_lab.instruments.sim.specs import SOURCE_CHANNELS

        if settings["channel"] > SOURCE_CHANNELS:
            raise ValueError(f"channel: {settings['channel']}; the embedded simulated generator "
                             f"has channel 1 only")


def open_source(address: str, settings: dict[str, Any], context: dict[str, Any]) -> Keysight33500:
    """Connect, switch the output off, identify, clear the status and confirm the output off
    (the first ``OUTP<n> OFF`` goes out before the identity is known, so that the output goes
    off even when the reply to ``*IDN?`` is unexpected)."""
    from fsi_lab.instruments._visa import VisaLink

    if address.strip() in ("", "embedded"):
        from fsi_lab.instruments.sim.embedded import resolve_address

        address = resolve_address("source", NAME, address, context)
    link = VisaLink(NAME, address, settings["timeout_s"])
    try:
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
    return Keysight33500(link, settings, identity)


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
