"""Exports: figures as PNG or SVG, results and curves as CSV."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pyqtgraph as pg
import pyqtgraph.exporters  # noqa: F401 - registers the exporters

FIGURE_SUFFIXES = (".png", ".svg")


def export_figure(item: Any, path: str | Path, width: int | None = None) -> Path:
    """Write a pyqtgraph scene, layout or plot to ``path`` (.png or .svg by its suffix)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FIGURE_SUFFIXES:
        raise ValueError(f"{path}: figures are exported as {' or '.join(FIGURE_SUFFIXES)}")
    if isinstance(item, pg.GraphicsLayoutWidget):
        item = item.scene()
    elif isinstance(item, pg.PlotWidget):
        item = item.getPlotItem()
    if suffix == ".png":
        exporter = pg.exporters.ImageExporter(item)
        if width:
            exporter.parameters()["width"] = int(width)
    else:
        exporter = pg.exporters.SVGExporter(item)
    path.parent.mkdir(parents=True, exist_ok=True)
    exporter.export(str(path))
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
