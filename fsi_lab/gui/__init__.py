"""The desktop application (PySide6 + pyqtgraph), imported only by ``fsi-lab gui``.

It holds no logic of its own: it drives the same runner, events and plugins as the command line.
"""

from fsi_lab.gui.qt_compat import guard_singleton_refcounts

guard_singleton_refcounts()
