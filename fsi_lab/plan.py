"""Sequence plans: a base profile and the steps of a campaign, expanded into runs.

A plan is a TOML file (see examples/sweep-heights.toml)::

    [plan]
    profile = "../profiles/wet-beam-sim.toml"   # the base profile, relative to the plan
    set = ["run.duration=5"]         # --set overrides of every run
    settle_s = 2.0                   # wait before each run after the first, s
    on_failure = "stop"              # or "continue"

    [plan.stop_when]                 # optional: stop once a number is known well enough
    quantity = "c_f"                 # c_i or c_f of the aggregated runs
    relative_half_width = 0.05       # its 95 % interval within +-5 % of its value
    frequency_hz = 17.0              # of the mode nearest 17 Hz (default: the largest)
    min_runs = 2                     # not before 2 runs completed

    [[step]]
    name = "three heights"
    repeats = 2
    [step.sweep]
    "excitation.height" = [0.01, 0.02, 0.03]

Each ``[[step]]`` is one run, or with ``sweep`` one run per point: a list of values, a linear or
log range (``{ from = 0.005, to = 0.02, points = 3, scale = "log" }``), and several paths make a
grid (every combination, the last path varying fastest). ``repeats`` runs each point that many
times in a row. Every run's overrides are ``--set`` text (``path=value``), applied after the
plan's and the step's own ``set``, so a run of a sequence is exactly ``fsi-lab run PROFILE --set
...`` and its run file records them.

:func:`check_plan` validates and safety-checks every run's profile before anything is driven;
one bad run refuses the whole plan, naming the step, the run and the key; with ``stop_when``,
also a run whose analysis cannot give the quantity (no specimen for mu + M, no analysed
channel, not the channel named).
"""

from __future__ import annotations

import hashlib
import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fsi_lab.accuracy import ACCURACY
from fsi_lab.errors import FsiLabError, ParameterError, ProfileError
from fsi_lab.inputfiles import MAX_PROFILE_BYTES, read_text
from fsi_lab.params import Param, validate
from fsi_lab.profile import Profile, parse_profile, parse_toml
from fsi_lab.registry import Registry
from fsi_lab.safety import SafetyReport, require_safe

#: Most runs a plan may expand into (a grid grows fast; the record is rewritten whole, about
#: 1 s for 2000 runs, before and after each run).
MAX_RUNS = 2_000
ON_FAILURE = ("stop", "continue")

PLAN_PARAMS: tuple[Param, ...] = (
    Param("profile", "str", help="The base profile, a path relative to the plan file."),
    Param("name", "str", "", "", help="Free text naming the sequence."),
    Param("set", "strs", "", [], help="--set overrides (path=value) applied to every run."),
    Param("settle_s", "float", "s", 0.0, minimum=0.0, maximum=86400.0,
          help="Wait before each run that follows another, for the beam and fluid to settle."),
    Param("on_failure", "str", "", "stop", choices=ON_FAILURE,
          help="After a failed run: stop the sequence, or continue with the next run (an "
               "interlock, a bench not confirmed safe and Ctrl+C stop it whatever this says)."),
)

STEP_PARAMS: tuple[Param, ...] = (
    Param("name", "str", "", "", help="Free text naming the step."),
    Param("set", "strs", "", [], help="--set overrides (path=value) of this step's runs."),
    Param("repeats", "int", "", 1, minimum=1, maximum=1000,
          help="Runs of each point of the step, one after the other."),
    Param("settle_s", "float", "s", None, minimum=0.0, maximum=86400.0,
          help="Wait before each run of this step that follows another (default: the plan's)."),
)

