"""What the simulated instruments offer: channels, ranges, resolution and line speed.

The simulated instruments answer with these, and the lab drivers' checks refuse a profile that
asks the embedded bench for anything else (``fsi-lab profile check``, before a run). They are
kept apart from the simulation itself, whose filters need scipy and whose wires need an event
loop, so that a check loads nothing more than this.
"""

from __future__ import annotations

#: Output channels of the simulated generator (a 33522B has two).
SOURCE_CHANNELS = 2

#: Velocity ranges of the simulated PDV-100-class vibrometer: name -> ((m/s)/V, noise density
#: (m/s)/sqrt(Hz)). The analogue output spans +-VIBROMETER_OUTPUT_V.
VIBROMETER_RANGES = {
    "5mm/s/V": (0.005, 0.02e-6),
    "25mm/s/V": (0.025, 0.1e-6),
    "125mm/s/V": (0.125, 0.5e-6),
}
VIBROMETER_OUTPUT_V = 4.0
#: Name of the simulated vibrometer's velocity decoder.
VIBROMETER_DECODER = "VD-PDV"

#: Input ranges of the simulated digitiser, V (peak); the ADC has 24 bits over +-range.
DIGITISER_RANGES = (0.316, 1.0, 3.16, 10.0)
ADC_BITS = 24

#: Line speed of the simulated serial ports, baud (8N1).
SERIAL_BAUD = 115200


def volts_per_code(range_v: float) -> float:
    """Volts per ADC code on a digitiser input of ``range_v`` (V, peak)."""
    return range_v / 2 ** (ADC_BITS - 1)
