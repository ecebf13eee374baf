"""Profiles: TOML files that describe the bench, the specimen, the excitation, the analysis
chain and the safety limits of a run.

Loading validates everything against the declared schemas (the core's sections below and each
named plugin's parameters) before anything is started or written. Every problem is reported as a
:class:`~fsi_lab.errors.ProfileError` naming the file, the key path and what is allowed.
"""

from __future__ import annotations

import copy
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from fsi_lab.chain import check_chain, default_chain
from fsi_lab.contract import ROLES
from fsi_lab.errors import ParameterError, PluginError, ProfileError
from fsi_lab.inputfiles import MAX_PROFILE_BYTES, nesting, read_text
from fsi_lab.modelling import MODEL_PARAMS
from fsi_lab.params import Param, Schema, find, validate
from fsi_lab.registry import Registry
from fsi_lab.specimen import SPECIMEN_PARAMS, Specimen
from fsi_lab.units import QUANTITIES, QUANTITY_OF_UNIT, SI_UNIT, STANDARD_GRAVITY

RUN_PARAMS: tuple[Param, ...] = (
    Param("name", "str", "", "", help="Free text describing the run."),
    Param("duration", "float", "s", 10.0, minimum=0.0, exclusive_minimum=True, maximum=86400.0,
          help="Length of the acquisition record."),
    Param("sample_rate", "float", "Hz", 10000.0, minimum=1.0, maximum=204800.0,
          help="Acquisition sample rate (the digitiser may round it)."),
    Param("block_duration", "float", "s", 0.1, minimum=0.001, maximum=0.5,
          help="Length of the blocks streamed from the digitiser into the run file (at most "
               "0.5 s: a crash loses at most 0.5 s of the record)."),
)

SAFETY_PARAMS: tuple[Param, ...] = (
    Param("max_drive_v", "float", "V", minimum=0.0, exclusive_minimum=True, maximum=10.0,
          help="Largest absolute source voltage the excitation may request."),
    Param("max_gain", "float", "V/V", minimum=0.0, exclusive_minimum=True, maximum=100.0,
          help="Largest amplifier gain the bench may be set to."),
    Param("max_stroke_mm", "float", "mm", minimum=0.0, exclusive_minimum=True, maximum=100.0,
          help="Largest base displacement (zero to peak) predicted by the shaker model."),
)

SHAKER_PARAMS: tuple[Param, ...] = (
    Param("suspension_hz", "float", "Hz", 30.0, minimum=0.1, maximum=2000.0,
          help="Resonance of the shaker armature on its suspension, loaded (about 30 Hz with "
               "the beam mount, 47 Hz unloaded)."),
    Param("damping_ratio", "float", "", 0.08, minimum=0.001, maximum=2.0,
          help="Damping ratio of the suspension resonance."),
    Param("mm_per_volt", "float", "mm/V", 0.5, minimum=0.0, exclusive_minimum=True,
          maximum=100.0, help="Static base displacement per volt at the amplifier output."),
)

CHANNEL_PARAMS: tuple[Param, ...] = (
    Param("quantity", "str", "", choices=QUANTITIES, help="What the channel measures."),
    Param("unit", "str", "", choices=tuple(SI_UNIT.values()),
          help="Unit the calibrated channel is stored in (SI: an acceleration in m/s^2)."),
    Param("sensitivity", "float", "V/unit", 1.0, minimum=1e-6, maximum=1e6,
          help="Sensor sensitivity: volts at the digitiser per unit of the quantity."),
    Param("input", "int", "", minimum=1, maximum=64, help="Digitiser input number."),
    Param("sensor", "str", "", "",
          help="Instrument role that sets this channel's sensitivity (e.g. 'vibrometer'); "
               "empty, or a role with a [bench.<role>] table."),
)

#: Channel names: they name HDF5 datasets in the run file and ``--set channels.<name>.key``
#: paths, so neither '/' nor '.' may appear in them.
CHANNEL_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]*")

