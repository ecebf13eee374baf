"""How plugins show analysis results: summary text, GUI views, compared curves, table columns,
figures of a sequence's aggregation.

The descriptors a plugin gives through the ``fsi_lab_summary_lines`` and ``fsi_lab_addviews``
hooks (:mod:`fsi_lab.hookspecs`). This module imports no Qt: a view's widget is named by a
callable (normally a :class:`fsi_lab.contract.Deferred`) that the GUI calls when it builds its
tabs. What no plugin describes is shown generically: an analysis's datasets by the GUI's
generic view, its scalar summary values as ``key: value`` lines and table columns.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class SummaryText:
    """What one plugin shows of a channel's or a component's summary in the text summary.

    Attributes
    ----------
    keys
        Summary keys this text shows (or deliberately leaves out): they are not shown again as
        plain ``key: value`` lines, nor as generic table columns in the GUI.
    inline
        Text appended to the channel's line (``channel tip_velocity``) or the component's
        (``component 0 at 17.061 Hz``); start it with ``": "`` or ``", "``.
    lines
        Lines shown below it, without indentation (the core indents them).
    """

    keys: tuple[str, ...] = ()
    inline: str = ""
    lines: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if isinstance(self.keys, str) or isinstance(self.lines, str):
            raise TypeError("SummaryText: keys and lines are tuples of strings, not a string")
        object.__setattr__(self, "keys", tuple(self.keys))
        object.__setattr__(self, "lines", tuple(self.lines))
        if not isinstance(self.inline, str):
            raise TypeError(f"SummaryText: inline is a string; got "
                            f"{type(self.inline).__name__}")
        for what in ("keys", "lines"):
            wrong = [item for item in getattr(self, what) if not isinstance(item, str)]
            if wrong:
                raise TypeError(f"SummaryText: {what} are strings; got {wrong[0]!r} "
                                f"({type(wrong[0]).__name__})")


@dataclass(frozen=True)
class AnalysisView:
    """A tab of the GUI's Analysis panel that draws the results of some analyses.

    Attributes
    ----------
    title
        Tab title.
    analyses
        Names of the analyses whose results it draws: they get no generic tab of their own.
    view
        Called with no argument, returns the widget: a
        :class:`fsi_lab.gui.analysis.view.View` subclass (``draw(results, channel)`` drawing a
        run's results), normally named ``Deferred("my_package.my_view:MyView")`` so that the
        module implementing the hook imports no Qt.
    order
        Tabs are sorted by it, then by title (fsi-lab's own views: 0 to 90; generic views of
        analyses without one: 500; the Results and All datasets tabs: 1000 and 1001).
    """

    title: str
    analyses: tuple[str, ...]
    view: Callable[[], Any]
    order: int = 100

    def __post_init__(self) -> None:
        if isinstance(self.analyses, str):
            raise TypeError(f"AnalysisView {self.title!r}: analyses is a tuple of analysis "
                            f"names; write analyses=({self.analyses!r},)")
        if not callable(self.view):
            raise TypeError(f"AnalysisView {self.title!r}: view must be callable (a widget "
                            "class, or Deferred('package.module:Class'))")
        object.__setattr__(self, "analyses", tuple(self.analyses))


@dataclass(frozen=True)
class AggregationView:
    """A figure of the GUI's Sequence tab that draws a sequence's aggregation (the record's
    ``aggregate``: :mod:`fsi_lab.aggregate`, layout in docs/sequence-format.md, "Aggregation").

    Attributes
    ----------
    title
        Title of the figure (a tab of its own when several are registered).
    view
        Called with no argument, returns the widget: a QWidget with ``draw(aggregate)``
        drawing the aggregation (a dict, or None when there is none yet) and returning whether
        it drew something. Name it with ``Deferred("my_package.my_view:MyView")`` so that the
        module implementing the hook imports no Qt.
    order
        Figures are sorted by it, then by title.
    """

    title: str
    view: Callable[[], Any]
    order: int = 100

    def __post_init__(self) -> None:
        if not callable(self.view):
            raise TypeError(f"AggregationView {self.title!r}: view must be callable (a widget "
                            "class, or Deferred('package.module:Class'))")


@dataclass(frozen=True)
class ComparisonCurve:
    """A curve the runs browser overlays across the ticked runs (and exports as CSV), one per
    component: a dataset ``y`` against a dataset ``x`` of one analysis (rows per component).

    Attributes
    ----------
    name
        Name of the curve (plot title, CSV ``curve`` column).
    analysis
        The analysis whose datasets hold it.
    x, y
        Dataset names.
    x_label, y_label
        Axis labels.
    x_unit, y_unit
        Units of the axes (None: none).
    x_name, y_name
        Names of the values in the CSV export (``displacement_amplitude_m``).
    summary
        Where a run whose datasets lack the curve keeps it in its summary: ``(section, x key,
        y key)`` of each component entry; None: nowhere.
    x_label_for
        Called with the runs compared, a list of ``(RunResults, channel)``, returns the x
        axis's label for them, where what ``x`` holds depends on the run (the amplitude at its
        specimen's measuring point, or in a modal coordinate); None, or no run compared:
        ``x_label``. Name it with ``Deferred`` to keep Qt out of the hook's module.
    """

    name: str
    analysis: str
    x: str
    y: str
    x_label: str
    y_label: str
    x_unit: str | None = None
    y_unit: str | None = None
    x_name: str = "x"
    y_name: str = "y"
    summary: tuple[str, str, str] | None = None
    x_label_for: Callable[[list[tuple[Any, str]]], str] | None = None

    def __post_init__(self) -> None:
        if self.x_label_for is not None and not callable(self.x_label_for):
            raise TypeError(f"ComparisonCurve {self.name!r}: x_label_for must be callable "
                            "(a function of the runs compared, or Deferred('package.module:"
                            "function'))")


@dataclass(frozen=True)
class SummaryColumn:
    """A column of the tables of identified values (the Analysis panel's Results, the runs
    browser's table and CSV export): one value of each component's summary entry.

    Attributes
    ----------
    name
        Column name in the CSV export (``c_i``).
    label
        Column header in the GUI (``C_i (kg/(m s))``).
    key
        Where the value is in a component entry, levels joined by dots
        (``equivalent_damping.c_i``).
    interval
        Where its 95 % interval ``[low, high]`` is, or None (CSV columns ``<name>_ci95_low``
        and ``<name>_ci95_high``, a ``<label> 95 %`` column in the GUI).
    order
        Columns are sorted by it.
    """

    name: str
    label: str
    key: str
    interval: str | None = None
    order: int = 100

    def value(self, component: dict[str, Any]) -> Any:
        """The column's value in a component entry, or None."""
        return lookup(component, self.key)

    def bounds(self, component: dict[str, Any]) -> tuple[Any, Any]:
        """The value's 95 % interval in a component entry, ``(None, None)`` when absent."""
        found = lookup(component, self.interval) if self.interval else None
        if isinstance(found, (list, tuple)) and len(found) == 2:
            return found[0], found[1]
        return None, None


def lookup(entry: Any, key: str) -> Any:
    """``entry["a"]["b"]`` for ``key`` ``"a.b"``; None where a level is missing."""
    for part in key.split("."):
        if not isinstance(entry, dict):
            return None
        entry = entry.get(part)
    return entry


def _require(method: str, kind: type, item: Any) -> None:
    """Refuse ``views.<method>(item)`` unless ``item`` is a ``kind``, naming what was given."""
    if not isinstance(item, kind):
        raise TypeError(f"views.{method}() takes an fsi_lab.presentation.{kind.__name__}; got "
                        f"{type(item).__name__}")


@dataclass
class ViewSet:
    """What the ``fsi_lab_addviews(views)`` hook registers into: the GUI's views, the curves
    the runs browser compares, the columns of the tables of identified values and the figures
    of a sequence's aggregation.

    Attributes
    ----------
    views, curves, columns, aggregation_views
        What was added, in order.
    owners
        The plugin that added each title, curve name or column name (for messages).
    current
        The plugin whose hook is being called (set by the registry).
    """

    views: list[AnalysisView] = field(default_factory=list)
    curves: list[ComparisonCurve] = field(default_factory=list)
    columns: list[SummaryColumn] = field(default_factory=list)
    aggregation_views: list[AggregationView] = field(default_factory=list)
    owners: dict[tuple[str, str], str] = field(default_factory=dict)
    current: str = ""

    def _claim(self, what: str, name: str) -> None:
        owner = self.owners.get((what, name))
        if owner is not None:
            raise ValueError(f"a {what} named {name!r} is already registered by {owner}")
        self.owners[(what, name)] = self.current

    def add(self, view: AnalysisView) -> None:
        """Add a tab of the Analysis panel."""
        _require("add", AnalysisView, view)
        self._claim("view", view.title)
        self.views.append(view)

    def add_curve(self, curve: ComparisonCurve) -> None:
        """Add a curve the runs browser compares across runs."""
        _require("add_curve", ComparisonCurve, curve)
        self._claim("curve", curve.name)
        self.curves.append(curve)

    def add_column(self, column: SummaryColumn) -> None:
        """Add a column of the tables of identified values."""
        _require("add_column", SummaryColumn, column)
        self._claim("column", column.name)
        self.columns.append(column)

    def add_aggregation_view(self, view: AggregationView) -> None:
        """Add a figure of the Sequence tab drawing a sequence's aggregation."""
        _require("add_aggregation_view", AggregationView, view)
        self._claim("aggregation view", view.title)
        self.aggregation_views.append(view)

    def drawn(self) -> set[str]:
        """Names of the analyses some registered view draws."""
        return {name for view in self.views for name in view.analyses}
