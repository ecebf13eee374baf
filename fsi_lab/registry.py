"""Discovery and loading of plugins through the ``fsi_lab`` entry-point group.

Built-in plugins are declared in fsi-lab's own pyproject.toml and loaded exactly like third-party
ones. Each entry point's module is registered with a pluggy plugin manager, and every hook of
:mod:`fsi_lab.hookspecs` is called through it (``manager.hook``), a plugin at a time: a plugin
that fails to import, fails to register, fails in a hook or returns descriptors that break the
contract is recorded with the reason and skipped; the others keep working.

Set ``FSI_LAB_DISABLE_PLUGIN_AUTOLOAD=1`` to load only the entry points named in
``FSI_LAB_PLUGINS`` (a comma-separated allow-list of entry-point names).
"""

from __future__ import annotations

import functools
import os
import traceback
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any, Iterable

import pluggy

from fsi_lab import hookspecs
from fsi_lab.contract import KINDS, check_descriptor
from fsi_lab.errors import PluginError
from fsi_lab.presentation import SummaryText, ViewSet

ENTRY_POINT_GROUP = "fsi_lab"
#: fsi-lab's own distribution: its plugins are registered first.
OWN = "fsi-lab"
#: The entry-point group of subcommands before the ``fsi_lab_addcommands`` hook: no longer read.
LEGACY_COMMANDS_GROUP = "fsi_lab.commands"
DISABLE_ENV = "FSI_LAB_DISABLE_PLUGIN_AUTOLOAD"
ALLOW_ENV = "FSI_LAB_PLUGINS"


@dataclass
class PluginRecord:
    """What became of one plugin (one descriptor, one entry point that failed, or one whose
    hooks contribute no descriptor: commands, summary text, views)."""

    name: str
    kind: str | None
    version: str
    distribution: str
    entry_point: str
    status: str  # "loaded" | "failed" | "invalid" | "disabled"
    error: str | None = None
    #: the hooks the entry point's module implements
    hooks: tuple[str, ...] = ()

    def warning(self) -> str | None:
        """The sentence a user is shown for a plugin that did not load whole (``None`` when it
        did): a failed entry point is left out entirely; an invalid hook or descriptor is left
        out alone, the plugin's other contributions stay."""
        where = f"plugin {self.name} ({self.distribution})"
        if self.status == "failed":
            return f"{where} not loaded: {self.error}"
        if self.status == "invalid":
            return f"{where}: {self.error}; left out, its other contributions are loaded"
        return None

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "kind": self.kind,
            "version": self.version,
            "distribution": self.distribution,
            "entry_point": self.entry_point,
            "status": self.status,
            "error": self.error,
            "hooks": list(self.hooks),
        }


def _manager() -> pluggy.PluginManager:
    manager = pluggy.PluginManager(hookspecs.PROJECT)
    manager.add_hookspecs(hookspecs)
    return manager


@dataclass
class HookAnswer:
    """What one plugin's implementation of a hook gave: its ``value``, or the ``error`` (a
    sentence naming the hook and the exception) it raised."""

    plugin: str
    value: Any = None
    error: str | None = None


@dataclass
class CommandRecord:
    """A subcommand a plugin added (or failed to add, or added through the old entry-point
    group, which is refused)."""

    name: str
    distribution: str
    version: str
    entry_point: str
    status: str  # "loaded" | "failed" | "refused"
    error: str | None = None
    help: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "distribution": self.distribution, "version": self.version,
                "entry_point": self.entry_point, "status": self.status, "error": self.error,
                "help": self.help}


class _RecordingSubparsers:
    """The argparse sub-parser action handed to one plugin's ``fsi_lab_addcommands``: it adds
    the plugin's parsers and notes their names and help."""

    def __init__(self, subparsers: Any) -> None:
        self._subparsers = subparsers
        self.added: list[tuple[str, str]] = []

    def add_parser(self, name: str, **kwargs: Any) -> Any:
        taken = getattr(self._subparsers, "choices", {})
        if name in taken:
            raise ValueError(f"the command {name!r} exists already")
        parser = self._subparsers.add_parser(name, **kwargs)
        self.added.append((name, str(kwargs.get("help", "") or "")))
        return parser

    def __getattr__(self, name: str) -> Any:
        return getattr(self._subparsers, name)


