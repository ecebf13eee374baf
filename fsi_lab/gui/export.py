"""Exports: figures as PNG or SVG, results and curves as CSV."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
from PySide6.QtCore import QRect
from PySide6.QtGui import QColor, QImage, QPainter
from PySide6.QtSvg import QSvgGenerator
from PySide6.QtWidgets import QWidget

FIGURE_SUFFIXES = (".png", ".svg")


def export_figure(widget: QWidget, path: str | Path, scale: float = 2.0) -> Path:
    """Write what ``widget`` shows (a plot or a layout of plots) to ``path``.

    PNG is rendered at ``scale`` times the on-screen size; SVG is vector (Qt's SVG generator:
    pyqtgraph's own SVG exporter cannot read the paths Qt 6.12 writes).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FIGURE_SUFFIXES:
        raise ValueError(f"{path}: figures are exported as {' or '.join(FIGURE_SUFFIXES)}")
    path.parent.mkdir(parents=True, exist_ok=True)
    size = widget.size()
    if suffix == ".png":
        image = QImage(int(size.width() * scale), int(size.height() * scale),
                       QImage.Format.Format_ARGB32)
        image.fill(QColor("white"))
        painter = QPainter(image)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        painter.scale(scale, scale)
        widget.render(painter)
        painter.end()
        if not image.save(str(path)):
            raise OSError(f"{path}: cannot write the image")
        return path
    generator = QSvgGenerator()
    generator.setFileName(str(path))
    generator.setSize(size)
    generator.setViewBox(QRect(0, 0, size.width(), size.height()))
    generator.setTitle(path.stem)
    generator.setDescription("exported by fsi-lab")
    painter = QPainter(generator)
    widget.render(painter)
    painter.end()
    if not path.exists():
        raise OSError(f"{path}: cannot write the drawing")
    return path


def _cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (np.floating, np.integer)):
        return repr(value.item())
    return value


def write_csv(path: str | Path, columns: Sequence[str], rows: Iterable[Mapping[str, Any]]) -> Path:
    """One header line, then one line per row (missing values empty)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(row.get(column)) for column in columns])
    return path
