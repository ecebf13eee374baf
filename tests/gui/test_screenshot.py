"""``fsi-lab gui RUN.h5 --screenshot OUT.png`` renders the run's analysis and exits."""

import argparse
import sys

from conftest import write_corrupt, write_run

from fsi_lab.gui.app import main


def _png(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    return width, height


def test_screenshot_in_process(qapp, tmp_path):
    out = tmp_path / "shot.png"
    code = main(argparse.Namespace(paths=[write_run(tmp_path / "run.h5")], screenshot=out))
    assert code == 0
    assert _png(out) == (1366, 768)
    assert out.stat().st_size > 50_000                  # plots, not an empty window


def test_screenshot_is_the_same_picture_every_time(qapp, tmp_path):
    from PySide6.QtGui import QImage

    run = write_run(tmp_path / "run.h5", hvd_components=3)
    pictures = []
    for k in range(2):
        out = tmp_path / f"shot{k}.png"
        assert main(argparse.Namespace(paths=[run], screenshot=out)) == 0
        pictures.append(QImage(str(out)))
    assert pictures[0].size().toTuple() == (1366, 768)
    assert pictures[0] == pictures[1]


def test_screenshot_of_a_corrupt_file_reports_and_exits(qapp, tmp_path, capsys):
    out = tmp_path / "bad.png"
    code = main(argparse.Namespace(paths=[write_corrupt(tmp_path / "bad.h5")], screenshot=out))
    assert code == 2 and out.exists()
    assert "not a readable HDF5 file" in capsys.readouterr().err


def test_screenshot_through_the_command(tmp_path):
    import os
    import subprocess

    out = tmp_path / "cli.png"
    proc = subprocess.run(
        [sys.executable, "-m", "fsi_lab.cli", "gui", str(write_run(tmp_path / "c.h5")),
         "--screenshot", str(out)], capture_output=True, text=True, timeout=600,
        env={**os.environ, "QT_QPA_PLATFORM": "offscreen"})
    assert proc.returncode == 0, proc.stderr
    assert _png(out) == (1366, 768)
    assert "propagateSizeHints" not in proc.stderr  # the offscreen platform's remark


def test_qt_s_offscreen_size_hint_message_alone_is_silenced(qtlog):
    from PySide6.QtCore import qWarning

    from fsi_lab.gui.app import quiet_qt_messages

    restore = quiet_qt_messages()
    try:
        qWarning("This plugin does not support propagateSizeHints()")
        qWarning("another Qt warning")
    finally:
        restore()
    said = [record.message for record in qtlog.records]
    assert "another Qt warning" in said
    assert not any("propagateSizeHints" in text for text in said)