STOP_QUANTITIES = ("c_i", "c_f")
#: How each quantity is written in messages.
STOP_SYMBOLS = {"c_i": "C_i", "c_f": "C_f"}
STOP_UNITS = {"c_i": "kg/(m s)", "c_f": "kg/m^2"}
STOP_PARAMS: tuple[Param, ...] = (
    Param("quantity", "str", "", choices=STOP_QUANTITIES,
          help="c_i (kg/(m s)) or c_f (kg/m^2) fitted to the union of the completed runs' "
               "free decays (fsi-lab aggregate)."),
    Param("relative_half_width", "float", "", minimum=0.0, exclusive_minimum=True,
          maximum=1.0,
          help="Stop once the quantity's 95 % interval reaches no further than this fraction "
               "of its value on either side (0.05: +-5 %); the runs not carried out are "
               "recorded as skipped. Above the method's accuracy (0.003 for c_i, 0.02 for "
               "c_f), which no aggregate's interval gets below."),
    Param("frequency_hz", "float", "Hz", None, minimum=0.0, exclusive_minimum=True,
          help="The mode: the aggregated mode nearest this frequency (unset: the one with the "
               "most extrema)."),
    Param("channel", "str", "", None,
          help="The channel whose mode it is (unset: any analysed channel)."),
    Param("min_runs", "int", "", 2, minimum=1, maximum=MAX_RUNS,
          help="Completed runs before the target may stop the sequence."),
)


@dataclass(frozen=True)
class StopWhen:
    """The plan's ``[plan.stop_when]``: stop once an aggregated quantity is known well enough
    (:data:`STOP_PARAMS`)."""

    quantity: str
    relative_half_width: float
    frequency_hz: float | None = None
    channel: str | None = None
    min_runs: int = 2

    def describe(self) -> str:
        """``C_f's 95 % interval within +-5 % (the mode nearest 17 Hz)``."""
        name = STOP_SYMBOLS[self.quantity]
        where = [f"the mode nearest {self.frequency_hz:g} Hz" if self.frequency_hz
                 else "the largest mode"]
        if self.channel:
            where.append(f"channel {self.channel}")
        return (f"{name}'s 95 % interval within +-{100 * self.relative_half_width:g} % "
                f"({', '.join(where)}), after {self.min_runs} run"
                f"{'s' * (self.min_runs != 1)}")


def _check_reachable(stop: StopWhen) -> None:
    """Refuse a target no aggregate can reach: an interval narrower than the method's
    accuracy (:data:`fsi_lab.accuracy.ACCURACY`), which the union's never goes below."""
    floor = ACCURACY[stop.quantity]
    if stop.relative_half_width <= floor:
        name = STOP_SYMBOLS[stop.quantity]
        raise ParameterError(
            f"plan.stop_when.relative_half_width: {stop.relative_half_width:g} can never be "
            f"reached: an aggregate's 95 % interval of {name} is never narrower than +-"
            f"{100 * floor:g} %, the identification's accuracy on records of known truth "
            f"(fsi_lab.accuracy); expected more than {floor:g}")


RANGE_PARAMS: tuple[Param, ...] = (
    Param("from", "float", help="First value of the range."),
    Param("to", "float", help="Last value of the range."),
    Param("points", "int", "", minimum=2, maximum=MAX_RUNS, help="Values in the range."),
    Param("scale", "str", "", "linear", choices=("linear", "log"),
          help="Evenly spaced values, or evenly spaced in their logarithm (from and to > 0)."),
)
RANGE_KEYS = frozenset(p.name for p in RANGE_PARAMS)
TOP_KEYS = ("plan", "step")


@dataclass(frozen=True)
class PlannedRun:
    """One run of a sequence.

    Attributes
    ----------
    index
        Position in the sequence, from 1.
    total
        Runs in the sequence.
    step, step_name
        The ``[[step]]`` table it comes from (from 1) and its name.
    point
        The sweep's ``(path, value text)`` pairs of this run (empty without a sweep).
    repeat, repeats
        Which repeat of its point (from 1), of how many.
    overrides
        Every ``--set`` override of the run: the plan's, the step's, then the point's.
    settle_s
        Wait before the run when another run precedes it, s.
    """

    index: int
    total: int
    step: int
    step_name: str
    point: tuple[tuple[str, str], ...]
    repeat: int
    repeats: int
    overrides: tuple[str, ...]
    settle_s: float

    @property
    def step_label(self) -> str:
        return step_label(self.step, self.step_name)

    @property
    def label(self) -> str:
        """``step 2 ("heights"), run 3 of 6 (excitation.height=0.02, repeat 1 of 2)``."""
        details = [f"{path}={value}" for path, value in self.point]
        if self.repeats > 1:
            details.append(f"repeat {self.repeat} of {self.repeats}")
        return (f"{self.step_label}, run {self.index} of {self.total}"
                + (f" ({', '.join(details)})" if details else ""))


