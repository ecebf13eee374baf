"""docs/writing-plugins.md: its Python examples are valid code, and the tutorial's plugin is the
one fsi-lab plugin new writes (so the tutorial's steps are the ones tests/test_scaffold.py
takes)."""

import ast
import re

from support import ROOT

from fsi_lab.scaffold.templates import files

DOC = (ROOT / "docs" / "writing-plugins.md").read_text()


def test_every_python_example_parses():
    blocks = re.findall(r"```python\n(.*?)```", DOC, re.S)
    assert len(blocks) >= 8
    for block in blocks:
        ast.parse(block)


def test_the_tutorials_declaration_is_the_scaffolds():
    written = files("analysis", "window-rms")["fsi_lab_window_rms/plugin.py"]
    declared = re.search(r"PLUGIN = AnalysisPlugin\(.*?\n\)\n", written, re.S).group(0)
    tutorial = re.search(r"PLUGIN = AnalysisPlugin\(.*?\n\)\n", DOC, re.S).group(0)
    strip = re.compile(r"\s*#.*")  # the scaffold's comments are not in the tutorial

    def lines(text):
        return [strip.sub("", line) for line in text.splitlines() if strip.sub("", line)]

    assert lines(tutorial) == lines(declared)
    assert "fsi-lab plugin new analysis window-rms --dir ~/src" in DOC
