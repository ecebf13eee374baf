"""The core's command line, chain runner and GUI name no built-in plugin (issue 15): what the
built-ins add (commands, summary text, the default chain, views, the Sequence tab's figure of
an aggregation) comes through the hooks.

Every string in the code of fsi_lab/cli.py, fsi_lab/chain.py and fsi_lab/gui/ (docstrings and
messages included) is checked against the names of fsi-lab's own plugins of every kind
(analyses, excitations, instruments, and the entry points that add commands and views: what
``fsi-lab plugins`` lists) and the summary keys they show in their own way; a name used as a
word in prose ("spectrum" in "amplitude spectrum", "step by step") is not a name of the plugin,
so a string must equal the name, or hold it as a dotted or slashed part
(``analysis.hvd.components``, ``tip/hvd``), to count.
"""

import ast
import re
from pathlib import Path

from fsi_lab.registry import load_registry

ROOT = Path(__file__).resolve().parents[1]
CORE = [ROOT / "fsi_lab" / "cli.py", ROOT / "fsi_lab" / "chain.py",
        *sorted((ROOT / "fsi_lab" / "gui").rglob("*.py"))]
#: Strings that are a word of a file format the core owns and only spell like a plugin's
#: name: a sequence plan's ``[[step]]`` tables and each run's ``step`` (docs/sequence-format.md)
#: are not the ``step`` excitation. Each is allowed in the one file that holds it, as written.
HOMONYMS = {("fsi_lab/gui/sequence_tab.py", "step"),
            ("fsi_lab/gui/sequence_tab.py", "[step.sweep]")}


def built_in_names() -> set[str]:
    """The names of fsi-lab's own plugins of every kind and their entry points (as written and
    with underscores), and the summary keys they show in their own way."""
    registry = load_registry()
    own = [r for r in registry.records if r.distribution == "fsi-lab"]
    names = {r.name for r in own} | {r.entry_point for r in own}
    names |= {name.replace("-", "_") for name in names}
    for component in ({}, None):  # the keys the built-ins' summary hooks claim
        for text in registry.summary_texts("tip", {}, component):
            names |= set(text.keys)
    return names


def strings(path: Path):
    """Every string constant of the module, and the dotted name of every module it imports
    (``fsi_lab.plugins.analysis.hvd`` names hvd as surely as ``"hvd"`` does)."""
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            yield node.lineno, node.value
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom) and node.module:
            yield node.lineno, node.module
            for alias in node.names:
                yield node.lineno, f"{node.module}.{alias.name}"


def hits(text: str, names: set[str]) -> set[str]:
    """The names ``text`` holds: all of it, or a part of a dotted or slashed word
    (``analysis.hvd.components``, ``tip/hvd``)."""
    parts = {part for word in re.findall(r"[\w-]+(?:[./][\w-]+)+", text)
             for part in re.split(r"[./]", word)}
    return names & ({text} | parts)


def test_no_built_in_plugin_is_named_in_the_cli_the_chain_or_the_gui():
    names = built_in_names()
    assert {"hvd", "equivalent-damping", "equivalent_damping", "modal_model", "backbone",
            "spectrum_peaks_hz", "extrema", "impulse-train", "random", "step", "keysight33500",
            "inprocess-source", "inprocess", "sim-bench", "analysis-views", "scaffold"} <= names
    found = []
    for path in CORE:
        where = path.relative_to(ROOT).as_posix()
        for line, text in strings(path):
            hit = hits(text, names)
            if hit and (where, text) not in HOMONYMS:
                found.append(f"{path.relative_to(ROOT)}:{line}: {sorted(hit)} in {text!r}")
    assert not found, "\n".join(found)


def test_the_check_finds_a_name_where_there_is_one(tmp_path):
    """The scan is not blind: it finds the names the core used to hold."""
    names = built_in_names()
    sample = tmp_path / "sample.py"
    sample.write_text('DEFAULT = ("spectrum", "hvd")\nHELP = "e.g. analysis.hvd.components=2"\n'
                      'KEY = "equivalent_damping"\nTEXT = "an amplitude spectrum"\n'
                      'EXC = "excitation.impulse-train"\nDRIVER = "keysight33500"\n'
                      'WORDS = "step by step, at random"\n'
                      'from fsi_lab.plugins.analysis import hvd\n'
                      'import fsi_lab.instruments.polytec\n')
    found = {text for _, text in strings(sample) if hits(text, names)}
    assert found == {"spectrum", "hvd", "e.g. analysis.hvd.components=2", "equivalent_damping",
                     "excitation.impulse-train", "keysight33500", "fsi_lab.plugins.analysis.hvd",
                     "fsi_lab.instruments.polytec"}
