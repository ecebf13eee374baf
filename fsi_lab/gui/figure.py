"""Figures that hold together: a layout of plots that always fills its widget and never shrinks
below a readable size, and a legend outside the plots.

:class:`Figure` is the pyqtgraph layout widget every figure of the window uses. Its central
layout item always takes the widget's size (Qt clamps a top-level layout item to its layout's
maximum size, and the maximum of a layout whose plots are all hidden is its margins: a figure
resized in that state, on a tab not shown yet or in the middle of a drawing, kept an 18-pixel
layout and its plots collapsed to stubs once shown). Every plot it holds has a minimum size, and
the widget's minimum size follows the plots it shows (:meth:`Figure.fit_minimum`), so a window
too small for a figure scrolls (the figures sit in scroll areas) instead of squashing it.

:class:`Legend` lists a figure's named curves above its plots, each with its line or marker
drawn as in the plot, wrapped to the figure's width: it never covers the data.

:meth:`Figure.release` takes the figure's items down while the window still exists (linked axes
first, then the scene), so that nothing is left pointing at a deleted item when the window goes.
"""

from __future__ import annotations

import base64
import html
import math
from typing import Iterable, Sequence

import pyqtgraph as pg
from pyqtgraph import functions as fn
from pyqtgraph.graphicsItems.ScatterPlotItem import drawSymbol
from PySide6.QtCore import QBuffer, QByteArray, QIODevice, QPoint, QPointF, QRect, QSize, QSizeF, Qt
from PySide6.QtGui import QPainter, QPixmap
from PySide6.QtWidgets import QLabel, QLayout, QScrollArea, QSizePolicy, QWidget

#: The smallest a plot of a figure becomes (axes included), in pixels.
MIN_PLOT_WIDTH = 240
MIN_PLOT_HEIGHT = 150
#: Qt's largest widget size.
UNBOUNDED = float((1 << 24) - 1)


