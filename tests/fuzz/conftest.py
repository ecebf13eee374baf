"""The fuzzing family runs ``fsi-lab`` in this process with the plugins loaded once."""

import pytest

import fsi_lab.cli
from fsi_lab.registry import load_registry


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