BENCH_PARAMS: tuple[Param, ...] = (
    Param("embedded", "bool", "", False,
          help="Start the simulated bench inside the fsi-lab process; instruments whose "
               "address is 'embedded' connect to it."),
    Param("fast", "bool", "", False,
          help="Simulated bench only: run as fast as possible instead of in real time."),
    Param("fault", "str", "", "none",
          choices=("none", "timeout", "drop", "garble", "interlock", "overload"),
          help="Simulated bench only: inject this fault (for rehearsing failures)."),
    Param("fault_after_s", "float", "s", 1.0, minimum=0.0, maximum=86400.0,
          help="Simulated bench only: when the injected fault happens after the start."),
    Param("fault_target", "str", "", "acquisition",
          choices=("source", "amplifier", "vibrometer", "acquisition"),
          help="Simulated bench only: the instrument whose link a timeout, drop or garble "
               "fault hits."),
    Param("seed", "int", "", 0, minimum=0, maximum=2**32 - 1,
          help="Simulated bench only: seed of its noise generators (runs with the same seed "
               "see the same noise; a sequence's repeats take the next seeds)."),
)

ROLE_KEYS = ("plugin", "address")
REQUIRED_ROLES = ("source", "amplifier", "acquisition")

ANALYSIS_PARAMS: tuple[Param, ...] = (
    Param("chain", "strs", "", default=[], help="Analysis plugins to run, in order."),
    Param("channels", "strs", "", default=[],
          help="Channels to analyse; empty means every velocity or displacement channel."),
    Param("reference", "str", "", default=None,
          help="Base-acceleration channel used by transfer functions and the modal model."),
    Param("segment_samples", "int", "", default=None, minimum=1000, maximum=10_000_000_000,
          help="Memory budget of the analysis, in samples of the used channels (analysed and "
               "reference) together: a record holding more is analysed in segments cut "
               "between its free decays, each within the budget (default 2000000: about 1.3 GB "
               "for the whole process; docs/streaming-analysis.md)."),
    Param("segment_stride", "int", "", default=None, minimum=1, maximum=1_000_000,
          help="A record analysed in segments stores its per-sample results (components, "
               "envelopes, frequencies) every this many samples; default: as many as keep 40 "
               "samples per cycle at the top of the highest mode's band (1 keeps them all)."),
)

SECTIONS = ("run", "safety", "shaker", "specimen", "model", "bench", "channels", "excitation",
            "analysis")


@dataclass(frozen=True)
class RoleConfig:
    """One instrument of the bench."""

    role: str
    plugin: str
    address: str
    settings: dict[str, Any]


@dataclass(frozen=True)
class ChannelConfig:
    """One acquisition channel."""

    name: str
    quantity: str
    unit: str
    sensitivity: float
    input: int
    sensor: str


@dataclass(frozen=True)
class Profile:
    """A validated profile. ``text`` is the file verbatim, stored in every run file."""

    path: str
    text: str
    run: dict[str, Any]
    safety: dict[str, Any] | None
    shaker: dict[str, Any]
    specimen: Specimen | None
    model: dict[str, Any]
    bench: dict[str, Any]
    roles: dict[str, RoleConfig]
    channels: dict[str, ChannelConfig]
    excitation_plugin: str | None
    excitation: dict[str, Any]
    analysis: dict[str, Any]
    analysis_params: dict[str, dict[str, Any]]
    overrides: tuple[str, ...] = ()

    @property
    def can_run(self) -> bool:
        """True when the profile describes a bench and an excitation (not only an analysis)."""
        return bool(self.roles) and self.excitation_plugin is not None

    def require_runnable(self) -> None:
        """Raise ProfileError unless the profile describes a run (:attr:`can_run`): an empty,
        comment-only or cut-short file is valid TOML but has nothing to run."""
        if not self.can_run:
            raise ProfileError(
                f"{self.path}: nothing to run: no [bench.<role>] tables and no [excitation]; "
                f"expected a profile with [safety], "
                f"{', '.join('[bench.' + r + ']' for r in REQUIRED_ROLES)}, [channels.<name>] "
                "and [excitation] (see profiles/wet-beam-sim.toml)")


def _table(raw: Mapping[str, Any], key: str, where: str) -> dict[str, Any]:
    value = raw.get(key, {})
    if not isinstance(value, dict):
        raise ParameterError(f"{where}: expected a table ([{where}]), got {value!r}")
    return value


