"""Third-party plugins that break the rules, installed as real distributions: a plugin whose
hooks raise, one whose hooks return the wrong type, two plugins with one name (one of them a
built-in's), an entry point named like a built-in's, and an analysis declaring a result it
never returns. Each is named with what went wrong, and fsi-lab keeps working: ``fsi-lab
plugins`` lists everything, ``fsi-lab analyze`` analyses with the rest and prints its summaries.

The distributions are pip-installed (no index, no build isolation: no network) into a folder
put on PYTHONPATH of the fsi-lab processes; every process has a timeout.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from support import GOOD_PROFILE, cli

HOSTILE = '''
"""Hooks that raise, hooks that return the wrong type, and an analysis that lies."""
from fsi_lab.contract import AnalysisPlugin, AnalysisResult
from fsi_lab.hookspecs import hookimpl
from fsi_lab.presentation import SummaryText


def _rms(context, params):
    x = context.channel.data
    return AnalysisResult(datasets={"level": abs(x[:8]).copy()}, units={"level": "m/s"},
                          summary={"twin": {"first": float(x[0])}})


def _lies(context, params):
    return _rms(context, params)  # declares provides="components", returns no such result


def _crashes(context, params):
    return 1 / 0


class Raising:
    @hookimpl
    def fsi_lab_analyses(self):
        raise RuntimeError("descriptors exploded")

    @hookimpl
    def fsi_lab_summary_lines(self, channel):
        raise RuntimeError("summary exploded")

    @hookimpl
    def fsi_lab_default_chain(self):
        raise RuntimeError("chain exploded")

    @hookimpl
    def fsi_lab_addviews(self, views):
        raise RuntimeError("views exploded")

    @hookimpl
    def fsi_lab_addcommands(self, subparsers):
        raise RuntimeError("commands exploded")


class WrongTypes:
    @hookimpl
    def fsi_lab_analyses(self):
        return {"name": "not-a-list"}

    @hookimpl
    def fsi_lab_excitations(self):
        return [{"name": "not-a-descriptor"}]

    @hookimpl
    def fsi_lab_summary_lines(self):
        return "a string"

    @hookimpl
    def fsi_lab_default_chain(self):
        return "spectrum"

    @hookimpl
    def fsi_lab_addviews(self, views):
        views.add("a title")


class BadText:
    @hookimpl
    def fsi_lab_summary_lines(self):
        return SummaryText(inline=3)


class Twin:
    @hookimpl
    def fsi_lab_analyses(self):
        return [AnalysisPlugin("twin", (), _rms, help="One of two of this name.")]


class Shadow:
    @hookimpl
    def fsi_lab_analyses(self):
        return [AnalysisPlugin("hvd", (), _rms, help="Takes a built-in's name.")]


class Liar:
    @hookimpl
    def fsi_lab_analyses(self):
        return [AnalysisPlugin("liar", (), _lies, provides="components",
                               help="Declares a result it never returns."),
                AnalysisPlugin("crasher", (), _crashes, help="Divides by zero.")]


raising, wrong, bad_text = Raising(), WrongTypes(), BadText()
twin, shadow, liar = Twin(), Shadow(), Liar()
'''

DISTRIBUTIONS = {
    "fsi-lab-hostile": {
        "aaa-raising": "raising", "aaa-wrong": "wrong", "aaa-bad-text": "bad_text",
        "aaa-twin": "twin", "aaa-shadow": "shadow", "liar": "liar"},
    # a second distribution: the same analysis name, and a built-in's entry-point name
    "fsi-lab-hostile-too": {"zzz-twin": "twin", "spectrum": "twin"},
}


def write_distribution(root: Path, name: str, entry_points: dict[str, str]) -> Path:
    package = name.replace("-", "_")
    folder = root / name
    (folder / package).mkdir(parents=True)
    (folder / package / "__init__.py").write_text(HOSTILE)
    points = "\n".join(f'{ep} = "{package}:{obj}"' for ep, obj in entry_points.items())
    (folder / "pyproject.toml").write_text(f'''[build-system]
requires = ["setuptools>=68"]
build-backend = "setuptools.build_meta"

[project]
name = "{name}"
version = "6.6.6"

[project.entry-points.fsi_lab]
{points}

[tool.setuptools]
packages = ["{package}"]
''')
    return folder


@pytest.fixture(scope="module")
def hostile(tmp_path_factory) -> dict[str, str]:
    """The environment of an fsi-lab process that sees the hostile distributions."""
    root = tmp_path_factory.mktemp("hostile")
    target = root / "site"
    for name, entry_points in DISTRIBUTIONS.items():
        folder = write_distribution(root, name, entry_points)
        subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                        "--no-index", "--no-build-isolation", "--target", str(target),
                        str(folder)], check=True, timeout=300, capture_output=True)
    return {"PYTHONPATH": str(target)}


def records(env) -> tuple[list[dict], subprocess.CompletedProcess]:
    proc = cli("plugins", "--json", env=env)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)["plugins"], proc


def errors_of(plugins, entry_point) -> list[str]:
    return [p["error"] for p in plugins if p["entry_point"] == entry_point and p["error"]]


def test_each_broken_hook_is_named_with_its_plugin_and_the_rest_load(hostile):
    plugins, proc = records(hostile)
    raising = errors_of(plugins, "aaa-raising")
    for hook, what in (("fsi_lab_analyses", "descriptors"), ("fsi_lab_default_chain", "chain"),
                       ("fsi_lab_addviews", "views")):
        assert any(e.startswith(f"{hook}() failed: RuntimeError: {what} exploded (at ")
                   and "fsi_lab_hostile/__init__.py:" in e for e in raising), raising
    wrong = errors_of(plugins, "aaa-wrong")
    assert set(wrong) >= {
        "fsi_lab_analyses() returned dict, expected a list",
        "breaks the excitation contract: returned dict, expected ExcitationPlugin",
        "fsi_lab_default_chain() returned str 'spectrum', expected a list of analysis names"}
    (views,) = [e for e in wrong if e.startswith("fsi_lab_addviews()")]
    assert views.startswith("fsi_lab_addviews() failed: TypeError: views.add() takes an "
                            "fsi_lab.presentation.AnalysisView; got str (at ")
    assert "fsi_lab_hostile/__init__.py:" in views  # the plugin's line, not fsi-lab's
    # the warnings on stderr name each plugin, and every built-in still loads
    assert "[warning] plugin aaa-raising (fsi-lab-hostile): fsi_lab_analyses() " \
           "failed: RuntimeError: descriptors exploded" in proc.stderr
    assert "left out, its other contributions are loaded" in proc.stderr
    assert "[warning] commands of plugin aaa-raising (fsi-lab-hostile) skipped: " \
           "fsi_lab_addcommands() failed: RuntimeError: commands exploded" in proc.stderr
    own = {p["name"] for p in plugins if p["distribution"] == "fsi-lab" and
           p["status"] == "loaded"}
    assert {"hvd", "spectrum", "step", "keysight33500", "analysis-views"} <= own


def test_two_plugins_of_one_name_the_second_is_refused_naming_the_first(hostile):
    plugins, _ = records(hostile)
    twins = [p for p in plugins if p["name"] == "twin"]
    assert [(p["entry_point"], p["status"]) for p in twins] == [
        ("aaa-twin", "loaded"), ("zzz-twin", "invalid")]
    assert twins[1]["error"] == ("another analysis plugin is already named 'twin' (entry point "
                                 "'aaa-twin' of fsi-lab-hostile 6.6.6); this one is left out: "
                                 "rename it")
    # a built-in's name stays the built-in's, though the entry point sorts before it
    hvd = [p for p in plugins if p["name"] == "hvd"]
    assert [(p["distribution"], p["status"]) for p in hvd] == [
        ("fsi-lab", "loaded"), ("fsi-lab-hostile", "invalid")]
    assert hvd[1]["error"].startswith("another analysis plugin is already named 'hvd' (entry "
                                      "point 'hvd' of fsi-lab ")
    # an entry point named like a built-in's is refused, the built-in kept
    (clash,) = [p for p in plugins if p["distribution"] == "fsi-lab-hostile-too"
                and p["entry_point"] == "spectrum"]
    assert clash["status"] == "failed"
    assert clash["error"] == ("entry point 'spectrum' (fsi_lab_hostile_too:twin) has the name "
                              "of fsi-lab's (fsi_lab.plugins.analysis.spectrum), and fsi-lab "
                              "registers plugins by entry-point name: rename it in "
                              "fsi-lab-hostile-too's [project.entry-points.fsi_lab]")


def test_analyze_goes_on_naming_each_plugin_that_failed(hostile, tmp_path):
    path = tmp_path / "run.h5"
    made = cli("simulate", str(GOOD_PROFILE), "--duration", "2", "--rate", "2000", "-o",
               str(path), env=hostile)
    assert made.returncode == 0, made.stderr
    proc = cli("analyze", str(path), "--set", "analysis.chain=spectrum,liar,crasher,twin",
               env=hostile, timeout=300)
    # Every analysis ran; the only one that provides components (liar) was refused, so the
    # record's identification is: exit 2, saying so, with every other result printed.
    assert proc.returncode == 2, proc.stderr
    assert f"{path}: nothing was identified: channel tip_velocity: liar on channel " \
           "'tip_velocity': TypeError" in proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("channel tip_velocity: spectrum peaks ")
    assert "  twin.first: " in "\n".join(lines)  # the working third-party analysis
    text = "\n".join(lines)
    assert "  failed liar: liar on channel 'tip_velocity': TypeError: returned an AnalysisResult " \
           "but declares provides='components'; return the typed result of that kind" in text
    assert "  failed crasher: crasher on channel 'tip_velocity': ZeroDivisionError: division " \
           "by zero" in text
    assert "(plugin aaa-raising: fsi_lab_summary_lines() failed: RuntimeError: summary " \
           "exploded (at " in text
    assert "(plugin aaa-wrong: fsi_lab_summary_lines() returned str 'a string', expected " \
           "fsi_lab.presentation.SummaryText or None)" in text
    assert "(plugin aaa-bad-text: fsi_lab_summary_lines() failed: TypeError: SummaryText: " \
           "inline is a string; got int (at " in text
