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


def test_the_tutorials_copy_of_its_run_file_works_with_earlier_runs_beside_it(tmp_path):
    """The step after `fsi-lab run ... --out runs` copies the run file it wrote to wet.h5 also
    when runs/ holds earlier run files (after `make demo` it holds the demo's)."""
    import os
    import subprocess

    from support import write_decay_run

    step = re.search(r"fsi-lab run profiles/wet-beam-sim.toml --out runs\n(.*?)\n```", DOC,
                     re.S).group(1)
    runs = tmp_path / "runs"
    runs.mkdir()
    older = write_decay_run(runs / "20261128-121911_4067344c.h5", frequency=20.0)
    newest = write_decay_run(runs / "20261129-101500_1a2b3c4d.h5", frequency=25.0)
    os.utime(older, (1_700_000_000, 1_700_000_000))  # the demo's run, a day before
    proc = subprocess.run(["bash", "-ec", step], cwd=tmp_path, capture_output=True, text=True,
                          timeout=30, check=False)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "wet.h5").read_bytes() == newest.read_bytes()