def _plugin_name(table: Mapping[str, Any], where: str) -> str:
    name = table.get("plugin")
    if not isinstance(name, str) or not name:
        raise ParameterError(f"{where}.plugin: missing; expected the name of a plugin")
    return name


def _plugin(registry: Registry, kind: str, name: str, where: str):
    try:
        return registry.get(kind, name)
    except PluginError as exc:
        raise ParameterError(f"{where}.plugin: {exc}") from None


def _role_schema(registry: Registry, role: str, table: Mapping[str, Any]) -> Schema:
    where = f"bench.{role}"
    descriptor = _plugin(registry, "instrument", _plugin_name(table, where), where)
    if descriptor.role != role:
        raise ParameterError(
            f"{where}.plugin: {descriptor.name!r} is a {descriptor.role} driver, not "
            f"{'an' if role[0] in 'aeiou' else 'a'} {role}"
        )
    return descriptor.params


def schema_for(raw: Mapping[str, Any], path: list[str], registry: Registry) -> Param:
    """The declared parameter at a dotted ``path`` of a profile (used by ``--set``)."""
    where = ".".join(path)
    section, rest = path[0], path[1:]
    fixed = {"run": RUN_PARAMS, "safety": SAFETY_PARAMS, "shaker": SHAKER_PARAMS,
             "specimen": SPECIMEN_PARAMS, "model": MODEL_PARAMS}
    schema: Schema | None = None
    name = rest[-1] if rest else ""
    if section in fixed and len(rest) == 1:
        schema = fixed[section]
    elif section == "excitation" and len(rest) == 1:
        table = _table(raw, "excitation", "excitation")
        schema = _plugin(registry, "excitation", _plugin_name(table, "excitation"),
                         "excitation").params
    elif section == "analysis" and len(rest) == 1:
        schema = ANALYSIS_PARAMS
    elif section == "analysis" and len(rest) == 2:
        schema = _plugin(registry, "analysis", rest[0], f"analysis.{rest[0]}").params
    elif section == "bench" and len(rest) == 1:
        schema = BENCH_PARAMS
    elif section == "bench" and len(rest) == 2 and rest[0] in ROLES:
        if rest[1] in ROLE_KEYS:
            return Param(rest[1], "str")
        bench = _table(raw, "bench", "bench")
        schema = _role_schema(registry, rest[0], _table(bench, rest[0], f"bench.{rest[0]}"))
    elif section == "channels" and len(rest) == 2:
        schema = CHANNEL_PARAMS
    if schema is None:
        raise ParameterError(
            f"{where}: no such parameter; use section.key (sections: {', '.join(SECTIONS)}), "
            "analysis.<plugin>.key, bench.<role>.key or channels.<name>.key"
        )
    param = find(schema, name)
    if param is None:
        allowed = ", ".join(p.name for p in schema)
        raise ParameterError(f"{where}: unknown key; allowed keys are {allowed}")
    return param


def apply_overrides(raw: dict[str, Any], overrides: list[str], registry: Registry) -> dict:
    """Return a copy of ``raw`` with each ``key.path=value`` of ``overrides`` applied.

    ``excitation.plugin=NAME`` is applied first, whatever its place: it replaces the
    ``[excitation]`` table by that plugin with its default parameters (the profile's are another
    plugin's), and the other ``excitation.*`` overrides then set the new plugin's parameters.
    ``analysis.chain+=NAME,...`` appends analyses to the chain in force (the profile's, an
    earlier override's, or the default chain of data without one), each that is not in it.
    """
    raw = copy.deepcopy(raw)
    parsed = []
    for item in overrides:
        key, sep, text = item.partition("=")
        key = key.strip()
        append = key.endswith("+")
        path = [part for part in key.removesuffix("+").strip().split(".") if part]
        if not sep or len(path) < 2:
            raise ParameterError(
                f"--set {item!r}: expected key.path=value, e.g. excitation.amplitude=0.5"
            )
        if append and path != ["analysis", "chain"]:
            raise ParameterError(
                f"--set {item!r}: += appends to the analysis chain only "
                "(analysis.chain+=NAME); expected key.path=value")
        parsed.append((path, text, append))
    parsed.sort(key=lambda entry: entry[0] != ["excitation", "plugin"])
    for path, text, append in parsed:
        if path == ["excitation", "plugin"]:
            name = text.strip()
            _plugin(registry, "excitation", name, "excitation")
            if _table(raw, "excitation", "excitation").get("plugin") != name:
                raw["excitation"] = {"plugin": name}
            continue
        param = schema_for(raw, path, registry)
        value = param.parse(text, ".".join(path))
        node = raw
        for part in path[:-1]:
            node = node.setdefault(part, {})
        if append:
            chain = list(node.get(path[-1]) or default_chain(registry))
            value = chain + [name for name in value if name not in chain]
        node[path[-1]] = value
    return raw


