"""A third-party amplifier driver written with fsi-lab's instrument kit.

It drives an amplifier that speaks SCPI over VISA (``*IDN?``, ``OUTP 0|1``, ``OUTP?``,
``GAIN <V/V>``, ``GAIN?``, ``STAT:INTL?``): fsi-lab's simulated shaker amplifier is one. The
kit gives it, in about sixty lines, what every output driver of fsi-lab does: the output
switched off before anything else when it is opened (and reported if it was found on), the
confirmed safe state, a typed state read back (``OutputState``), settings checked against
their declared bounds before they are sent, and the error queue read after every write.
"""

from __future__ import annotations

from typing import Any

from fsi_lab.contract import Amplifier, InstrumentPlugin
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.kit import ScpiOutput, Setting, connect
from fsi_lab.params import Param

NAME = "example-amplifier"
#: Interlock name for each bit of ``STAT:INTL?``.
INTERLOCKS = ("over_travel", "supply_fault", "over_temperature", "over_current", "e_stop",
              "input_clip", "watchdog")


class ExampleAmplifier(ScpiOutput, Amplifier):
    """An open amplifier; use :func:`open_amplifier`."""

    NAME = NAME
    output = Setting("OUTP", "bool", choices=("1", "0"), help="Output stage on.")
    gain = Setting("GAIN", "float", "V/V", minimum=0.0, maximum=20.0, fmt=".6g",
                   help="Voltage gain of the amplifier.")
    interlock_bits = Setting("STAT:INTL", "int", readonly=True, help="Latched interlocks.")

    def set_gain(self, gain: float) -> None:
        """Set the gain (V/V), checked against its bounds, and read it back."""
        self.set("gain", gain, verify=True)

    def interlocks(self) -> dict[str, bool]:
        """Latched interlocks by name."""
        bits = self.interlock_bits
        return {name: bool(bits >> bit & 1) for bit, name in enumerate(INTERLOCKS)}

    def enable_output(self, enabled: bool) -> None:
        """Output on (refused while an interlock is latched) or off."""
        active = [name for name, on in self.interlocks().items() if on]
        if enabled and active:
            raise InstrumentError(f"{self.where}: output on refused: interlock "
                                  f"{', '.join(active)} is active")
        self.output = enabled

    def state_details(self, output_enabled: bool) -> dict[str, Any]:
        """The gain (V/V), next to the output state the kit reads."""
        return {"gain": self.gain}


def open_amplifier(address: str, settings: dict[str, Any], bench) -> ExampleAmplifier:
    """Connect (``embedded`` names fsi-lab's embedded simulated bench) and take the amplifier
    over with its output off."""
    link = connect(NAME, "amplifier", address, settings, bench)
    try:
        identity, found_on = ExampleAmplifier.take_over(link)
    except BaseException:
        link.close()
        raise
    amplifier = ExampleAmplifier(link, identity)
    amplifier.found_on = found_on
    return amplifier


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="amplifier",
    params=(ExampleAmplifier.gain.param(1.0),
            Param("timeout_s", "float", "s", 2.0, minimum=0.05, maximum=60.0,
                  help="Time allowed for each reply.")),
    open=open_amplifier,
    help="Example third-party SCPI amplifier driver written with the instrument kit.",
)


@hookimpl
def fsi_lab_instruments():
    return [PLUGIN]