def step_label(step: int, name: str) -> str:
    return f"step {step}" + (f" ({name!r})" if name else "")


@dataclass(frozen=True)
class Plan:
    """A parsed plan: its text, the base profile's text and the runs it expands into."""

    path: Path
    text: str
    name: str
    profile_path: Path
    profile_text: str
    on_failure: str
    runs: tuple[PlannedRun, ...]
    stop_when: StopWhen | None = None

    @property
    def sha256(self) -> str:
        return sha256(self.text)

    @property
    def profile_sha256(self) -> str:
        return sha256(self.profile_text)

    def profile_for(self, run: PlannedRun, registry: Registry) -> Profile:
        """The validated profile of ``run`` (ProfileError naming the profile and the key)."""
        return parse_profile(self.profile_text, str(self.profile_path), registry,
                             list(run.overrides))


def sha256(text: str) -> str:
    """Hex SHA-256 of ``text`` as UTF-8."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def value_text(value: Any, where: str) -> str:
    """A plan value (TOML number, string, boolean or list of them) as ``--set`` text.

    Floats keep every digit (``repr``), so the value the run gets is the value written.
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return value
    if isinstance(value, list) and value and all(
            isinstance(item, (bool, int, float, str)) for item in value):
        return ",".join(value_text(item, where) for item in value)
    raise ParameterError(f"{where}: got {value!r}; expected a number, a string, true or false, "
                         "or a list of them (for a list parameter)")


def sweep_values(spec: Any, where: str) -> list[str]:
    """The ``--set`` texts of one swept path: a list of values, or a range table.

    Parameters
    ----------
    spec
        ``[v1, v2, ...]`` or ``{from, to, points, scale}`` (``scale`` ``"linear"`` or ``"log"``).
    where
        Key path for messages (``sweep.excitation.height``).
    """
    if isinstance(spec, list):
        if not spec:
            raise ParameterError(f"{where}: an empty list; expected at least one value")
        return [value_text(item, f"{where}[{i}]") for i, item in enumerate(spec)]
    if isinstance(spec, dict):
        values = validate(RANGE_PARAMS, spec, where)
        low, high, points = values["from"], values["to"], values["points"]
        if values["scale"] == "log":
            if not (low > 0 and high > 0):
                raise ParameterError(f"{where}: a log range from {low:g} to {high:g}; expected "
                                     "from and to both > 0")
            numbers = np.geomspace(low, high, points)
        else:
            numbers = np.linspace(low, high, points)
        # 12 significant digits: 0.0075, not 0.007500000000000001
        return [repr(float(f"{x:.12g}")) for x in numbers]
    raise ParameterError(f"{where}: got {spec!r}; expected a list of values or a range "
                         "{ from = ..., to = ..., points = ..., scale = \"linear\" or \"log\" }")


def _sweep_paths(table: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """``(path, spec)`` of a sweep table, whose dotted keys TOML may have nested (a range
    table is recognised by its keys ``from``, ``to``, ``points``, ``scale``)."""
    found = []
    for key, value in table.items():
        path = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict) and value and not (set(value) & RANGE_KEYS):
            found.extend(_sweep_paths(value, path))
        else:
            found.append((path, value))
    return found


