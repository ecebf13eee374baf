"""Hook specifications: the three things a plugin can contribute.

A plugin is a module (or object) named by an entry point in the ``fsi_lab`` group. It
implements any of these hooks, decorated with :data:`hookimpl`, each returning a list of
descriptors from :mod:`fsi_lab.contract`.
"""

from __future__ import annotations

import pluggy

PROJECT = "fsi_lab"

hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def fsi_lab_instruments() -> list:
    """Return a list of :class:`fsi_lab.contract.InstrumentPlugin` this plugin provides."""


@hookspec
def fsi_lab_excitations() -> list:
    """Return a list of :class:`fsi_lab.contract.ExcitationPlugin` this plugin provides."""


@hookspec
def fsi_lab_analyses() -> list:
    """Return a list of :class:`fsi_lab.contract.AnalysisPlugin` this plugin provides."""


#: Hook name for each plugin kind.
HOOK_FOR_KIND = {
    "instrument": "fsi_lab_instruments",
    "excitation": "fsi_lab_excitations",
    "analysis": "fsi_lab_analyses",
}