def load_profile(path: str | Path, registry: Registry, overrides: list[str] = (),
                 sections: tuple[str, ...] | None = None) -> Profile:
    """Read, override and validate a profile.

    Parameters
    ----------
    path
        The TOML file.
    registry
        Loaded plugins, whose schemas validate the plugin sections.
    overrides
        ``key.path=value`` strings from ``--set``.
    sections
        Keep only these sections (:func:`parse_profile`), or None for the whole profile.

    Raises
    ------
    ProfileError
        With the file name, the key path and what is allowed.
    """
    text = read_text(path, "a profile (TOML text)", MAX_PROFILE_BYTES, error=ProfileError)
    return parse_profile(text, str(path), registry, overrides, sections=sections)


#: Deepest nesting of tables and arrays a profile needs (``analysis.hvd.band_hz`` is 4 deep).
MAX_DEPTH = 8


def parse_toml(text: str, path: str) -> dict[str, Any]:
    """The tables of profile ``text`` (``path`` names it in messages).

    Raises
    ------
    ProfileError
        A TOML syntax error, or tables and arrays nested deeper than :data:`MAX_DEPTH`.
    """
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProfileError(f"{path}: TOML syntax error: {exc}") from None
    except RecursionError:
        raw = None
    depth, keys = nesting(raw) if raw is not None else (MAX_DEPTH + 1, [])
    if depth > MAX_DEPTH:
        where = ".".join(keys[:3]).replace(".[", "[") if keys else "the profile"
        raise ProfileError(
            f"{path}: {where}: tables or arrays nested more than {MAX_DEPTH} levels deep; "
            f"a profile's sections nest at most {MAX_DEPTH} levels "
            "(e.g. [analysis.hvd] band_hz = [10, 20])")
    return raw


def parse_profile(text: str, path: str, registry: Registry, overrides: list[str] = (),
                  sections: tuple[str, ...] | None = None) -> Profile:
    """Validate profile ``text`` (``path`` names it in messages); see :func:`load_profile`.

    With ``sections``, only those sections are kept and validated (``fsi-lab analyze`` keeps
    ``analysis`` and ``specimen`` so that a run made with drivers not installed here can still
    be analysed), and ``--set`` may address only them.
    """
    raw = parse_toml(text, path)
    if sections is not None:
        raw = {key: value for key, value in raw.items() if key in sections}
        for item in overrides:
            if item.split(".", 1)[0] not in sections:
                raise ProfileError(
                    f"--set {item!r}: only {', '.join(sections)} parameters can be set here"
                )
    try:
        raw = apply_overrides(raw, list(overrides), registry)
        return _validate(raw, path, text, registry, tuple(overrides),
                         complete=sections is None,
                         bench_kept=sections is None or "bench" in sections)
    except ParameterError as exc:
        raise ProfileError(f"{_culprit(str(exc), path, overrides)}: {exc}") from None


def _culprit(message: str, path: str, overrides: list[str] | tuple[str, ...]) -> str:
    """Where the value a message about ``KEY: ...`` refuses came from: the profile at
    ``path``, and the last ``--set`` of that key when one gave it."""
    key = message.partition(":")[0].strip()
    given = [item for item in overrides if item.partition("=")[0].strip() == key]
    return f"{path}: --set {given[-1]}" if given else path


