"""``fsi-lab plugin new``: the distributions it writes install into a fresh venv next to fsi-lab,
pass their own tests unchanged, and the analysis shows up everywhere a user looks for it:
``fsi-lab plugins``, ``fsi-lab analyze`` (JSON and text) and the GUI's generic view.

The venv is made without pip and sees the suite's environment (fsi-lab and its dependencies,
pytest, setuptools) through a ``.pth`` file; pip installs with ``--no-index`` and
``--no-build-isolation``: no network is needed. Every child process has a timeout, and the
venv and the distributions are deleted when the module's tests are done.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import h5py
import numpy as np
import pytest
from support import GOOD_PROFILE, cli

KINDS = ("analysis", "excitation", "instrument")
#: The colour of the first curve of a figure (fsi_lab.gui.analysis.plotting.COLOURS[0]).
FIRST_CURVE = (0x1F, 0x77, 0xB4)


def run(args, cwd=None, timeout=600) -> subprocess.CompletedProcess:
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen"}
    env.pop("PYTHONPATH", None)  # only what the venv sees
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, cwd=cwd,
                          timeout=timeout, env=env)


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    """A fresh venv with the three scaffolded distributions installed: (python, folder)."""
    folder = tmp_path_factory.mktemp("scaffold")
    for kind in KINDS:
        proc = cli("plugin", "new", kind, f"my-{kind}", "--dir", str(folder))
        assert proc.returncode == 0, proc.stderr
        assert f"wrote {folder}/fsi-lab-my-{kind}/" in proc.stdout
    made = run([sys.executable, "-m", "venv", "--without-pip", folder / "venv"])
    assert made.returncode == 0, made.stderr
    python = folder / "venv" / "bin" / "python"
    site = run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"])
    suite = sysconfig.get_paths()["purelib"]
    Path(site.stdout.strip(), "fsi-lab-suite.pth").write_text(
        f"import site; site.addsitedir({suite!r})\n")
    installed = run([python, "-m", "pip", "install", "--quiet", "--no-index",
                     "--no-build-isolation", *(folder / f"fsi-lab-my-{k}" for k in KINDS)])
    assert installed.returncode == 0, installed.stderr
    yield python, folder
    shutil.rmtree(folder, ignore_errors=True)


def test_each_scaffold_is_a_complete_distribution(venv):
    _, folder = venv
    root = folder / "fsi-lab-my-analysis"
    assert sorted(p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()
                  and "egg-info" not in p.as_posix() and "build" not in p.parts) == [
        "README.md", "fsi_lab_my_analysis/__init__.py", "fsi_lab_my_analysis/_compute.py",
        "fsi_lab_my_analysis/plugin.py", "pyproject.toml", "tests/test_my_analysis.py"]
    assert 'my-analysis = "fsi_lab_my_analysis.plugin"' in (root / "pyproject.toml").read_text()
    assert "from fsi_lab.testing import AnalysisContract" in \
        (root / "tests" / "test_my_analysis.py").read_text()


@pytest.mark.parametrize("kind, tests", [("analysis", 8), ("excitation", 24),
                                         ("instrument", 6)])
def test_a_scaffold_passes_its_tests_unchanged(venv, kind, tests):
    python, folder = venv
    proc = run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider"],
               cwd=folder / f"fsi-lab-my-{kind}")
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert f"{tests} passed" in proc.stdout


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", ["x", "abcdefghij-abcdefghij-abcdefghij-abcdefg"])
def test_a_scaffold_is_lint_clean_alone_and_inside_a_checkout(kind, name, tmp_path):
    """The files pass fsi-lab's rule set under the distribution's own ruff settings (fsi-lab
    a library it uses) with the shortest and the longest name accepted; written inside an
    fsi-lab checkout (the README's tour, no --dir), the checkout's `ruff check .` (make
    test's first step) passes too."""
    root = Path(__file__).resolve().parent.parent
    shutil.copy(root / "pyproject.toml", tmp_path / "pyproject.toml")
    proc = cli("plugin", "new", kind, name, "--dir", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    for where in (tmp_path / f"fsi-lab-{name}", tmp_path):
        lint = run([sys.executable, "-m", "ruff", "check", "--no-cache", "."], cwd=where)
        assert lint.returncode == 0, (where, lint.stdout + lint.stderr)


def test_the_scaffolded_analysis_is_listed_analysed_and_drawn(venv, tmp_path):
    python, _ = venv
    listed = run([python, "-m", "fsi_lab.cli", "plugins", "--json"])
    plugins = {p["name"]: p for p in json.loads(listed.stdout)["plugins"]}
    for kind in KINDS:
        assert plugins[f"my-{kind}"]["status"] == "loaded"
        assert plugins[f"my-{kind}"]["distribution"] == f"fsi-lab-my-{kind}"

    path = tmp_path / "run.h5"
    made = run([python, "-m", "fsi_lab.cli", "simulate", GOOD_PROFILE, "--duration", "2",
                "--rate", "2000", "-o", path])
    assert made.returncode == 0, made.stderr
    # as docs/writing-plugins.md does it: after a built-in, and drawn with --view
    analysed = run([python, "-m", "fsi_lab.cli", "analyze", path, "--set",
                    "analysis.chain=spectrum,my-analysis", "--json"])
    assert analysed.returncode == 0, analysed.stderr
    values = json.loads(analysed.stdout)["channels"]["tip_velocity"]["my_analysis"]
    with h5py.File(path, "r") as handle:  # the truth: the RMS of the record as stored
        tip = handle["channels/tip_velocity"][()]
        stored = handle["analysis/tip_velocity/my-analysis"]
        assert stored["rms"].attrs["units"] == "m/s" and stored["rms"].attrs["axis"] == "time"
    assert values["overall_rms"] == pytest.approx(np.sqrt(np.mean(tip ** 2)), rel=1e-12)
    text = run([python, "-m", "fsi_lab.cli", "show", path]).stdout
    assert f"  my_analysis.overall_rms: {values['overall_rms']:.4g}" in text.splitlines()

    shot = tmp_path / "shot.png"
    drawn = run([python, "-m", "fsi_lab.cli", "gui", path, "--view", "my-analysis",
                 "--screenshot", shot])
    assert drawn.returncode == 0, drawn.stderr
    assert first_curve_pixels(shot) > 100  # the 20 windows' RMS, drawn by the generic view
    wrong = run([python, "-m", "fsi_lab.cli", "gui", path, "--view", "no-such-view",
                 "--screenshot", tmp_path / "wrong.png"])
    assert wrong.returncode == 2
    assert "--view no-such-view: no view of that title or drawing that analysis for the run " \
           "shown; its views: " in wrong.stderr and "my-analysis" in wrong.stderr
    empty = tmp_path / "empty.h5"
    run([python, "-m", "fsi_lab.cli", "simulate", GOOD_PROFILE, "--duration", "2", "--rate",
         "2000", "-o", empty])
    run([python, "-m", "fsi_lab.cli", "gui", empty, "--screenshot", tmp_path / "none.png"])
    assert first_curve_pixels(tmp_path / "none.png") < 10  # the same window, nothing analysed


def first_curve_pixels(path: Path) -> int:
    """Pixels of the first curve's colour in a PNG."""
    from PySide6.QtGui import QImage

    image = QImage(str(path)).convertToFormat(QImage.Format.Format_RGB888)
    width, height = image.width(), image.height()
    data = np.frombuffer(image.constBits(), np.uint8, count=image.sizeInBytes())
    rgb = data.reshape(height, image.bytesPerLine())[:, :3 * width].reshape(height, width, 3)
    return int(np.all(rgb == FIRST_CURVE, axis=2).sum())


def test_the_scaffold_refuses_what_it_cannot_write(tmp_path):
    assert cli("plugin", "new", "analysis", "peaks", "--dir", str(tmp_path)).returncode == 0
    again = cli("plugin", "new", "analysis", "peaks", "--dir", str(tmp_path))
    assert again.returncode == 2
    assert f"{tmp_path}/fsi-lab-peaks: exists already; choose another NAME or --dir (nothing " \
           "was written)" in again.stderr
    bad = cli("plugin", "new", "analysis", "Peaks_2")
    assert bad.returncode == 2 and "'Peaks_2': expected lower-case words" in bad.stderr
    kind = cli("plugin", "new", "widget", "x")
    assert kind.returncode == 2 and "invalid choice: 'widget'" in kind.stderr
