"""Hook specifications: what a plugin can contribute to fsi-lab.

A plugin is a module (or object) named by an entry point in the ``fsi_lab`` group. It implements
any of these hooks, decorated with :data:`hookimpl`; fsi-lab calls every hook through its plugin
manager (``manager.hook.<name>(...)``, see :class:`fsi_lab.registry.Registry`), a plugin at a
time, so that one plugin's failure is reported with its name and does not hide the others. A
hook implementation may take any subset of the arguments its specification names, as in pytest.

fsi-lab's own plugins (``plugins/``, ``instruments/``) use exactly these hooks: the core names no
instrument, excitation or analysis.
"""

from __future__ import annotations

from typing import Any

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


@hookspec
def fsi_lab_addcommands(subparsers: Any) -> None:
    """Add ``fsi-lab`` subcommands: ``subparsers`` is the argparse sub-parser action of the
    ``fsi-lab`` command.

    Call ``subparsers.add_parser(NAME, help=...)`` for each command, add its arguments, and set
    the function that runs it with ``parser.set_defaults(func=run)``: ``run(args)`` returns the
    exit code. Keep the module light (import what the command needs inside ``run``): the hook is
    called whenever ``fsi-lab`` starts.
    """


@hookspec
def fsi_lab_summary_lines(channel: str, summary: dict, component: dict | None) -> Any:
    """Text of the analysis summary (``fsi-lab run``, ``analyze``, ``show``) for what this
    plugin's analyses put in it.

    Called once for each analysed channel with ``component`` None (``summary`` is the channel's
    summary), then once for each of its components (``component`` is the entry of
    ``summary["components"]``). Return a :class:`fsi_lab.presentation.SummaryText` (or None): the
    summary keys it shows (which are then not shown again as plain values), text appended to the
    channel's or the component's line, and lines below it. Keys no plugin claims are shown as
    ``key: value`` when their values are numbers or strings.
    """


@hookspec
def fsi_lab_default_chain(analyses: tuple) -> list:
    """Names of the analyses this plugin puts in the default chain: the chain of data that
    comes without a profile (``fsi-lab import``, then ``analyze``).

    ``analyses`` holds the names of the analyses installed. fsi-lab keeps the names among them
    and orders the chain so that each analysis comes after those providing what it requires or
    uses (:func:`fsi_lab.chain.default_chain`).
    """


@hookspec
def fsi_lab_addviews(views: Any) -> None:
    """Register GUI views of analysis results in ``views`` (a
    :class:`fsi_lab.presentation.ViewSet`): ``views.add(AnalysisView(...))`` for a tab of the
    Analysis panel, ``views.add_curve(...)`` for curves the runs browser compares across runs,
    ``views.add_column(...)`` for columns of the tables of identified values,
    ``views.add_aggregation_view(AggregationView(...))`` for a figure of the Sequence tab drawing
    a sequence's aggregation.

    An analysis with no view of its own is drawn by the generic view (its datasets plotted with
    their units, and tabled): register one only to draw it better. Name the widget class with
    :class:`fsi_lab.contract.Deferred` so that the module implementing the hook imports no Qt.
    """


#: Hook name for each plugin kind.
HOOK_FOR_KIND = {
    "instrument": "fsi_lab_instruments",
    "excitation": "fsi_lab_excitations",
    "analysis": "fsi_lab_analyses",
}