def _channel(name: str, table: Any, roles: Mapping[str, RoleConfig] | None) -> ChannelConfig:
    """The checked ``[channels.<name>]`` table; its ``sensor`` must name one of ``roles`` (not
    checked when ``roles`` is None: the bench was not kept)."""
    where = f"channels.{name}"
    if not CHANNEL_NAME.fullmatch(name):
        raise ParameterError(
            f"{where}: channel name {name!r} is not accepted; expected a letter followed by "
            "letters, digits, '_' or '-' (e.g. tip_velocity)"
        )
    if not isinstance(table, dict):
        raise ParameterError(f"{where}: expected a table ([{where}]), got {table!r}")
    if table.get("unit") == "g":  # read as m/s^2 by the analysis: refused before a run
        sensitivity = table.get("sensitivity")
        per_si = (f"{sensitivity} V/g is {float(sensitivity) / STANDARD_GRAVITY:.6g} V/(m/s^2)"
                  if isinstance(sensitivity, (int, float)) and not isinstance(sensitivity, bool)
                  else f"S V/g is S/{STANDARD_GRAVITY:g} V/(m/s^2)")
        raise ParameterError(
            f"{where}.unit: 'g' is not accepted for a recorded channel (runs store SI units, "
            "and the analysis and the modal model read an acceleration in m/s^2); expected "
            f"'m/s^2' with the sensitivity in V/(m/s^2): {per_si}")
    values = validate(CHANNEL_PARAMS, table, where)
    implied = QUANTITY_OF_UNIT[values["unit"]]
    if implied != values["quantity"]:
        raise ParameterError(
            f"{where}.unit: {values['unit']!r} is a unit of {implied}, but the channel's "
            f"quantity is {values['quantity']!r}"
        )
    if values["sensor"] and roles is not None and values["sensor"] not in roles:
        accepted = ", ".join(repr(role) for role in roles) or "none (no [bench.<role>] tables)"
        raise ParameterError(
            f"{where}.sensor: {values['sensor']!r} is not an instrument of this bench; expected "
            f"empty or one of the roles with a [bench.<role>] table: {accepted}"
        )
    return ChannelConfig(name=name, **values)


#: Fewest samples a record may hold (one period of the lowest frequency needs two).
MIN_RECORD_SAMPLES = 2


def _check_record(run: Mapping[str, Any]) -> None:
    """The ``[run]`` record must hold :data:`MIN_RECORD_SAMPLES` samples at least."""
    samples = round(run["duration"] * run["sample_rate"])
    if samples < MIN_RECORD_SAMPLES:
        raise ParameterError(
            f"run.duration: {run['duration']:g} s at run.sample_rate = {run['sample_rate']:g} Hz "
            f"records {samples} sample{'s' if samples != 1 else ''}; expected at least "
            f"{MIN_RECORD_SAMPLES} (a duration of {MIN_RECORD_SAMPLES / run['sample_rate']:g} s "
            "or more)")


def _check_model(specimen: Specimen, model: Mapping[str, Any]) -> None:
    """The beam model of ``[specimen]`` and ``[model]`` must be one the model can build (the
    damping given one way, ratios for the modes)."""
    from fsi_lab.modelling import beam_model

    try:
        beam_model(specimen, dict(model))
    except ParameterError as exc:
        raise ParameterError(f"model: {exc}") from None