def parse_plan(text: str, path: Path) -> Plan:
    """Read plan ``text`` (from ``path``) and expand its runs; the base profile is read here
    but validated by :func:`check_plan`.

    Raises
    ------
    ProfileError
        Naming the plan, the step and the key, and what is accepted.
    """
    raw = parse_toml(text, str(path))
    try:
        unknown = sorted(set(raw) - set(TOP_KEYS))
        if unknown:
            raise ParameterError(f"{unknown[0]}: unknown key; a plan has a [plan] table and "
                                 "[[step]] tables")
        table = raw.get("plan")
        if not isinstance(table, dict):
            raise ParameterError("plan: missing; expected a [plan] table naming the profile")
        table = dict(table)
        stop = table.pop("stop_when", None)
        _refuse_unknown(table, PLAN_PARAMS, "plan", "stop_when")
        plan = validate(PLAN_PARAMS, table, "plan")
        if stop is not None and not isinstance(stop, dict):
            raise ParameterError(f"plan.stop_when: got {stop!r}; expected a table "
                                 "[plan.stop_when] with quantity and relative_half_width")
        stop_when = StopWhen(**validate(STOP_PARAMS, stop, "plan.stop_when")) \
            if stop is not None else None
        if stop_when is not None:
            _check_reachable(stop_when)
        steps = raw.get("step")
        if not isinstance(steps, list) or not steps or not all(isinstance(s, dict)
                                                               for s in steps):
            raise ParameterError("step: missing; expected one or more [[step]] tables")
    except ParameterError as exc:
        raise ProfileError(f"{path}: {exc}") from None
    runs: list[dict[str, Any]] = []
    for number, step in enumerate(steps, start=1):
        name = step.get("name") if isinstance(step.get("name"), str) else ""
        try:
            runs.extend(_expand(step, number, plan, len(runs)))
        except ParameterError as exc:
            raise ProfileError(f"{path}: {step_label(number, name)}: {exc}") from None
    profile_path = (path.parent / plan["profile"]) if not Path(plan["profile"]).is_absolute() \
        else Path(plan["profile"])
    try:
        profile_text = read_text(profile_path, "the plan's base profile (TOML text)",
                                 MAX_PROFILE_BYTES, error=ProfileError)
    except ProfileError as exc:
        raise ProfileError(f"{path}: plan.profile: {exc}") from None
    _seed_runs(runs, profile_text, str(profile_path))
    total = len(runs)
    return Plan(path=path, text=text, name=plan["name"], profile_path=profile_path,
                profile_text=profile_text, on_failure=plan["on_failure"],
                runs=tuple(PlannedRun(total=total, **run) for run in runs),
                stop_when=stop_when)


def _refuse_unknown(table: dict[str, Any], schema: tuple[Param, ...], where: str,
                    *tables: str) -> None:
    """ParameterError naming the first unknown key of ``table`` and every allowed one: the
    parameters of ``schema`` and the sub-tables ``tables`` (taken out before validation)."""
    allowed = {p.name for p in schema} | set(tables)
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ParameterError(f"{where}.{unknown[0]}: unknown key; allowed keys are "
                             f"{', '.join(sorted(allowed))}")


def _expand(step: dict[str, Any], number: int, plan: dict[str, Any],
            before: int) -> list[dict[str, Any]]:
    """The runs of one ``[[step]]`` table (``before`` runs precede it)."""
    step = dict(step)
    sweep = step.pop("sweep", {})
    _refuse_unknown(step, STEP_PARAMS, "step", "sweep")
    values = validate(STEP_PARAMS, step, "step")
    if not isinstance(sweep, dict):
        raise ParameterError(f"step.sweep: got {sweep!r}; expected a table of parameter paths, "
                             "e.g. sweep = { \"excitation.height\" = [0.01, 0.02] }")
    paths = _sweep_paths(sweep)
    axes = [[(p, text) for text in sweep_values(spec, f"step.sweep.{p}")] for p, spec in paths]
    count = math.prod(len(axis) for axis in axes) * values["repeats"]
    if before + count > MAX_RUNS:
        raise ParameterError(f"makes the plan {before + count:,} runs long; a plan holds at "
                             f"most {MAX_RUNS:,}")
    settle = plan["settle_s"] if values["settle_s"] is None else values["settle_s"]
    runs = []
    for point in itertools.product(*axes):
        for repeat in range(1, values["repeats"] + 1):
            runs.append({
                "index": before + len(runs) + 1, "step": number, "step_name": values["name"],
                "point": tuple(point), "repeat": repeat, "repeats": values["repeats"],
                "overrides": (*plan["set"], *values["set"],
                              *(f"{p}={text}" for p, text in point)),
                "settle_s": float(settle)})
    return runs


