"""The Examples sections of fsi_lab.dsp's public functions run and print what they say."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import fsi_lab.dsp

MODULES = sorted(m.name for m in pkgutil.iter_modules(fsi_lab.dsp.__path__)
                 if not m.name.startswith("_"))


@pytest.mark.parametrize("name", MODULES)
def test_examples_run_as_written(name):
    module = importlib.import_module(f"fsi_lab.dsp.{name}")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} of {result.attempted} example lines failed"
