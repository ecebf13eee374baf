"""Whether Qt can open a window here, told before Qt tries (it aborts the process when it
cannot), and the system libraries its X11 platform plugin needs.

PySide6's wheels carry Qt but not the X11 client libraries Qt's ``xcb`` platform plugin loads;
a desktop usually has them, a fresh server or container often lacks ``libxcb-cursor0``,
``libxcb-icccm4`` and ``libxcb-keysyms1``. ``python -m fsi_lab.gui.display --missing-packages``
prints the Debian/Ubuntu packages of those that cannot be loaded (``make gui`` installs them
where it may). Rendering to a file (``fsi-lab gui RUN.h5 --screenshot OUT.png``) needs none of
them: it uses Qt's ``offscreen`` platform.
"""

from __future__ import annotations

import ctypes
import os
import sys
from typing import Callable, Mapping

#: The shared libraries Qt's xcb platform plugin (PySide6 6.x) loads, with the Debian/Ubuntu
#: package that provides each.
XCB_LIBRARIES = {
    "libxcb-cursor.so.0": "libxcb-cursor0",
    "libxcb-icccm.so.4": "libxcb-icccm4",
    "libxcb-keysyms.so.1": "libxcb-keysyms1",
    "libxcb-image.so.0": "libxcb-image0",
    "libxcb-randr.so.0": "libxcb-randr0",
    "libxcb-render-util.so.0": "libxcb-render-util0",
    "libxcb-render.so.0": "libxcb-render0",
    "libxcb-shape.so.0": "libxcb-shape0",
    "libxcb-shm.so.0": "libxcb-shm0",
    "libxcb-sync.so.1": "libxcb-sync1",
    "libxcb-util.so.1": "libxcb-util1",
    "libxcb-xfixes.so.0": "libxcb-xfixes0",
    "libxcb-xkb.so.1": "libxcb-xkb1",
    "libxcb.so.1": "libxcb1",
    "libxkbcommon-x11.so.0": "libxkbcommon-x11-0",
    "libxkbcommon.so.0": "libxkbcommon0",
    "libX11-xcb.so.1": "libx11-xcb1",
    "libX11.so.6": "libx11-6",
    "libEGL.so.1": "libegl1",
    "libGL.so.1": "libgl1",
    "libfontconfig.so.1": "libfontconfig1",
    "libfreetype.so.6": "libfreetype6",
    "libdbus-1.so.3": "libdbus-1-3",
    "libglib-2.0.so.0": "libglib2.0-0",
}


def _loads(name: str) -> bool:
    try:
        ctypes.CDLL(name)
    except OSError:
        return False
    return True


def missing_libraries(loads: Callable[[str], bool] = _loads) -> list[str]:
    """The libraries of :data:`XCB_LIBRARIES` the dynamic loader cannot find."""
    return [name for name in XCB_LIBRARIES if not loads(name)]


def window_problem(environ: Mapping[str, str] = os.environ, platform: str = sys.platform,
                   loads: Callable[[str], bool] = _loads) -> str | None:
    """Why Qt could not open a window with this environment, or None when it can (or when
    the platform was chosen with ``QT_QPA_PLATFORM``, or is not Linux: Qt is left to try)."""
    if environ.get("QT_QPA_PLATFORM") or not platform.startswith("linux"):
        return None
    if environ.get("WAYLAND_DISPLAY"):
        return None  # Qt's wayland plugin; its libraries come with the compositor
    if not environ.get("DISPLAY"):
        return ("there is no display to open the window on (DISPLAY and WAYLAND_DISPLAY are "
                "unset): start it from a desktop session, or render a run file to a picture "
                "with --screenshot OUT.png, which needs no display")
    missing = missing_libraries(loads)
    if missing:
        packages = " ".join(XCB_LIBRARIES[name] for name in missing)
        return (f"Qt's X11 platform plugin needs system libraries this machine lacks "
                f"({', '.join(missing)}); install them with `make gui` (as root) or "
                f"`sudo apt-get install {packages}` (Debian/Ubuntu package names)")
    return None


def main(argv: list[str] | None = None) -> int:
    """``python -m fsi_lab.gui.display --missing-packages``: the packages to install."""
    args = sys.argv[1:] if argv is None else argv
    if args != ["--missing-packages"]:
        print("usage: python -m fsi_lab.gui.display --missing-packages", file=sys.stderr)
        return 2
    print(" ".join(XCB_LIBRARIES[name] for name in missing_libraries()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