def _seed_runs(runs: list[dict[str, Any]], profile_text: str, where: str) -> None:
    """Give every run of the plan its own noise on a simulated bench.

    A simulated bench with one seed makes the same record every time, so runs with one seed
    (the repeats of a point, or the points of steps with ``repeats = 1`` whose excitation is
    the same) would be the same record, or share their noise, and an aggregation would count
    one record several times. Run ``i`` of the plan (numbered from 1 in the order carried out)
    whose overrides leave ``bench.seed`` alone runs with the base profile's seed + ``i - 1``,
    written as one more ``--set`` so its run file says so: deterministic from the plan, so a
    resumed sequence gives its runs the same seeds. A real bench has no seed: nothing is added
    when the base profile's bench is not embedded.
    """
    bench = parse_toml(profile_text, where).get("bench")
    bench = bench if isinstance(bench, dict) else {}
    base = bench.get("seed", 0)
    if bench.get("embedded") is not True or not isinstance(base, int) or isinstance(base, bool):
        return
    for run in runs:
        if run["index"] > 1 and not any(is_seed(o) for o in run["overrides"]):
            seed = (base + run["index"] - 1) % 2**32
            run["overrides"] = (*run["overrides"], f"bench.seed={seed}")


def is_seed(override: str) -> bool:
    """Whether ``override`` (``KEY=VALUE``) sets ``bench.seed``."""
    return override.split("=", 1)[0].strip() == "bench.seed"


def require_stop_can_act(plan: Plan) -> None:
    """ProfileError when ``[plan.stop_when]`` asks for more runs than the plan has, so it
    could never act. Checked when a sequence starts, not on resume: a sequence started with
    such a plan before this check continues as it was recorded."""
    total, stop_when = len(plan.runs), plan.stop_when
    if stop_when is not None and stop_when.min_runs > total:
        raise ProfileError(f"{plan.path}: plan.stop_when.min_runs: {stop_when.min_runs} is "
                           f"more than the plan's {total} run{'s' * (total != 1)}, so "
                           f"[plan.stop_when] can never act; expected at most {total} (or more "
                           "runs in the plan)")


def load_plan(path: str | Path) -> Plan:
    """Read and expand the plan file at ``path`` (:func:`parse_plan`)."""
    path = Path(path)
    text = read_text(path, "a sequence plan (TOML text)", MAX_PROFILE_BYTES, error=ProfileError)
    return parse_plan(text, path)


def check_plan(plan: Plan, registry: Registry,
               runs: tuple[PlannedRun, ...] | None = None) -> dict[int, SafetyReport]:
    """Validate and safety-check the profile of every run (or of ``runs``) before any is
    started: the profile check, the instruments' own checks and the safety limits, as
    ``fsi-lab run`` does them (runs with the same overrides are checked once).

    Returns
    -------
    dict
        The safety report of each run, by index.

    Raises
    ------
    ProfileError
        The first run refused, naming the plan, the step, the run and the key or limit.
    """
    from fsi_lab.runner import check_safety

    checked: dict[tuple[str, ...], SafetyReport] = {}
    reports = {}
    for run in plan.runs if runs is None else runs:
        if run.overrides not in checked:
            try:
                profile = plan.profile_for(run, registry)
                profile.require_runnable()
                _, _, report = check_safety(profile, registry)
                require_safe(report, profile.path)
                if plan.stop_when is not None:
                    check_stop_when(plan.stop_when, profile)
            except FsiLabError as exc:
                raise ProfileError(f"{plan.path}: {run.label}: {exc}") from None
            checked[run.overrides] = report
        reports[run.index] = checked[run.overrides]
    return reports


def check_stop_when(stop: StopWhen, profile: Profile) -> None:
    """ProfileError unless a run of ``profile`` gives ``stop``'s quantity: a specimen (for
    mu + M) and an analysed velocity or displacement channel (the one named, if one is)."""
    from fsi_lab.chain import ANALYSED_QUANTITIES

    where = "plan.stop_when"
    if profile.specimen is None:
        raise ProfileError(f"{profile.path}: {where}: {stop.quantity} needs mu + M, the mass "
                           "per length of beam and fluid: the profile has no [specimen]; give "
                           "it one or remove [plan.stop_when]")
    named = profile.analysis.get("channels") or []
    analysed = list(named) if named else [name for name, channel in profile.channels.items()
                                          if channel.quantity in ANALYSED_QUANTITIES]
    if not analysed:
        raise ProfileError(f"{profile.path}: {where}: the profile analyses no velocity or "
                           "displacement channel, so no run gives " + stop.quantity)
    if stop.channel is not None and stop.channel not in analysed:
        raise ProfileError(f"{profile.path}: {where}.channel: {stop.channel!r} is not analysed "
                           f"(analysed: {', '.join(analysed)})")
