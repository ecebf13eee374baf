"""Without a display or Qt's X11 libraries, ``fsi-lab gui`` says so (exit 2) instead of letting
Qt abort the process; ``--screenshot`` needs neither: it renders offscreen."""

import os
import subprocess
import sys

from conftest import write_run
from support import cli

from fsi_lab.gui.display import XCB_LIBRARIES, missing_libraries, window_problem

LACKING = {"libxcb-cursor.so.0", "libxcb-icccm.so.4", "libxcb-keysyms.so.1"}


def test_no_display_is_named_with_the_way_out():
    problem = window_problem({"PATH": "/usr/bin"}, "linux", loads=lambda name: True)
    assert "no display" in problem and "--screenshot" in problem


def test_missing_x11_libraries_are_named_with_their_packages():
    problem = window_problem({"DISPLAY": ":0"}, "linux", loads=lambda name: name not in LACKING)
    assert problem is not None
    for name in LACKING:
        assert name in problem and XCB_LIBRARIES[name] in problem
    assert "make gui" in problem
    assert missing_libraries(lambda name: name not in LACKING) == [
        n for n in XCB_LIBRARIES if n in LACKING]


def test_nothing_to_say_when_qt_can_open_a_window_or_was_told_where():
    everything = lambda name: True
    nothing = lambda name: False
    assert window_problem({"DISPLAY": ":0"}, "linux", everything) is None
    assert window_problem({"QT_QPA_PLATFORM": "offscreen"}, "linux", nothing) is None
    assert window_problem({"WAYLAND_DISPLAY": "wayland-0"}, "linux", nothing) is None
    assert window_problem({}, "darwin", nothing) is None


def _without_display():
    return {k: v for k, v in os.environ.items()
            if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}


def test_the_window_without_a_display_is_refused_with_a_message(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.cli", "gui"], capture_output=True,
                          text=True, timeout=600, env=_without_display(), cwd=tmp_path)
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert "no display" in proc.stderr and "Traceback" not in proc.stderr


def test_screenshot_without_a_display_renders_offscreen(tmp_path):
    out = tmp_path / "shot.png"
    proc = subprocess.run(
        [sys.executable, "-m", "fsi_lab.cli", "gui", str(write_run(tmp_path / "r.h5")),
         "--screenshot", str(out), "--size", "1024x700"],
        capture_output=True, text=True, timeout=600, env=_without_display())
    assert proc.returncode == 0, proc.stderr
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert (int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")) == (1024, 700)


def test_a_bad_window_size_is_refused():
    proc = cli("gui", "--size", "big")
    assert proc.returncode == 2 and "WIDTHxHEIGHT" in proc.stderr


def test_the_packages_to_install_are_listed_for_make(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.gui.display", "--missing-packages"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert set(proc.stdout.split()) <= set(XCB_LIBRARIES.values())
