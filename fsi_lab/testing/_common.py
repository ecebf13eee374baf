"""What the contract classes share: finding the plugin under test, failing with a message that
says what to fix, and comparing values deeply (to tell whether an input was changed)."""

from __future__ import annotations

import copy
import dataclasses
import json
from typing import Any

import numpy as np
import pytest


def broken(plugin: str, text: str) -> None:
    """Fail the test with ``"<plugin>: <text>"`` and no traceback: the sentence says what is
    wrong and what to change."""
    pytest.fail(f"{plugin}: {text}", pytrace=False)


def all_broken(plugin: str, problems: list[str]) -> None:
    """Fail with every problem found, one line each (an author fixes them in one go)."""
    if problems:
        pytest.fail("\n".join(f"{plugin}: {text}" for text in problems), pytrace=False)


def with_plugin(registry, kind: str, plugin: Any):
    """``registry`` (not changed) with ``plugin`` added when it is a descriptor rather than the
    name of an installed plugin."""
    if isinstance(plugin, str):
        return registry
    out = copy.copy(registry)
    out.descriptors = {k: dict(v) for k, v in registry.descriptors.items()}
    name = getattr(plugin, "name", None)
    if isinstance(name, str) and name:
        out.descriptors[kind][name] = plugin
    return out


def descriptor_of(kind: str, plugin: Any, registry, expected: type) -> Any:
    """The descriptor of the plugin under test: ``plugin`` itself when it is a descriptor,
    else the installed one of that name; the test fails saying how to make it found
    otherwise."""
    if isinstance(plugin, expected):
        return plugin
    if not isinstance(plugin, str) or not plugin:
        pytest.fail(f"set the class attribute plugin to the name of your {kind} plugin (or its "
                    f"{expected.__name__}); got {plugin!r}", pytrace=False)
    found = registry.descriptors[kind].get(plugin)
    if found is None:
        why = next((r.error for r in registry.records if r.name == plugin and r.error), None)
        installed = ", ".join(registry.names(kind)) or "none"
        broken(plugin, (f"is not usable: {why}" if why else
                        f"is not an installed {kind} plugin (installed: {installed}); install "
                        "your distribution (pip install -e .) so that its entry point in the "
                        "'fsi_lab' group is found, or set plugin to the descriptor itself"))
    return found


def json_default(value: Any) -> Any:
    """What the JSON output does with numpy values (an array as a list, a scalar as a number);
    anything else is refused."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON-ready")


def json_problem(value: Any) -> str:
    """Why ``value`` cannot be printed as JSON by ``--json``, or ''."""
    try:
        json.dumps(value, default=json_default)
    except (TypeError, ValueError) as exc:
        return str(exc)
    return ""


def freeze(value: Any, depth: int = 0) -> None:
    """Make the numpy arrays in ``value`` (dataclasses, dicts, lists, objects) read-only, so
    that writing into them raises at the line that does it."""
    if depth > 6:
        return
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif isinstance(value, dict):
        for item in value.values():
            freeze(item, depth + 1)
    elif isinstance(value, (list, tuple)):
        for item in value:
            freeze(item, depth + 1)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            freeze(getattr(value, f.name, None), depth + 1)
    elif hasattr(value, "__dict__") and not isinstance(value, type):
        for item in vars(value).values():
            freeze(item, depth + 1)


def difference(before: Any, after: Any, where: str = "", depth: int = 0) -> str:
    """Where ``after`` differs from ``before`` (a deep copy taken earlier), in words; '' when
    they hold the same values (NaN equal to NaN)."""
    if depth > 6:
        return ""
    if isinstance(before, np.ndarray) or isinstance(after, np.ndarray):
        a, b = np.asarray(before), np.asarray(after)
        if a.shape != b.shape:
            return f"{where}: shape {a.shape} became {b.shape}"
        if a.dtype.kind in "fc":
            same = (a == b) | (np.isnan(a) & np.isnan(b))
        else:
            same = a == b
        if not np.all(same):
            index = tuple(int(i) for i in np.argwhere(~np.asarray(same))[0])
            return f"{where}{list(index)}: {a[index]!r} became {b[index]!r}"
        return ""
    if isinstance(before, dict) and isinstance(after, dict):
        if set(before) != set(after):
            return f"{where}: keys {sorted(map(str, before))} became {sorted(map(str, after))}"
        for key in before:
            found = difference(before[key], after[key], f"{where}[{key!r}]", depth + 1)
            if found:
                return found
        return ""
    if isinstance(before, (list, tuple)) and isinstance(after, (list, tuple)):
        if len(before) != len(after):
            return f"{where}: {len(before)} items became {len(after)}"
        for i, (a, b) in enumerate(zip(before, after)):
            found = difference(a, b, f"{where}[{i}]", depth + 1)
            if found:
                return found
        return ""
    if dataclasses.is_dataclass(before) and not isinstance(before, type):
        for f in dataclasses.fields(before):
            found = difference(getattr(before, f.name, None), getattr(after, f.name, None),
                               f"{where}.{f.name}", depth + 1)
            if found:
                return found
        return ""
    if hasattr(before, "__dict__") and not isinstance(before, type):
        return difference(vars(before), vars(after), where, depth + 1)
    try:
        same = before == after or (before != before and after != after)  # NaN
    except Exception:  # noqa: BLE001 - values that cannot be compared are taken as equal
        return ""
    return "" if same else f"{where}: {before!r} became {after!r}"
