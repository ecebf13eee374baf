"""The fuzzing family runs ``fsi-lab`` in this process with the plugins loaded once."""

import pytest

import fsi_lab.cli
from fsi_lab import isolation
from fsi_lab.registry import load_registry

#: s: the time a damaged file's read may take in its child before the file is refused. Some
#: damage makes the HDF5 library loop; each such case would take the whole minute allowed for
#: a real file, while an undamaged small file reads in milliseconds.
READ_TIMEOUT_S = 3.0


@pytest.fixture(autouse=True)
def short_read_timeout(monkeypatch):
    """Damaged files that hang the HDF5 library are refused after :data:`READ_TIMEOUT_S`."""
    monkeypatch.setattr(isolation, "TIMEOUT_S", READ_TIMEOUT_S)


@pytest.fixture(scope="module")
def loaded_once():
    """``fsi_lab.cli`` takes the registry loaded once (entry points are read once per module)
    for the module's many cases."""
    registry = load_registry()
    saved = fsi_lab.cli._registry
    fsi_lab.cli._registry = lambda: registry
    yield registry
    fsi_lab.cli._registry = saved


def pytest_terminal_summary(terminalreporter):
    """How many cases the fuzzing family generated in this session."""
    from fuzzkit import TALLY

    if TALLY:
        parts = ", ".join(f"{name} {count}" for name, count in TALLY.items())
        terminalreporter.write_line(f"fuzzing: {sum(TALLY.values())} generated cases ({parts})")
