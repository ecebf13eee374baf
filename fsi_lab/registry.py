"""Discovery and loading of plugins through the ``fsi_lab`` entry-point group.

Built-in plugins are declared in fsi-lab's own pyproject.toml and loaded exactly like third-party
ones. A plugin that fails to import, fails to register or returns descriptors that break the
contract is recorded with the reason and skipped; the others keep working.

Set ``FSI_LAB_DISABLE_PLUGIN_AUTOLOAD=1`` to load only the entry points named in
``FSI_LAB_PLUGINS`` (a comma-separated allow-list of entry-point names).
"""

from __future__ import annotations

import os
import traceback
from dataclasses import dataclass, field
from importlib import metadata
from typing import Any, Iterable

import pluggy

from fsi_lab import hookspecs
from fsi_lab.contract import KINDS, check_descriptor
from fsi_lab.errors import PluginError

ENTRY_POINT_GROUP = "fsi_lab"
DISABLE_ENV = "FSI_LAB_DISABLE_PLUGIN_AUTOLOAD"
ALLOW_ENV = "FSI_LAB_PLUGINS"


@dataclass
class PluginRecord:
    """What became of one plugin (one descriptor, or one entry point that failed)."""

    name: str
    kind: str | None
    version: str
    distribution: str
    entry_point: str
    status: str  # "loaded" | "failed" | "invalid" | "disabled"
    error: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "kind": self.kind,
            "version": self.version,
            "distribution": self.distribution,
            "entry_point": self.entry_point,
            "status": self.status,
            "error": self.error,
        }


@dataclass
class Registry:
    """Loaded plugin descriptors by kind and name, plus a record of every plugin seen."""

    descriptors: dict[str, dict[str, Any]] = field(
        default_factory=lambda: {kind: {} for kind in KINDS}
    )
    records: list[PluginRecord] = field(default_factory=list)

    def get(self, kind: str, name: str) -> Any:
        """The descriptor of plugin ``name`` of ``kind``; PluginError listing the choices."""
        try:
            return self.descriptors[kind][name]
        except KeyError:
            failed = [r for r in self.records if r.name == name and r.status != "loaded"]
            if failed:
                raise PluginError(
                    f"{kind} plugin {name!r} is not usable: {failed[0].error}"
                ) from None
            raise PluginError(
                f"unknown {kind} plugin {name!r}; installed {kind} plugins: "
                f"{', '.join(sorted(self.descriptors[kind])) or 'none'}"
            ) from None

    def names(self, kind: str) -> list[str]:
        return sorted(self.descriptors[kind])

    def version_of(self, kind: str, name: str) -> str:
        for record in self.records:
            if record.kind == kind and record.name == name and record.status == "loaded":
                return f"{record.distribution} {record.version}"
        return "unknown"


def _entry_points() -> Iterable[metadata.EntryPoint]:
    return metadata.entry_points(group=ENTRY_POINT_GROUP)


def _allowed(name: str) -> bool:
    if os.environ.get(DISABLE_ENV, "").strip() not in ("1", "true", "yes"):
        return True
    allow = {n.strip() for n in os.environ.get(ALLOW_ENV, "").split(",") if n.strip()}
    return name in allow


def _short_error(exc: BaseException) -> str:
    last = traceback.extract_tb(exc.__traceback__)[-1:] if exc.__traceback__ else []
    where = f" (at {last[0].filename}:{last[0].lineno})" if last else ""
    return f"{type(exc).__name__}: {exc}{where}"


def load_registry() -> Registry:
    """Load every allowed plugin of the ``fsi_lab`` entry-point group.

    Returns
    -------
    Registry
        Usable descriptors and a record (loaded / failed / invalid / disabled) per plugin.
    """
    registry = Registry()
    manager = pluggy.PluginManager(hookspecs.PROJECT)
    manager.add_hookspecs(hookspecs)
    seen: set[str] = set()
    for ep in sorted(_entry_points(), key=lambda e: e.name):
        if ep.name in seen:  # the same distribution seen twice on sys.path
            continue
        seen.add(ep.name)
        dist = ep.dist.name if ep.dist else "unknown"
        version = ep.dist.version if ep.dist else "unknown"

        def record(name, kind, status, error=None):
            registry.records.append(
                PluginRecord(name, kind, version, dist, ep.name, status, error)
            )

        if not _allowed(ep.name):
            record(ep.name, None, "disabled", f"not in {ALLOW_ENV} while {DISABLE_ENV}=1")
            continue
        try:
            module = ep.load()
            manager.register(module, name=ep.name)
        except Exception as exc:  # noqa: BLE001 - any import error is reported, not raised
            record(ep.name, None, "failed", _short_error(exc))
            continue
        _collect(manager, module, ep.name, registry, record)
    return registry


def _collect(manager, module, ep_name, registry, record) -> None:
    """Call each hook of one plugin separately so that one bad answer cannot hide the others."""
    provided = False
    for kind in KINDS:
        hook_name = hookspecs.HOOK_FOR_KIND[kind]
        for impl in getattr(manager.hook, hook_name).get_hookimpls():
            if impl.plugin is not module:
                continue
            provided = True
            try:
                descriptors = impl.function()
                if not isinstance(descriptors, (list, tuple)):
                    raise TypeError(
                        f"{hook_name}() returned {type(descriptors).__name__}, expected a list"
                    )
            except Exception as exc:  # noqa: BLE001
                record(ep_name, kind, "invalid", f"{hook_name}() failed: {_short_error(exc)}")
                continue
            for descriptor in descriptors:
                name = getattr(descriptor, "name", None) or ep_name
                try:
                    check_descriptor(kind, descriptor)
                except (TypeError, ValueError) as exc:
                    record(name, kind, "invalid", f"breaks the {kind} contract: {exc}")
                    continue
                if name in registry.descriptors[kind]:
                    record(name, kind, "invalid", f"another {kind} plugin is already named {name!r}")
                    continue
                registry.descriptors[kind][name] = descriptor
                record(name, kind, "loaded")
    if not provided:
        record(ep_name, None, "invalid", "implements none of the fsi_lab hooks")
