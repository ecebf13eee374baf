"""The fsi-lab pytest plugin, registered through the ``pytest11`` entry point: every pytest run
in an environment where fsi-lab is installed has its fixtures.

Fixtures
--------
tcp_peer
    ``tcp_peer(script)`` starts a :class:`~fsi_lab.testing.peers.ScriptedPeer` on 127.0.0.1
    (its ``address`` is a VISA resource name); stopped at the end of the test.
pty_peer
    ``pty_peer(script)`` starts a :class:`~fsi_lab.testing.peers.PtyPeer` on a pseudo-terminal
    (its ``address`` is the device path); stopped at the end of the test.
fsi_lab_registry
    The installed plugins (:func:`fsi_lab.registry.load_registry`), loaded once per session.

The contract classes of :mod:`fsi_lab.testing` use them. This module is imported whenever pytest
starts: it imports nothing heavy.
"""

from __future__ import annotations

import pytest

from fsi_lab.testing.peers import PtyPeer, ScriptedPeer


def _peers(cls):
    started = []

    def make(script):
        peer = cls(script).start()
        started.append(peer)
        return peer

    return started, make


@pytest.fixture
def tcp_peer():
    """Make scripted TCP peers on 127.0.0.1: ``peer = tcp_peer([(expected, reply), ...])``."""
    started, make = _peers(ScriptedPeer)
    yield make
    for peer in started:
        peer.stop()


@pytest.fixture
def pty_peer():
    """Make scripted serial peers on pseudo-terminals: ``peer = pty_peer([...])``."""
    started, make = _peers(PtyPeer)
    yield make
    for peer in started:
        peer.stop()


@pytest.fixture(scope="session")
def fsi_lab_registry():
    """The installed plugins, loaded once per session."""
    from fsi_lab.registry import load_registry

    return load_registry()


def pytest_generate_tests(metafunc):
    """Parametrise the contract tests that take a ``contract_case`` with the cases their class
    gives for its plugin (each bound of each parameter, ...)."""
    if "contract_case" not in metafunc.fixturenames or metafunc.cls is None:
        return
    cases_of = getattr(metafunc.cls, "contract_cases", None)
    if cases_of is None:
        return
    try:
        cases = metafunc.cls().contract_cases(metafunc.function.__name__)
    except (Exception, pytest.fail.Exception):  # noqa: BLE001 - the test itself says why
        cases = [("plugin-not-usable", None)]
    metafunc.parametrize("contract_case", [value for _, value in cases],
                         ids=[name for name, _ in cases])