@dataclass
class Registry:
    """Loaded plugin descriptors by kind and name, a record of every plugin seen, and the plugin
    manager every hook is called through.

    Attributes
    ----------
    descriptors
        Usable descriptors by kind and name.
    records
        What became of each plugin (:class:`PluginRecord`).
    manager
        The pluggy plugin manager the plugins are registered with.
    plugins
        Registered plugin names (entry-point names), in the order they were registered.
    sources
        ``(distribution, version)`` of each registered plugin.
    commands
        What :meth:`add_commands` added (:class:`CommandRecord`).
    """

    descriptors: dict[str, dict[str, Any]] = field(
        default_factory=lambda: {kind: {} for kind in KINDS}
    )
    records: list[PluginRecord] = field(default_factory=list)
    manager: pluggy.PluginManager = field(default_factory=_manager)
    plugins: list[str] = field(default_factory=list)
    sources: dict[str, tuple[str, str]] = field(default_factory=dict)
    commands: list[CommandRecord] = field(default_factory=list)
    _callers: dict[tuple[str, str], Any] = field(default_factory=dict, repr=False)
    _views: ViewSet | None = field(default=None, repr=False)
    #: the old group's entry points, read with the plugins' own by :func:`load_registry`
    _legacy: list[metadata.EntryPoint] | None = field(default=None, repr=False)

    # ------------------------------------------------------------------ calling hooks
    def register(self, plugin: Any, name: str, distribution: str = "unknown",
                 version: str = "unknown") -> None:
        """Register ``plugin`` (a module or object with hook implementations) as ``name``."""
        self.manager.register(plugin, name=name)
        self.plugins.append(name)
        self.sources[name] = (distribution, version)
        self._callers.clear()
        self._views = None

    def implements(self, plugin: str, hook_name: str) -> bool:
        """Whether the registered plugin ``plugin`` implements ``hook_name``."""
        module = self.manager.get_plugin(plugin)
        return any(impl.plugin is module
                   for impl in getattr(self.manager.hook, hook_name).get_hookimpls())

    def call_each(self, hook_name: str, only: tuple[str, ...] | None = None,
                  **kwargs: Any) -> list[HookAnswer]:
        """Call ``hook_name`` with ``kwargs`` through the plugin manager, one plugin at a time
        (each through its own subset of the hook), in registration order; ``only`` the named
        plugins when given.

        Returns
        -------
        list of HookAnswer
            One per plugin implementing the hook: its value (an implementation returning None
            included), or the error it raised, as a sentence; one plugin's error does not stop
            the others.
        """
        answers = []
        for name in self.plugins:
            if only is not None and name not in only:
                continue
            if not self.implements(name, hook_name):
                continue
            caller = self._callers.get((hook_name, name))
            if caller is None:
                others = [self.manager.get_plugin(n) for n in self.plugins if n != name]
                caller = self.manager.subset_hook_caller(hook_name, remove_plugins=others)
                self._callers[(hook_name, name)] = caller
            try:
                values = caller(**kwargs)
            except Exception as exc:  # noqa: BLE001 - reported with the plugin's name
                answers.append(HookAnswer(name, error=f"{hook_name}() failed: "
                                                       f"{_short_error(exc)}"))
                continue
            answers.append(HookAnswer(name, values[0] if values else None))
        return answers

    # ------------------------------------------------------------------ descriptors

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



    # ------------------------------------------------------------------ the other hooks
    def add_commands(self, subparsers: Any) -> list[CommandRecord]:
        """Let every plugin add its subcommands to ``subparsers`` (``fsi_lab_addcommands``).

        Returns
        -------
        list of CommandRecord
            The commands added, the plugins whose hook failed (``failed``, with the reason),
            and the entry points of the old ``fsi_lab.commands`` group (``refused``, saying
            what to write instead); also kept in :attr:`commands`.
        """
        records = []
        for name in self.plugins:
            if not self.implements(name, "fsi_lab_addcommands"):
                continue
            dist, version = self.sources.get(name, ("unknown", "unknown"))
            recorder = _RecordingSubparsers(subparsers)
            (answer,) = self._call_one("fsi_lab_addcommands", name, subparsers=recorder)
            for command, text in recorder.added:
                records.append(CommandRecord(command, dist, version, name, "loaded", None, text))
            if answer.error:
                records.append(CommandRecord(name, dist, version, name, "failed", answer.error))
        records.extend(legacy_commands(self._legacy))
        self.commands = records
        return records

    def _call_one(self, hook_name: str, plugin: str, **kwargs: Any) -> list[HookAnswer]:
        return self.call_each(hook_name, only=(plugin,), **kwargs)

    def summary_texts(self, channel: str, summary: dict[str, Any],
                      component: dict[str, Any] | None = None) -> list[SummaryText]:
        """What the plugins show of a channel's summary (``component`` None) or of one of its
        components (``fsi_lab_summary_lines``); a plugin whose hook fails or returns something
        else is left out, its reason in the text."""
        texts = []
        for answer in self.call_each("fsi_lab_summary_lines", channel=channel, summary=summary,
                                     component=component):
            if answer.error:
                texts.append(SummaryText(lines=(f"(plugin {answer.plugin}: {answer.error})",)))
            elif isinstance(answer.value, SummaryText):
                texts.append(answer.value)
            elif answer.value is not None:
                texts.append(SummaryText(lines=(
                    f"(plugin {answer.plugin}: fsi_lab_summary_lines() returned "
                    f"{_describe(answer.value)}, expected fsi_lab.presentation.SummaryText "
                    "or None)",)))
        return texts

    def default_chain_names(self) -> list[str]:
        """The analyses the plugins put in the default chain (``fsi_lab_default_chain``), kept
        when installed, each once, in the order given; see :func:`fsi_lab.chain.default_chain`
        for the chain's order. A plugin whose hook fails or returns something other than a
        list of names is left out and recorded as ``invalid`` with the reason (once)."""
        installed = tuple(self.names("analysis"))
        names: list[str] = []
        for answer in self.call_each("fsi_lab_default_chain", analyses=installed):
            error = answer.error
            value = answer.value
            if error is None and (not isinstance(value, (list, tuple))
                                  or not all(isinstance(n, str) for n in value)):
                error = (f"fsi_lab_default_chain() returned {_describe(value)}, expected a "
                         "list of analysis names")
            if error is not None:
                self._hook_failed(answer.plugin, error)
                continue
            names.extend(n for n in value if n in installed and n not in names)
        return names

    def _hook_failed(self, plugin: str, error: str) -> None:
        """Record (once) that one of ``plugin``'s hooks failed: ``fsi-lab plugins`` and the
        GUI's log list it as ``invalid`` with ``error``; its other contributions stay."""
        if any(r.entry_point == plugin and r.error == error for r in self.records):
            return
        dist, version = self.sources.get(plugin, ("unknown", "unknown"))
        self.records.append(PluginRecord(plugin, None, version, dist, plugin, "invalid", error))

    def check_hooks(self) -> None:
        """Call the hooks whose answers do not depend on a run (the default chain, the views),
        so that a plugin whose hook fails is recorded now, with its name and the reason."""
        self.default_chain_names()
        self.views()

    def views(self) -> ViewSet:
        """The GUI views, compared curves and table columns the plugins register
        (``fsi_lab_addviews``), gathered once; a plugin whose hook fails is recorded as
        ``invalid`` with the reason and its registrations kept up to the failure."""
        if self._views is None:
            views = ViewSet()
            for name in self.plugins:
                if not self.implements(name, "fsi_lab_addviews"):
                    continue
                views.current = name
                for answer in self._call_one("fsi_lab_addviews", name, views=views):
                    if answer.error:
                        self._hook_failed(name, answer.error)
            views.current = ""
            self._views = views
        return self._views


