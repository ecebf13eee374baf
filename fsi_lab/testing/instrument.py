"""The instrument contract: what every instrument driver must do, as tests its author inherits.

::

    import pytest
    from fsi_lab.testing import InstrumentContract

    class TestMyAmplifier(InstrumentContract):
        plugin = "my-amplifier"
        settings = {"gain": 1.0}
        transport = "tcp"                 # "serial" for a pyserial driver, None for neither

        @pytest.fixture
        def address(self, my_simulated_amplifier):
            return my_simulated_amplifier.address   # where an instrument answers

pytest then runs, on the driver opened at ``address``:

- it is an instance of its role's class and identifies itself;
- its safe state is confirmed: after ``safe_state()`` (twice: it must be safe to repeat),
  ``read_state()`` of a role with an output (a source, an amplifier) is an
  :class:`fsi_lab.contract.OutputState` whose ``output_enabled`` is False;
- its state is typed: ``read_state()`` is a mapping, ``settings()`` a dict, and both are
  stored in a run file's attributes as they are;
- ``close()`` may be called twice;
- against a scripted peer on a real loopback socket (``transport = "tcp"``) or
  pseudo-terminal (``"serial"``) that never answers, opening it fails with
  :class:`fsi_lab.errors.InstrumentError` naming the address, within its timeout, instead of
  hanging or failing with a library's exception.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pytest

from fsi_lab.bench_access import unsafe_roles
from fsi_lab.contract import ROLE_INTERFACES, BenchContext, InstrumentPlugin, OutputState
from fsi_lab.errors import FsiLabError, InstrumentError
from fsi_lab.params import REQUIRED, validate
from fsi_lab.testing._common import broken, descriptor_of
from fsi_lab.testing.peers import PtyPeer, ScriptedPeer

TRANSPORTS = ("tcp", "serial")


class InstrumentContract:
    """Contract tests of an instrument driver; subclass it in a ``Test...`` class and give it
    an ``address`` fixture.

    Attributes
    ----------
    plugin
        Name of the instrument plugin as installed, or its :class:`InstrumentPlugin`.
    settings
        Values of its parameters (the profile's ``[bench.<role>]`` table).
    transport
        ``"tcp"`` (VISA over a socket), ``"serial"`` (a serial port), or None (neither: the
        silent-peer test is not run).
    """

    plugin: str | InstrumentPlugin = ""
    settings: dict[str, Any] = {}
    transport: str | None = None

    @pytest.fixture
    def address(self):
        """Where an instrument the driver talks to answers: override it in the test class."""
        pytest.fail("give the address of an instrument to test the driver against: define a "
                    "fixture 'address' in the test class returning it (the address of a "
                    "fsi_lab.testing.ScriptedPeer, of a simulated instrument, or of fsi-lab's "
                    "simulated bench: fsi_lab.instruments.sim.bench.SimBench)", pytrace=False)

    # ------------------------------------------------------------------ helpers
    def _descriptor(self, registry) -> InstrumentPlugin:
        return descriptor_of("instrument", self.plugin, registry, InstrumentPlugin)

    def _settings(self, plugin: InstrumentPlugin, changes: dict[str, Any] | None = None
                  ) -> dict[str, Any]:
        missing = [p.name for p in plugin.params
                   if p.default is REQUIRED and p.name not in self.settings]
        if missing:
            broken(plugin.name, f"setting(s) {', '.join(missing)} have no default: give values "
                                "in the test class's settings")
        return validate(plugin.params, {**self.settings, **(changes or {})}, plugin.name)

    @pytest.fixture
    def instrument(self, fsi_lab_registry, address):
        """The driver opened at ``address`` for a run; made safe and closed afterwards."""
        plugin = self._descriptor(fsi_lab_registry)
        context = BenchContext(purpose="run")
        opened = failure = None
        try:
            opened = plugin.open(address, self._settings(plugin), context)
        except Exception as exc:  # noqa: BLE001 - the author needs the reason
            failure = exc
        if failure is not None:
            broken(plugin.name, f"cannot be opened at {address!r}: {type(failure).__name__}: "
                                f"{failure}")
        yield opened
        # leave it safe and closed whatever the test did (a failure there is the tests' to say)
        for step in (opened.safe_state, opened.close, *reversed(context.cleanup)):
            try:
                step()
            except Exception:  # noqa: BLE001 - reported by the test of that step
                pass

    # ------------------------------------------------------------------ the contract
    def test_is_its_role_and_identifies_itself(self, fsi_lab_registry, instrument):
        plugin = self._descriptor(fsi_lab_registry)
        role_class = ROLE_INTERFACES[plugin.role]
        if not isinstance(instrument, role_class):
            broken(plugin.name, f"open() returned a {type(instrument).__name__}; return an "
                                f"instance of fsi_lab.contract.{role_class.__name__} (its role "
                                f"is {plugin.role})")
        identity = instrument.identify()
        if not isinstance(identity, str) or not identity.strip():
            broken(plugin.name, f"identify() returned {identity!r}; return the identity the "
                                "instrument reports (*IDN? or its equivalent)")

    def test_safe_state_is_confirmed(self, fsi_lab_registry, instrument):
        plugin = self._descriptor(fsi_lab_registry)
        for attempt in ("first", "second"):
            failure = _raised(instrument.safe_state)
            if failure is not None:
                broken(plugin.name, f"safe_state() failed the {attempt} time "
                                    f"({type(failure).__name__}: {failure}); it must make the "
                                    "instrument safe every time it is called")
        state = instrument.read_state()
        unsafe = unsafe_roles({plugin.role: state}, {plugin.role: plugin.name})
        if unsafe:
            broken(plugin.name, f"is not confirmed safe after safe_state(): "
                                f"{unsafe[plugin.role]}")
        if ROLE_INTERFACES[plugin.role].has_output and not isinstance(state, OutputState):
            broken(plugin.name, f"read_state() returned a {type(state).__name__}; a "
                                f"{plugin.role} returns fsi_lab.contract.OutputState("
                                "output_enabled=<bool read from the instrument>, ...)")

    def test_state_is_typed_and_stored_as_read(self, fsi_lab_registry, instrument, tmp_path):
        import h5py

        from fsi_lab.runfile import read_attrs, write_attrs

        plugin = self._descriptor(fsi_lab_registry)
        state = instrument.read_state()
        if not isinstance(state, Mapping):
            broken(plugin.name, f"read_state() returned a {type(state).__name__}; return an "
                                "fsi_lab.contract.InstrumentState (or OutputState) of named "
                                "values")
        settings = instrument.settings()
        if not isinstance(settings, dict):
            broken(plugin.name, f"settings() returned a {type(settings).__name__}; return a "
                                "dict of the settings in force")
        for what, values in (("read_state()", dict(state)), ("settings()", settings)):
            with h5py.File(tmp_path / "state.h5", "w") as handle:
                failure = _raised(lambda: write_attrs(handle, values))
                back = read_attrs(handle)
            if isinstance(failure, (FsiLabError, TypeError, ValueError)):
                broken(plugin.name, f"{what} cannot be stored in a run file ({failure}); give "
                                    "numbers, strings, booleans and lists or dicts of them")
            if failure is not None:
                raise failure
            if set(back) != set(values):
                broken(plugin.name, f"{what} keys {sorted(values)} were stored as "
                                    f"{sorted(back)}")

    def test_closes_twice(self, fsi_lab_registry, instrument):
        plugin = self._descriptor(fsi_lab_registry)
        instrument.safe_state()
        for attempt in ("first", "second"):
            failure = _raised(instrument.close)
            if failure is not None:
                broken(plugin.name, f"close() raised {type(failure).__name__} ({failure}) the "
                                    f"{attempt} time; it must not raise when already closed")

    def test_a_silent_peer_is_an_instrument_error(self, fsi_lab_registry):
        plugin = self._descriptor(fsi_lab_registry)
        if self.transport is None:
            return  # neither a socket nor a serial port to be silent on
        if self.transport not in TRANSPORTS:
            pytest.fail(f"transport is {self.transport!r}; expected one of "
                        f"{', '.join(TRANSPORTS)} or None", pytrace=False)
        peer = (ScriptedPeer if self.transport == "tcp" else PtyPeer)([], timeout=30.0)
        peer.start()
        try:
            changes = {"timeout_s": 0.2} if any(p.name == "timeout_s" for p in plugin.params) \
                else {}
            settings = self._settings(plugin, changes)
            opened = failure = None
            try:
                opened = plugin.open(peer.address, settings, BenchContext(purpose="run"))
            except Exception as exc:  # noqa: BLE001 - judged below
                failure = exc
            if isinstance(failure, InstrumentError):
                if peer.address not in str(failure) and plugin.name not in str(failure):
                    broken(plugin.name, f"a peer that never answers gave InstrumentError "
                                        f"({failure}) naming neither the driver nor the "
                                        "address; name both")
                return
            if failure is not None:
                broken(plugin.name, f"a peer at {peer.address} that never answers made open() "
                                    f"raise {type(failure).__name__} ({failure}); raise "
                                    "fsi_lab.errors.InstrumentError naming the instrument and "
                                    "its address")
            _raised(opened.close)
            broken(plugin.name, f"opened at {peer.address}, where nothing answers; ask the "
                                "instrument who it is (identify) when opening, and fail with "
                                "InstrumentError when it does not answer")
        finally:
            peer.stop()


def _raised(step) -> BaseException | None:
    """What ``step()`` raised, or None."""
    try:
        step()
    except Exception as exc:  # noqa: BLE001 - the caller judges it
        return exc
    return None