def _validate(raw, path, text, registry, overrides, complete=True, bench_kept=True) -> Profile:
    """The checked profile; ``complete`` False when only some sections were kept, so a bench
    need not come with its excitation and channels; ``bench_kept`` False when ``[bench]`` was
    not among them, so a channel's ``sensor`` cannot be checked against its roles."""
    unknown = sorted(set(raw) - set(SECTIONS))
    if unknown:
        raise ParameterError(
            f"{unknown[0]}: unknown section; allowed sections are {', '.join(SECTIONS)}"
        )
    run = validate(RUN_PARAMS, _table(raw, "run", "run"), "run")
    shaker = validate(SHAKER_PARAMS, _table(raw, "shaker", "shaker"), "shaker")
    specimen = (
        Specimen.from_mapping(_table(raw, "specimen", "specimen"))
        if "specimen" in raw else None
    )
    model = validate(MODEL_PARAMS, _table(raw, "model", "model"), "model")

    bench_raw = dict(_table(raw, "bench", "bench"))
    role_tables = {role: bench_raw.pop(role) for role in ROLES if role in bench_raw}
    bench = validate(BENCH_PARAMS, bench_raw, "bench")
    roles: dict[str, RoleConfig] = {}
    for role, table in role_tables.items():
        where = f"bench.{role}"
        if not isinstance(table, dict):
            raise ParameterError(f"{where}: expected a table ([{where}]), got {table!r}")
        schema = _role_schema(registry, role, table)
        address = table.get("address", "")
        if not isinstance(address, str):
            raise ParameterError(f"{where}.address: expected a string (VISA resource or port)")
        settings = {k: v for k, v in table.items() if k not in ROLE_KEYS}
        roles[role] = RoleConfig(role, table["plugin"], address,
                                 validate(schema, settings, where))

    channels = {name: _channel(name, table, roles if bench_kept else None)
                for name, table in _table(raw, "channels", "channels").items()}

    excitation_plugin = None
    excitation: dict[str, Any] = {}
    if "excitation" in raw:
        table = dict(_table(raw, "excitation", "excitation"))
        excitation_plugin = _plugin_name(table, "excitation")
        descriptor = _plugin(registry, "excitation", excitation_plugin, "excitation")
        table.pop("plugin")
        excitation = validate(descriptor.params, table, "excitation")

    analysis_raw = dict(_table(raw, "analysis", "analysis"))
    plugin_tables = {k: analysis_raw.pop(k) for k in list(analysis_raw)
                     if isinstance(analysis_raw[k], dict)}
    analysis = validate(ANALYSIS_PARAMS, analysis_raw, "analysis")
    analysis_params: dict[str, dict[str, Any]] = {}
    for name in analysis["chain"]:
        descriptor = _plugin(registry, "analysis", name, f"analysis.{name}")
        analysis_params[name] = validate(descriptor.params, plugin_tables.pop(name, {}),
                                         f"analysis.{name}")
    check_chain(analysis["chain"], registry)   # each finds what it requires before it
    # A chain shortened with --set leaves the other plugins' tables unused, not wrong.
    chain_overridden = any(item.partition("=")[0].strip() == "analysis.chain"
                           for item in overrides)
    if plugin_tables and not chain_overridden:
        extra = sorted(plugin_tables)[0]
        raise ParameterError(
            f"analysis.{extra}: parameters for a plugin that is not in analysis.chain "
            f"({', '.join(analysis['chain']) or 'empty'}); add it to the chain or remove the table"
        )
    for name in analysis["channels"] + ([analysis["reference"]] if analysis["reference"] else []):
        if channels and name not in channels:
            raise ParameterError(
                f"analysis: channel {name!r} is not defined; channels are {', '.join(channels)}"
            )

    safety = None
    if complete and (roles or excitation_plugin):
        if "safety" not in raw:
            raise ParameterError(
                "safety: missing; a profile that drives a bench needs [safety] with "
                "max_drive_v, max_gain and max_stroke_mm"
            )
        missing_roles = [r for r in REQUIRED_ROLES if r not in roles]
        if missing_roles:
            raise ParameterError(
                f"bench.{missing_roles[0]}: missing; a runnable profile needs "
                f"{', '.join('[bench.' + r + ']' for r in REQUIRED_ROLES)}"
            )
        if excitation_plugin is None:
            raise ParameterError("excitation: missing; expected [excitation] with a plugin")
        if not channels:
            raise ParameterError("channels: missing; expected at least one [channels.<name>]")
    if "safety" in raw:
        safety = validate(SAFETY_PARAMS, _table(raw, "safety", "safety"), "safety")
    if specimen is not None and specimen.measurement_point > specimen.length:
        raise ParameterError(
            f"specimen.measurement_point: {specimen.measurement_point} m lies beyond the beam "
            f"(length {specimen.length} m); expected a point between 0 and the length"
        )
    if specimen is not None:
        _check_model(specimen, model)
    if complete:
        _check_record(run)

    return Profile(path=path, text=text, run=run, safety=safety, shaker=shaker,
                   specimen=specimen, model=model, bench=bench, roles=roles, channels=channels,
                   excitation_plugin=excitation_plugin, excitation=excitation,
                   analysis=analysis, analysis_params=analysis_params, overrides=overrides)