def legacy_commands(entry_points: Iterable[metadata.EntryPoint] | None = None,
                    ) -> list[CommandRecord]:
    """The entry points of the old ``fsi_lab.commands`` group (``entry_points``, or those
    installed), refused (not imported): fsi-lab adds subcommands through the
    ``fsi_lab_addcommands(subparsers)`` hook only."""
    if entry_points is None:
        entry_points = metadata.entry_points(group=LEGACY_COMMANDS_GROUP)
    out = []
    for ep in sorted(entry_points, key=lambda e: e.name):
        dist, version = _distribution(ep)
        out.append(CommandRecord(
            ep.name, dist, version, ep.value, "refused",
            f"declared in the {LEGACY_COMMANDS_GROUP!r} entry-point group, which fsi-lab no "
            f"longer reads; {dist} should implement the fsi_lab_addcommands(subparsers) hook in "
            "a module of its 'fsi_lab' entry points instead (with a CliCommand: "
            "COMMAND.add_to(subparsers); see docs/writing-plugins.md)"))
    return out


def _entry_points() -> metadata.EntryPoints:
    # one scan of the installed distributions for both groups (a scan reads every
    # distribution's entry_points.txt)
    return metadata.entry_points()


def _allowed(name: str) -> bool:
    if os.environ.get(DISABLE_ENV, "").strip() not in ("1", "true", "yes"):
        return True
    allow = {n.strip() for n in os.environ.get(ALLOW_ENV, "").split(",") if n.strip()}
    return name in allow


