"""fsi-lab's conformance kit: contract tests a plugin author inherits, and scripted peers.

::

    from fsi_lab.testing import AnalysisContract

    class TestMyAnalysis(AnalysisContract):
        plugin = "my-analysis"

Each contract class (:class:`AnalysisContract`, :class:`ExcitationContract`,
:class:`InstrumentContract`) holds the tests every plugin of its kind must pass, parametrised
where a rule has several cases; a failure says what to change. fsi-lab's own plugins pass them
in fsi-lab's test suite (tests/test_conformance.py). The kit is a pytest plugin, registered
through the ``pytest11`` entry point (:mod:`fsi_lab.testing.plugin`: the fixtures
``fsi_lab_registry``, ``tcp_peer`` and ``pty_peer``, and the parametrisation of the contract
tests), so installing fsi-lab is all a plugin's test suite needs.

:class:`ScriptedPeer` and :class:`PtyPeer` are the other end of a real loopback socket or
pseudo-terminal for a driver's protocol tests.
"""

from fsi_lab.testing.analysis import AnalysisContract, two_decaying_modes
from fsi_lab.testing.excitation import ExcitationContract
from fsi_lab.testing.instrument import InstrumentContract
from fsi_lab.testing.peers import PtyPeer, ScriptedPeer

__all__ = ["AnalysisContract", "ExcitationContract", "InstrumentContract", "PtyPeer",
           "ScriptedPeer", "two_decaying_modes"]
