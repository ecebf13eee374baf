"""The core's command line, chain runner and GUI name no built-in analysis (issue 15): what the
built-ins add (commands, summary text, the default chain, views) comes through the hooks.

Every string in the code of fsi_lab/cli.py, fsi_lab/chain.py and fsi_lab/gui/ (docstrings and
messages included) is checked against the names of fsi-lab's own plugins and the summary keys
they show in their own way; a name used as a word in prose ("spectrum" in "amplitude
spectrum", "step by step") is not a name of the plugin, so a string must equal the name, or
hold it as a dotted or slashed part (``analysis.hvd.components``, ``tip/hvd``), to count.
"""

import ast
import re
from pathlib import Path

from fsi_lab.registry import load_registry

ROOT = Path(__file__).resolve().parents[1]
#: The sequence tab draws a sequence's aggregation (fsi_lab.aggregate, docs/sequence-format.md),
#: a record of its own built on the identification library, whose curves are named backbone,
#: damping and c_q by that record's layout; making the aggregation a contribution of the
#: analysis plugins is work of its own, not done here.
NOT_YET = {ROOT / "fsi_lab" / "gui" / "sequence_tab.py"}
CORE = [ROOT / "fsi_lab" / "cli.py", ROOT / "fsi_lab" / "chain.py",
        *sorted(p for p in (ROOT / "fsi_lab" / "gui").rglob("*.py") if p not in NOT_YET)]


def built_in_names() -> set[str]:
    """The names of fsi-lab's own analyses (as written and with underscores) and the summary
    keys they show in their own way."""
    registry = load_registry()
    names = {r.name for r in registry.records
             if r.distribution == "fsi-lab" and r.kind == "analysis"}
    names |= {name.replace("-", "_") for name in names}
    for component in ({}, None):  # the keys the built-ins' summary hooks claim
        for text in registry.summary_texts("tip", {}, component):
            names |= set(text.keys)
    return names


def strings(path: Path):
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            yield node.lineno, node.value


def hits(text: str, names: set[str]) -> set[str]:
    """The names ``text`` holds: all of it, or a part of a dotted or slashed word
    (``analysis.hvd.components``, ``tip/hvd``)."""
    parts = {part for word in re.findall(r"[\w-]+(?:[./][\w-]+)+", text)
             for part in re.split(r"[./]", word)}
    return names & ({text} | parts)


def test_no_built_in_plugin_is_named_in_the_cli_the_chain_or_the_gui():
    names = built_in_names()
    assert {"hvd", "equivalent-damping", "equivalent_damping", "modal_model", "backbone",
            "spectrum_peaks_hz", "extrema"} <= names
    found = []
    for path in CORE:
        for line, text in strings(path):
            hit = hits(text, names)
            if hit:
                found.append(f"{path.relative_to(ROOT)}:{line}: {sorted(hit)} in {text!r}")
    assert not found, "\n".join(found)


def test_the_check_finds_a_name_where_there_is_one(tmp_path):
    """The scan is not blind: it finds the names the core used to hold."""
    names = built_in_names()
    sample = tmp_path / "sample.py"
    sample.write_text('DEFAULT = ("spectrum", "hvd")\nHELP = "e.g. analysis.hvd.components=2"\n'
                      'KEY = "equivalent_damping"\nTEXT = "an amplitude spectrum"\n')
    found = {text for _, text in strings(sample) if hits(text, names)}
    assert found == {"spectrum", "hvd", "e.g. analysis.hvd.components=2", "equivalent_damping"}