class Figure(pg.GraphicsLayoutWidget):
    """A grid of plots (``addPlot(row, col)``) that fills the widget and keeps a readable size.

    Parameters
    ----------
    min_plot
        Minimum (width, height) of each plot, axes included, in pixels.
    """

    def __init__(self, min_plot: tuple[float, float] = (MIN_PLOT_WIDTH, MIN_PLOT_HEIGHT),
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.min_plot = min_plot
        self.ci.setMaximumSize(QSizeF(UNBOUNDED, UNBOUNDED))
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.addPlot = self._add_plot  # pyqtgraph binds the layout's own to the instance

    def _add_plot(self, *args, **kwargs) -> pg.PlotItem:
        """``addPlot(row, col, ...)`` of the layout, with the figure's minimum plot size."""
        plot = self.ci.addPlot(*args, **kwargs)
        plot.setMinimumSize(QSizeF(*self.min_plot))
        return plot

    def plots(self, visible_only: bool = True) -> list[pg.PlotItem]:
        """The plots of the figure (those shown, by default)."""
        return [item for item in self.ci.items if isinstance(item, pg.PlotItem)
                and (item.isVisible() or not visible_only)]

    def fit_minimum(self) -> None:
        """Make the widget's minimum size that of the plots it shows (call after a drawing)."""
        layout = self.ci.layout
        layout.invalidate()
        size = layout.effectiveSizeHint(Qt.SizeHint.MinimumSize)
        self.setMinimumSize(math.ceil(size.width()), math.ceil(size.height()))

    def release(self) -> None:
        """Take the items down in order: unlink the axes, then delete the scene's items."""
        for plot in self.plots(visible_only=False):
            plot.setXLink(None)
            plot.setYLink(None)
        self.close()  # pyqtgraph: clears the scene and ignores later resizes


class FlowLayout(QLayout):
    """Lays its items out left to right, wrapping to the next line when the width runs out."""

    def __init__(self, parent: QWidget | None = None, spacing: int = 12,
                 line_spacing: int = 2) -> None:
        super().__init__(parent)
        self._items: list = []
        self._spacing = spacing
        self._line_spacing = line_spacing
        self.setContentsMargins(0, 0, 0, 0)

    def addItem(self, item) -> None:
        self._items.append(item)

    def count(self) -> int:
        return len(self._items)

    def itemAt(self, index: int):
        return self._items[index] if 0 <= index < len(self._items) else None

    def takeAt(self, index: int):
        return self._items.pop(index) if 0 <= index < len(self._items) else None

    def expandingDirections(self):
        return Qt.Orientation(0)

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        return self._arrange(QRect(0, 0, width, 0), move=False)

    def setGeometry(self, rect: QRect) -> None:
        super().setGeometry(rect)
        self._arrange(rect, move=True)

    def sizeHint(self) -> QSize:
        return self.minimumSize()

    def minimumSize(self) -> QSize:
        size = QSize()
        for item in self._items:
            size = size.expandedTo(item.minimumSize())
        margins = self.contentsMargins()
        return size + QSize(margins.left() + margins.right(), margins.top() + margins.bottom())

    def _arrange(self, rect: QRect, move: bool) -> int:
        margins = self.contentsMargins()
        area = rect.adjusted(margins.left(), margins.top(), -margins.right(), -margins.bottom())
        x, y, line_height = area.x(), area.y(), 0
        for item in self._items:
            hint = item.sizeHint()
            if x > area.x() and x + hint.width() > area.right() + 1:
                x, y = area.x(), y + line_height + self._line_spacing
                line_height = 0
            if move:
                item.setGeometry(QRect(QPoint(x, y), hint))
            x += hint.width() + self._spacing
            line_height = max(line_height, hint.height())
        return y + line_height - rect.y() + margins.bottom()


class Legend(QWidget):
    """The legend of a figure, outside its plots: each named curve with its line or marker,
    entries wrapped to the figure's width (an entry is never broken)."""

    SAMPLE_WIDTH = 28
    SAMPLE_HEIGHT = 14

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("legend")
        self.flow = FlowLayout(self)
        policy = QSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Minimum)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.entries: list[str] = []
        self._labels: list[QLabel] = []
        self._samples: dict[tuple, str] = {}

    def show_items(self, items: Iterable[pg.PlotDataItem]) -> None:
        """List the named ``items`` in their order, once per name and colour: a curve drawn as
        a line in one plot and as markers in another (a component's curve against time and its
        points against amplitude) is one entry whose sample shows both."""
        merged: dict[tuple, list] = {}
        for item in items:
            name = item.name() if hasattr(item, "name") else None
            if not name:
                continue
            colour, width, style, symbol, symbol_colour = self._look(item)
            entry = merged.setdefault((name, colour or symbol_colour), [None, 1.2, 1, None, None])
            if colour is not None and entry[0] is None:
                entry[0:3] = [colour, width, style]
            if symbol is not None and entry[3] is None:
                entry[3:5] = [symbol, symbol_colour]
        self.show_entries([(name, tuple(look)) for (name, _), look in merged.items()])

    def show_entries(self, entries: Sequence[tuple[str, tuple]]) -> None:
        """``entries``: (text, look) pairs, a look as made by :meth:`look`."""
        texts = [f'<img src="{self._sample(look)}" width="{self.SAMPLE_WIDTH}" '
                 f'height="{self.SAMPLE_HEIGHT}">&nbsp;{html.escape(name)}'
                 for name, look in entries]
        if texts != [label.text() for label in self._labels]:
            while self._labels:
                label = self._labels.pop()
                self.flow.removeWidget(label)
                label.deleteLater()
            for text in texts:
                label = QLabel(text)
                label.setTextFormat(Qt.TextFormat.RichText)
                self.flow.addWidget(label)
                self._labels.append(label)
        self.entries = [name for name, _ in entries]
        self.setVisible(bool(entries))

    def clear_entries(self) -> None:
        self.show_entries([])

    @staticmethod
    def look(colour: str | None = None, width: float = 1.2, style=Qt.PenStyle.SolidLine,
             symbol: str | None = None, symbol_colour: str | None = None) -> tuple:
        """The look of a legend sample: a line (``colour`` None: none) and/or a marker."""
        return (colour, float(width), int(style.value) if hasattr(style, "value") else int(style),
                symbol, symbol_colour)

    @classmethod
    def _look(cls, item: pg.PlotDataItem) -> tuple:
        opts = item.opts
        pen = fn.mkPen(opts.get("pen"))
        colour = None if pen.style() == Qt.PenStyle.NoPen else pen.color().name()
        symbol = opts.get("symbol")
        symbol_colour = None
        if symbol is not None:
            symbol_colour = fn.mkBrush(opts.get("symbolBrush")).color().name()
        return cls.look(colour, pen.widthF() or 1.0, pen.style(),
                        symbol if isinstance(symbol, str) else None, symbol_colour)

    def _sample(self, look: tuple) -> str:
        """The sample of ``look`` as a data URL (PNG), drawn once."""
        url = self._samples.get(look)
        if url is not None:
            return url
        colour, width, style, symbol, symbol_colour = look
        ratio = 2  # drawn at twice the size: sharp on high-density screens too
        pixmap = QPixmap(self.SAMPLE_WIDTH * ratio, self.SAMPLE_HEIGHT * ratio)
        pixmap.fill(Qt.GlobalColor.transparent)
        painter = QPainter(pixmap)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        painter.scale(ratio, ratio)
        middle = self.SAMPLE_HEIGHT / 2
        if colour is not None:
            pen = fn.mkPen(colour, width=max(width, 1.5))
            pen.setStyle(Qt.PenStyle(style))
            painter.setPen(pen)
            painter.drawLine(QPointF(1, middle), QPointF(self.SAMPLE_WIDTH - 1, middle))
        if symbol is not None:
            painter.translate(self.SAMPLE_WIDTH / 2, middle)
            drawSymbol(painter, symbol, 8, fn.mkPen(None), fn.mkBrush(symbol_colour or "k"))
        painter.end()
        data = QByteArray()
        buffer = QBuffer(data)
        buffer.open(QIODevice.OpenModeFlag.WriteOnly)
        pixmap.save(buffer, "PNG")
        url = "data:image/png;base64," + base64.b64encode(bytes(data)).decode("ascii")
        self._samples[look] = url
        return url


def scrolled(widget: QWidget) -> QScrollArea:
    """``widget`` in a frameless scroll area that gives it all the room there is, and scrolls
    when there is less than the widget's minimum (its figures never collapse)."""
    area = QScrollArea()
    area.setWidgetResizable(True)
    area.setFrameShape(QScrollArea.Shape.NoFrame)
    area.setWidget(widget)
    return area
