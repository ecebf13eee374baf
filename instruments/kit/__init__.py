"""The instrument kit: what fsi-lab's drivers are written with, for third-party drivers too.

- :class:`Setting`: one declared setting (command, type, unit, bounds or choices, help), read
  and written as an attribute of the driver and turned into the profile parameter that gives it
  (:meth:`Setting.param`), in the spirit of PyMeasure's ``Instrument.control``.
- :class:`ScpiInstrument`: a driver over a SCPI link (pyvisa, pyvisa-py) with declared
  settings, the error queue checked after every write and messages naming the instrument.
- :class:`ScpiOutput`: the template of every driver whose output can drive the shaker (a
  source, an amplifier): take-over with the output switched off first, the confirmed safe state
  and an :class:`~fsi_lab.contract.OutputState` read back.
- :func:`confirmed_safe_state` and :func:`output_found_on`, for drivers of other protocols.
- :func:`connect` and :func:`checked_identity`, the first steps of every ``open``.

The role classes (:class:`~fsi_lab.contract.SignalSource`, ``Amplifier``, ``Vibrometer``,
``Acquisition``) say which settings the runner reads (``run_settings``); docs/writing-plugins.md
shows a driver written with the kit.
"""

from fsi_lab.contract import InstrumentState, OutputState
from fsi_lab.instruments.kit.safe import SAFE_TIMEOUT_S, confirmed_safe_state, output_found_on
from fsi_lab.instruments.kit.scpi import ScpiInstrument, ScpiOutput, checked_identity, connect
from fsi_lab.instruments.kit.settings import Setting

__all__ = ["SAFE_TIMEOUT_S", "InstrumentState", "OutputState", "ScpiInstrument", "ScpiOutput",
           "Setting", "checked_identity", "confirmed_safe_state", "connect", "output_found_on"]
