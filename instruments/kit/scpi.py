"""A SCPI instrument base: a VISA link, declared settings, identity, and an output template.

:class:`ScpiInstrument` gives a driver its link (:class:`~fsi_lab.instruments._visa.VisaLink`),
reads and writes its declared :class:`~fsi_lab.instruments.kit.settings.Setting`\\ s with the
error queue checked after every write, and names the instrument and its address in every
message. :class:`ScpiOutput` adds what every driver of an output that can drive the shaker
(a source, an amplifier) must do the same way: take the instrument over switching the output
off first, the confirmed safe state, and a state read back that always says ``output_enabled``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from fsi_lab.contract import OutputState
from fsi_lab.errors import InstrumentError
from fsi_lab.instruments.kit.safe import SAFE_TIMEOUT_S, confirmed_safe_state, output_found_on
from fsi_lab.instruments.kit.settings import Setting


def connect(name: str, role: str, address: str, settings: Mapping[str, Any],
            context: Mapping[str, Any], baud_rate: int | None = None):
    """Open the VISA link of a driver (pyvisa, pyvisa-py backend).

    Parameters
    ----------
    name
        The driver's name, which messages start with.
    role
        Its role (``"amplifier"``): an ``embedded`` (or empty) address is resolved to the
        embedded simulated bench's instrument of that role.
    address
        VISA resource name (``TCPIP0::192.168.1.20::5025::SOCKET``, ``ASRL/dev/ttyUSB0::INSTR``)
        or ``embedded``.
    settings
        Validated settings; ``timeout_s`` (s) is the time allowed for each reply.
    context
        The bench context (:class:`~fsi_lab.contract.BenchContext`, or a dict with its keys).
    baud_rate
        Serial addresses only: the line speed, Bd.

    Returns
    -------
    VisaLink
        The open link; InstrumentError naming the driver and address if it cannot be opened.
    """
    from fsi_lab.instruments._visa import VisaLink

    if address.strip() in ("", "embedded"):
        from fsi_lab.instruments.sim.embedded import resolve_address

        address = resolve_address(role, name, address, context)
    if baud_rate is None:
        return VisaLink(name, address, settings["timeout_s"])
    return VisaLink(name, address, settings["timeout_s"], baud_rate)


def checked_identity(name: str, link, note: str = "") -> str:
    """``*IDN?``, which must answer ``<maker>,<model>,<serial>,<firmware>``; InstrumentError
    naming the driver, its address and the reply otherwise (``note`` is added to it)."""
    identity = link.query("*IDN?")
    if identity.count(",") < 3:
        raise InstrumentError(f"{name} at {link.address}: unexpected identity {identity!r}; "
                              "expected <maker>,<model>,<serial>,<firmware>"
                              + (f" ({note})" if note else ""))
    return identity


class ScpiInstrument:
    """An open SCPI instrument with declared settings.

    Subclasses set :attr:`NAME` (the plugin name) and declare their settings as class
    attributes (:class:`~fsi_lab.instruments.kit.settings.Setting`); command fields such as
    ``{channel}`` are filled from the instance's attributes of that name unless given.

    Parameters
    ----------
    link
        The open :class:`~fsi_lab.instruments._visa.VisaLink` (see :func:`connect`).
    identity
        What ``*IDN?`` answered.
    """

    #: The driver's (plugin's) name, which messages start with.
    NAME: ClassVar[str] = "scpi-instrument"

    def __init__(self, link, identity: str) -> None:
        self.link = link
        self.identity = identity

    @property
    def where(self) -> str:
        """``"<NAME> at <address>"``, the start of every message about this instrument."""
        return f"{self.NAME} at {self.link.address}"

    @classmethod
    def declared_settings(cls) -> dict[str, Setting]:
        """Every :class:`Setting` of the class and its bases, by attribute name."""
        found: dict[str, Setting] = {}
        for klass in reversed(cls.__mro__):
            found.update({k: v for k, v in vars(klass).items() if isinstance(v, Setting)})
        return found

    def _setting(self, name: str) -> Setting:
        setting = self.declared_settings().get(name)
        if setting is None:
            raise InstrumentError(f"{self.where}: no setting {name!r}; declared: "
                                  f"{', '.join(self.declared_settings()) or 'none'}")
        return setting

    def _fields(self, setting: Setting, given: Mapping[str, Any]) -> dict[str, Any]:
        values = dict(given)
        for name in setting.fields:
            if name not in values:
                if not hasattr(self, name):
                    raise InstrumentError(f"{self.where}: setting {setting.name!r} needs "
                                          f"{name}= ({setting.command})")
                values[name] = getattr(self, name)
        return values

    # ------------------------------------------------------------------ settings
    def command(self, name: str, value: Any, **fields: Any) -> str:
        """The command that sets setting ``name`` to ``value`` (checked, nothing sent)."""
        setting = self._setting(name)
        try:
            return setting.command_for(value, **self._fields(setting, fields))
        except ValueError as exc:
            raise InstrumentError(f"{self.where}: {exc}") from None

    def get(self, name: str, **fields: Any) -> Any:
        """Read setting ``name`` from the instrument, converted to its type."""
        setting = self._setting(name)
        try:
            query = setting.query_for(**self._fields(setting, fields))
        except ValueError as exc:
            raise InstrumentError(f"{self.where}: {exc}") from None
        reply = self.link.query(query)
        try:
            return setting.parse(reply)
        except ValueError as exc:
            raise self.link.fail(query, f"unexpected reply {reply!r}; {exc}") from None

    def set(self, name: str, value: Any, *, check: bool = True, verify: bool = False,
            **fields: Any) -> Any:
        """Send setting ``name`` = ``value``.

        Parameters
        ----------
        name, value
            The setting and its value, checked against its declaration first (InstrumentError
            naming the setting and what it accepts; nothing is sent).
        check
            Read the error queue after it (InstrumentError with the instrument's own message
            and the setting's ``accepted`` text); False for commands sent on a link that may
            misbehave (the safe state).
        verify
            Read it back; InstrumentError if it differs by more than its tolerance.
        **fields
            Command fields (``input=3``).

        Returns
        -------
        object
            The value read back with ``verify``, else the value sent.
        """
        setting = self._setting(name)
        command = self.command(name, value, **fields)
        if check:
            self.link.send_checked(command, setting.accepted)
        else:
            self.link.write(command)
        if verify:
            read = self.get(name, **fields)
            if setting.type in ("float", "int"):
                same = abs(read - value) <= setting.tolerance * max(1.0, abs(value))
            else:
                same = read == value
            if not same:
                shown = f"{read:g}" if setting.type in ("float", "int") else repr(read)
                raise InstrumentError(f"{self.where}: {setting.name} reads back {shown} after "
                                      f"{command}")
            return read
        return value

    # ------------------------------------------------------------------ common
    def identify(self) -> str:
        """The identity ``*IDN?`` gave when the instrument was opened."""
        return self.identity

    def close(self) -> None:
        """Close the link (never raises)."""
        self.link.close()


class ScpiOutput(ScpiInstrument):
    """An SCPI instrument whose output can drive the shaker: the one way every such driver takes
    the instrument over, makes it safe and reads its state back.

    A subclass declares ``output``, a bool :class:`Setting` (``Setting("OUTP{channel}",
    "bool")``), and may extend :meth:`switch_off` (what else makes it safe: abort a burst, an
    offset to 0 V) and :meth:`state_details` (what else its state holds).
    """

    output: ClassVar[Setting]
    #: Whether the output was on when the instrument was opened (None: it could not be read).
    found_on: bool | None = None

    @classmethod
    def take_over(cls, link, **fields: Any) -> tuple[str, bool | None]:
        """Open an instrument whose output may have been left on.

        In this order: read the output state (``found_on``; None if the reply cannot be read,
        the link then reopened), switch the output off, identify (``*IDN?``), clear the status
        (``*CLS``) and switch the output off again, checked. The output goes off before the
        identity is known, so even when ``*IDN?`` answers something unexpected.

        Returns
        -------
        tuple
            The identity and ``found_on``.
        """
        setting = cls.output
        found_on = output_found_on(link, setting.query_for(**fields))
        off = setting.command_for(False, **fields)
        link.write(off)
        identity = checked_identity(cls.NAME, link, f"{setting.generic(False)} was sent first")
        link.write("*CLS")
        link.send_checked(off)
        return identity, found_on

    def switch_off(self) -> None:
        """Send what makes the instrument safe, unchecked (the link may misbehave): the output
        off. Extend it with what else the instrument needs."""
        self.set("output", False, check=False)

    def safe_state(self) -> None:
        """Switch the output off and confirm it (:func:`confirmed_safe_state`): reconnect if the
        link misbehaved, with a short timeout, and try twice before reporting failure."""
        confirmed_safe_state(self.NAME, self.where, self.link, self.switch_off,
                             lambda: self.get("output"), timeout_s=SAFE_TIMEOUT_S)

    def state_details(self, output_enabled: bool) -> dict[str, Any]:
        """Further values of the state read back, after the output (none by default);
        ``output_enabled`` is what the output read."""
        return {}

    def read_state(self) -> OutputState:
        """The output state read back (``output``), with :meth:`state_details`, on a link
        reopened if it misbehaved and with a short timeout."""
        with self.link.timeout(SAFE_TIMEOUT_S):
            self.link.recover(SAFE_TIMEOUT_S)
            on = self.get("output")
            return OutputState(on, **self.state_details(on))