def _describe(value: Any) -> str:
    """A value a hook returned, for a message: its type, and the value when short."""
    text = repr(value)
    return type(value).__name__ + (f" {text}" if len(text) <= 40 else "")


def _short_error(exc: BaseException) -> str:
    """The exception in one line, with the place it was raised in the plugin's code (rather
    than in fsi-lab's core, e.g. the recorder or the dataclass that refused what it did)."""
    frames = traceback.extract_tb(exc.__traceback__) if exc.__traceback__ else []
    last = [f for f in frames if not _in_core(f.filename)][-1:] or frames[-1:]
    where = f" (at {last[0].filename}:{last[0].lineno})" if last else ""
    return f"{type(exc).__name__}: {exc}{where}"


#: fsi-lab's core package folder; its plugins live in fsi_lab.plugins and fsi_lab.instruments.
_CORE = Path(__file__).resolve().parent


def _in_core(filename: str) -> bool:
    """Whether ``filename`` is a module of fsi-lab's core (not of a plugin, built-in or not)."""
    if filename.startswith("<"):  # code made at run time (a dataclass's __init__)
        return True
    path = Path(filename).resolve()
    return path.parent == _CORE or (_CORE in path.parents and path.parts[len(_CORE.parts)]
                                    not in ("plugins", "instruments"))


def _distribution(ep: metadata.EntryPoint) -> tuple[str, str]:
    """The name and version of the distribution that declares ``ep``."""
    return _name_and_version(ep.dist) if ep.dist is not None else ("unknown", "unknown")


@functools.lru_cache(maxsize=64)
def _name_and_version(dist: metadata.Distribution) -> tuple[str, str]:
    # Distribution.name and .version each parse the METADATA file again, and the entry points
    # of one distribution share its object: once per object, not per entry point and use,
    # halves a command's start-up time
    meta = dist.metadata
    return meta["Name"], meta["Version"]


def load_registry() -> Registry:
    """Load every allowed plugin of the ``fsi_lab`` entry-point group.

    Returns
    -------
    Registry
        Usable descriptors and a record (loaded / failed / invalid / disabled) per plugin.
    """
    installed = _entry_points()
    registry = Registry(_legacy=list(installed.select(group=LEGACY_COMMANDS_GROUP)))
    seen: dict[str, metadata.EntryPoint] = {}
    # fsi-lab's own first, then the others by name: a plugin of another distribution that
    # takes a built-in's name is the one refused, whatever its entry point is called
    for ep in sorted(installed.select(group=ENTRY_POINT_GROUP),
                     key=lambda e: (_distribution(e)[0] != OWN, e.name)):
        dist, version = _distribution(ep)
        first = seen.get(ep.name)
        if first is not None:
            first_dist = _distribution(first)[0]
            if first_dist != dist or first.value != ep.value:
                registry.records.append(PluginRecord(
                    ep.name, None, version, dist, ep.name, "failed",
                    f"entry point {ep.name!r} ({ep.value}) has the name of {first_dist}"
                    f"'s ({first.value}), and fsi-lab registers plugins by entry-point name: "
                    f"rename it in {dist}'s [project.entry-points.fsi_lab]"))
            continue  # else the same distribution seen twice on sys.path
        seen[ep.name] = ep
        if not _allowed(ep.name):
            registry.records.append(PluginRecord(
                ep.name, None, version, dist, ep.name, "disabled",
                f"not in {ALLOW_ENV} while {DISABLE_ENV}=1"))
            continue
        try:
            module = ep.load()
        except Exception as exc:  # noqa: BLE001 - any import error is reported, not raised
            registry.records.append(PluginRecord(ep.name, None, version, dist, ep.name,
                                                 "failed", _short_error(exc)))
            continue
        add_plugin(registry, module, ep.name, dist, version)
    return registry


def add_plugin(registry: Registry, plugin: Any, name: str, distribution: str = "unknown",
               version: str = "unknown") -> None:
    """Register ``plugin`` (a module or object with hook implementations) as ``name`` and take
    its descriptors, each checked against the contract of its kind; what fails is recorded in
    ``registry.records`` with the reason."""

    hooks: tuple[str, ...] = ()

    def record(plugin_name, kind, status, error=None):
        registry.records.append(PluginRecord(plugin_name, kind, version, distribution, name,
                                             status, error, hooks))

    try:
        registry.register(plugin, name, distribution, version)
    except Exception as exc:  # noqa: BLE001 - e.g. a hook pluggy cannot match to a spec
        record(name, None, "failed", f"cannot be registered: {_short_error(exc)}")
        return
    known = sorted(spec for spec in dir(hookspecs) if spec.startswith("fsi_lab_"))
    hooks = tuple(hook_name for hook_name in known if registry.implements(name, hook_name))
    if not hooks:
        record(name, None, "invalid", "implements none of the fsi_lab hooks")
        return
    if not set(hooks) & set(hookspecs.HOOK_FOR_KIND.values()):  # commands, text, views only
        record(name, None, "loaded")
        return
    for kind in KINDS:
        hook_name = hookspecs.HOOK_FOR_KIND[kind]
        for answer in registry._call_one(hook_name, name):
            if answer.error:
                record(name, kind, "invalid", answer.error)
                continue
            descriptors = answer.value
            if not isinstance(descriptors, (list, tuple)):
                record(name, kind, "invalid", f"{hook_name}() returned "
                                              f"{type(descriptors).__name__}, expected a list")
                continue
            for descriptor in descriptors:
                descriptor_name = getattr(descriptor, "name", None) or name
                try:
                    check_descriptor(kind, descriptor)
                except (TypeError, ValueError) as exc:
                    record(descriptor_name, kind, "invalid", f"breaks the {kind} contract: {exc}")
                    continue
                if descriptor_name in registry.descriptors[kind]:
                    holder = next(r for r in registry.records if r.kind == kind
                                  and r.name == descriptor_name and r.status == "loaded")
                    record(descriptor_name, kind, "invalid",
                           f"another {kind} plugin is already named {descriptor_name!r} (entry "
                           f"point {holder.entry_point!r} of {holder.distribution} "
                           f"{holder.version}); this one is left out: rename it")
                    continue
                registry.descriptors[kind][descriptor_name] = descriptor
                record(descriptor_name, kind, "loaded")
