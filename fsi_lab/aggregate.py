"""Aggregation across runs: one answer, with its spread, from many runs of the same beam.

``fsi-lab aggregate RUN.h5 ... | DIR`` and a sequence (as its runs complete) identify each run's
modes (:mod:`fsi_lab.aggregate_extract`, through an executor: in parallel with ``--jobs`` or on a
Dask cluster), then:

- group the modes across runs by frequency (per channel: modes within
  :data:`FREQUENCY_TOLERANCE` of a group's median small-amplitude natural frequency are one
  mode; each run gives a group at most its largest mode there);
- fit C_i and C_f to the union of the free decays of the group's runs, with intervals
  (:mod:`fsi_lab.aggregate_fit`), and say whether the runs together prefer the quadratic law;
- put the backbones and damping curves (C_q against amplitude) of all runs on one amplitude
  axis: the displacement amplitude in the coordinate C_i and C_f belong to (the modal
  coordinate when the run has a beam model, else as measured), with their medians on
  :data:`AXIS_POINTS` logarithmically spaced amplitudes and the fitted C_q line there;
- give the between-run spread (repeatability: the standard deviation of the runs' own
  values) next to the median within-run 95 % interval (its half width), and the amplitude
  range the runs cover.

The result is one JSON-ready dict (layout in docs/sequence-format.md, "Aggregation").
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from fsi_lab import accuracy as method_accuracy
from fsi_lab.aggregate_extract import ExtractTask, ModeExtract, RunExtract, extract_run
from fsi_lab.errors import FsiLabError
from fsi_lab.summary import coefficient_words, fluid_power_words

#: Modes of different runs closer than this (relative) to a group's median natural frequency
#: are the same mode.
FREQUENCY_TOLERANCE = 0.05
#: Amplitudes of the common axis of the curves.
AXIS_POINTS = 16
LEVEL = 0.95


def extract_runs(tasks: Sequence[ExtractTask], executor, on_done=None) -> list[RunExtract]:
    """Every task's :class:`~fsi_lab.aggregate_extract.RunExtract`, in the order of ``tasks``,
    extracted by ``executor`` (:mod:`fsi_lab.executor`); a run that fails is kept with its
    error. ``on_done(count)`` is called after each."""
    out: list[RunExtract | None] = [None] * len(tasks)
    for done, result in enumerate(executor.map_unordered(extract_run, tasks), start=1):
        task = tasks[result.index]
        if result.ok:
            out[result.index] = result.value
        else:
            out[result.index] = RunExtract(path=task.path, label=task.label or task.path,
                                           errors=[result.error], exit_code=result.exit_code)
        if on_done is not None:
            on_done(done)
    return [extract for extract in out if extract is not None]


def group_modes(extracts: Iterable[RunExtract]) -> list[list[tuple[int, ModeExtract]]]:
    """The modes of the runs grouped by channel and frequency (module notes): lists of
    ``(run position, mode)``, by channel then increasing frequency."""
    by_channel: dict[str, list[tuple[int, ModeExtract]]] = {}
    for position, extract in enumerate(extracts):
        for mode in extract.modes:
            by_channel.setdefault(mode.channel, []).append((position, mode))
    groups = []
    for channel in sorted(by_channel):
        found: list[list[tuple[int, ModeExtract]]] = []
        for position, mode in sorted(by_channel[channel], key=lambda pm: pm[1].frequency_hz):
            if found:
                centre = float(np.median([m.frequency_hz for _, m in found[-1]]))
                if abs(mode.frequency_hz / centre - 1.0) <= FREQUENCY_TOLERANCE:
                    same_run = [i for i, (p, _) in enumerate(found[-1]) if p == position]
                    if not same_run:
                        found[-1].append((position, mode))
                    elif mode.index < found[-1][same_run[0]][1].index:  # the larger mode
                        found[-1][same_run[0]] = (position, mode)
                    continue
            found.append([(position, mode)])
        groups.extend(sorted(group, key=lambda pm: pm[0]) for group in found)
    return groups


def _finite(value: float) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


def _spread(values: list[float], intervals: list[list[float]]) -> dict[str, Any]:
    """Between-run standard deviation of ``values`` and the median half width of their
    within-run intervals."""
    arr = np.asarray(values, dtype=np.float64)
    mean = float(arr.mean()) if arr.size else math.nan
    sd = float(arr.std(ddof=1)) if arr.size > 1 else math.nan
    halves = [0.5 * (hi - lo) for lo, hi in intervals if lo is not None and hi is not None]
    return {"mean": _finite(mean), "sd": _finite(sd),
            "sd_pct": _finite(100.0 * sd / abs(mean)) if mean else None,
            "median_half_width": _finite(float(np.median(halves))) if halves else None,
            "runs": int(arr.size)}


def _medians(x: np.ndarray, y: np.ndarray, runs: np.ndarray, edges: np.ndarray
             ) -> tuple[list, list]:
    values, counts = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = (x >= lo) & (x <= hi) & np.isfinite(y)
        values.append(_finite(float(np.median(y[inside]))) if inside.any() else None)
        counts.append(int(np.unique(runs[inside]).size))
    return values, counts


def _curves(members: list[tuple[int, ModeExtract]], c_i: float | None, c_f: float | None,
            frequency: float) -> tuple[dict[str, Any], dict[str, Any], list[float]]:
    """The runs' backbones and damping curves on one amplitude axis, and their medians."""
    from fsi_lab.dsp.equivalent_damping import equivalent_coefficient

    bb_a, bb_f, bb_r, dm_a, dm_q, dm_z, dm_r = [], [], [], [], [], [], []
    for position, mode in members:
        scale = abs(mode.modal_scale)
        bb_a.append(mode.backbone_amplitude / scale)
        bb_f.append(mode.backbone_frequency)
        bb_r.append(np.full(mode.backbone_amplitude.size, position))
        dm_a.append(mode.damping_amplitude / scale)
        dm_z.append(mode.damping_zeta)
        dm_q.append(equivalent_coefficient(mode.damping_zeta, mode.damping_frequency,
                                           mode.mass_per_length))
        dm_r.append(np.full(mode.damping_amplitude.size, position))
    cat = [np.concatenate(part) for part in (bb_a, bb_f, bb_r, dm_a, dm_q, dm_z, dm_r)]
    bb_a, bb_f, bb_r, dm_a, dm_q, dm_z, dm_r = cat
    lo_hi = [min(m.amplitude_range[1] / abs(m.modal_scale) for _, m in members),
             max(m.amplitude_range[0] / abs(m.modal_scale) for _, m in members)]
    edges = np.geomspace(lo_hi[0], lo_hi[1], AXIS_POINTS + 1) if lo_hi[1] > lo_hi[0] > 0 \
        else np.array(lo_hi)
    centres = np.sqrt(edges[:-1] * edges[1:])
    freq, freq_runs = _medians(bb_a, bb_f, bb_r, edges)
    c_q, c_q_runs = _medians(dm_a, dm_q, dm_r, edges)
    omega = 2.0 * math.pi * frequency
    fitted = [None if c_i is None or c_f is None else c_i + 8.0 * c_f * omega * w / (3.0 * math.pi)
              for w in centres]
    curves = {"backbone": {"amplitude_m": bb_a, "frequency_hz": bb_f, "run": bb_r},
              "damping": {"amplitude_m": dm_a, "c_q": dm_q, "zeta": dm_z, "run": dm_r}}
    axis = {"amplitude_m": centres.tolist(), "backbone_frequency_hz": freq,
            "backbone_runs": freq_runs, "c_q": c_q, "c_q_runs": c_q_runs, "c_q_fit": fitted}
    return curves, axis, lo_hi


def group_summary(members: list[tuple[int, ModeExtract]], labels: list[str]
                  ) -> dict[str, Any]:
    """One group of modes (:func:`group_modes`) as its JSON-ready entry: C_i and C_f fitted to
    the union of its runs' decays with intervals, each run's own numbers (``per_run``), the
    spread between runs and the curves (layout in docs/sequence-format.md, "Aggregation";
    ``labels`` name the runs by position)."""
    first = members[0][1]
    modes = [m for _, m in members]
    frequency = float(np.median([m.frequency_hz for m in modes]))
    mass = float(np.median([m.mass_per_length for m in modes]))
    scale = float(np.median([m.modal_scale for m in modes]))
    per_run = []
    for position, mode in members:
        own = mode.coefficients(LEVEL)
        per_run.append({"run": position, "label": labels[position], "component": mode.index,
                        "frequency_hz": mode.frequency_hz,
                        "frequency_ci95_hz": list(mode.frequency_ci), **own,
                        "amplitude_range_m": [mode.amplitude_range[1] / abs(mode.modal_scale),
                                              mode.amplitude_range[0] / abs(mode.modal_scale)],
                        "warnings": list(mode.warnings)})
    entry: dict[str, Any] = {
        "channel": first.channel, "frequency_hz": frequency,
        "frequency_range_hz": [min(m.frequency_hz for m in modes),
                               max(m.frequency_hz for m in modes)],
        "runs": len(members), "mass_per_length": mass, "modal_scale": scale,
        "amplitude_convention": first.amplitude_convention}
    differing = [m for m in modes if abs(m.mass_per_length / mass - 1) > 1e-9
                 or abs(m.modal_scale / scale - 1) > 1e-9]
    c_i = c_f = None
    power_warning: list[str] = []
    if differing:
        entry["fit_error"] = ("the runs have different beams (mu + M or mode shape differ: "
                              f"{', '.join(labels[p] for p, m in members if m in differing)}); "
                              "aggregate the runs of one beam")
    else:
        from fsi_lab.aggregate_fit import fit_union

        try:
            union = fit_union([m.run_decays() for m in modes])
        except FsiLabError as exc:
            entry["fit_error"] = str(exc)
        else:
            (a_lo, a_hi), (b_lo, b_hi) = union.interval("a", LEVEL), union.interval("beta",
                                                                                      LEVEL)
            ci, cf = 2.0 * mass, mass * scale
            c_i, c_f = ci * union.value("a"), cf * union.value("beta")
            entry.update({
                "c_i": c_i, "c_i_ci95": [ci * a_lo, ci * a_hi],
                "c_f": c_f, "c_f_ci95": [cf * b_lo, cf * b_hi],
                "decays": union.decays, "extrema": union.extrema,
                "preferred_law": union.comparison.preferred, "pooled_by": union.pooled,
                "delta_aicc": {k: float(v) for k, v in union.comparison.delta.items()},
                "widened": {
                    "runs": [float(f) for f in union.widenings],
                    "noise": float(union.noise_factor),
                    "spread": {"c_i": float(union.spread_factor[0]),
                               "c_f": float(union.spread_factor[1])},
                    "spread_chi2": {"c_i": _finite(union.spread_chi2[0]),
                                    "c_f": _finite(union.spread_chi2[1])},
                    "accuracy": {"c_i": _finite(union.accuracy_factor[0]),
                                 "c_f": _finite(union.accuracy_factor[1])}}})
            low, high = union.power.interval(LEVEL) if union.power is not None \
                else (math.nan, math.nan)
            if math.isfinite(low) and math.isfinite(high):
                from fsi_lab.dsp.identify import fluid_power_warning

                entry.update(fluid_power=union.power.power, fluid_power_ci95=[low, high])
                power_warning = fluid_power_warning(union.power.power, low, high,
                                                    union.power.change)
    entry["between_runs"] = {
        "c_i": _spread([r["c_i"] for r in per_run], [r["c_i_ci95"] for r in per_run]),
        "c_f": _spread([r["c_f"] for r in per_run], [r["c_f_ci95"] for r in per_run]),
        "frequency_hz": _spread([r["frequency_hz"] for r in per_run],
                                [r["frequency_ci95_hz"] for r in per_run])}
    entry["warnings"] = power_warning + _pooled_warnings(per_run)
    curves, axis, lo_hi = _curves(members, c_i, c_f, frequency)
    entry.update(amplitude_range_m=lo_hi, per_run=per_run, axis=axis, curves=curves)
    return entry


#: A number in a warning (its values across runs are given as a range).
_NUMBER = re.compile(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def _gist(warning: str) -> str:
    """A warning's first clause: up to its first colon, semicolon or parenthesis (the rest
    says why and what was done, in the run's own warnings)."""
    cut = min((i for i in (warning.find(": "), warning.find("; "), warning.find(" (")) if i > 0),
              default=len(warning))
    return warning[:cut].strip()


def _warning_kinds(per_run: list[dict[str, Any]]) -> list[tuple[str, int]]:
    """The distinct warnings of the runs, shortened (:func:`_gist`), with how many runs carry
    each, most frequent first: warnings that differ only by their numbers are one, their
    numbers given as ranges (``up to`` a number: the largest)."""
    kinds: dict[str, list[list[float]]] = {}
    runs: dict[str, set[int]] = {}
    for position, run in enumerate(per_run):
        for warning in run["warnings"]:
            gist = _gist(warning)
            template = _NUMBER.sub("{}", gist.replace("{", "(").replace("}", ")"))
            kinds.setdefault(template, []).append([float(v) for v in _NUMBER.findall(gist)])
            runs.setdefault(template, set()).add(position)
    out = []
    for template, numbers in kinds.items():
        texts, pieces = [], template.split("{}")
        for slot in range(len(pieces) - 1):
            values = [n[slot] for n in numbers]
            low, high = min(values), max(values)
            if pieces[slot].endswith("up to ") or f"{low:g}" == f"{high:g}":
                texts.append(f"{high:g}")
            else:
                texts.append(f"{low:g} to {high:g}")
        out.append(("".join(p + t for p, t in zip(pieces, [*texts, ""])),
                    len(runs[template])))
    return sorted(out, key=lambda kind: -kind[1])


def _pooled_warnings(per_run: list[dict[str, Any]]) -> list[str]:
    """A sentence when runs of the group carry warnings on the mode: which (each distinct
    warning, shortened, with how many runs carry it), and that pooling narrows what differs
    between runs (their noise, their scatter), not a bias they share, which those warnings
    may name (a law that misfits, decays whose start is not free, a close mode's smear
    corrected with a model); empty when no run was warned."""
    warned = [r for r in per_run if r["warnings"]]
    if not warned:
        return []
    kinds = "; ".join(f"{text} ({count} run{'s' * (count != 1)})"
                      for text, count in _warning_kinds(per_run))
    return [f"{len(warned)} of {len(per_run)} runs carry warnings on this mode: {kinds}. "
            "Pooling narrows the runs' noise and scatter, not a bias they share: where these "
            "warnings name one (a damping law that misfits, decays whose start is not free, a "
            "smear corrected with a model), every run carries it, and the pooled interval, "
            "narrower than each run's own, may miss the true value that the runs' own "
            "intervals hold; read each run's warnings and interval beside the pooled numbers"]


def same_records(extracts: Sequence[RunExtract]) -> dict[int, int]:
    """The runs (by position) whose analysed channels hold the same samples as an earlier
    run's (:func:`~fsi_lab.aggregate_extract.record_fingerprint`), each with the position of
    the first: one record under several files (and uuids), which pooled as independent runs
    would narrow the intervals and show no spread between them."""
    first: dict[str, int] = {}
    same: dict[int, int] = {}
    for position, extract in enumerate(extracts):
        if not extract.fingerprint or not extract.modes:
            continue
        if extract.fingerprint in first:
            same[position] = first[extract.fingerprint]
        else:
            first[extract.fingerprint] = position
    return same


def _same_record_notes(labels: list[str], same_as: dict[int, int]) -> list[str]:
    """A note per record given more than once, naming its files."""
    notes = []
    for original in sorted(set(same_as.values())):
        copies = [labels[k] for k in sorted(same_as) if same_as[k] == original]
        notes.append(
            f"{', '.join(copies)}: the same record as {labels[original]}, sample for sample "
            f"(their analysed channels hold identical samples: a copy, or runs of the "
            f"simulated bench with one bench.seed); pooled once, as {labels[original]}: "
            f"{len(copies) + 1} copies of one record are one measurement, not "
            f"{len(copies) + 1} independent runs")
    return notes


def _unapplied_notes(extracts: Sequence[RunExtract]) -> list[str]:
    """A note per set of overrides that runs' stored analyses were computed with and this
    aggregation is not (:attr:`~fsi_lab.aggregate_extract.RunExtract.unapplied`), naming
    the runs: their numbers here are not those ``fsi-lab show`` prints for them."""
    runs: dict[tuple[str, ...], list[str]] = {}
    for extract in extracts:
        if extract.unapplied:
            runs.setdefault(tuple(extract.unapplied), []).append(extract.label)
    return [f"{', '.join(labels)}: {'its' if len(labels) == 1 else 'their'} stored analysis "
            f"(what fsi-lab show prints) was computed with {' '.join(items)} beyond the run's "
            "own settings, and this aggregate identifies the modes without it: give the same "
            "to aggregate (--set KEY=VALUE, --mass-per-length) to pool that analysis"
            for items, labels in runs.items()]


def aggregate_extracts(extracts: Sequence[RunExtract]) -> dict[str, Any]:
    """The aggregation of the runs (module notes) as one JSON-ready dict.

    Returns
    -------
    dict
        ``runs`` (each run's ``label``, ``run`` path, ``modes`` found, ``errors`` and
        ``exit_code``), ``modes`` (one entry per mode group), ``amplitude_range_m`` over every
        mode, and ``exit_code``: 2 when runs were refused (and no other failed), 1 when a run's
        analysis failed or a mode's fit did, or no mode was found, else 0.
    """
    labels = [extract.label for extract in extracts]
    same_as = same_records(extracts)
    runs = [{"label": e.label, "run": e.path, "modes": len(e.modes), "errors": list(e.errors),
             "exit_code": e.exit_code, "start_time": e.start_time,
             "same_record_as": labels[same_as[k]] if k in same_as else None}
            for k, e in enumerate(extracts)]
    # a record given several times is pooled once (as its first file): the others lend no modes
    pooled = [dataclasses.replace(e, modes=[]) if k in same_as else e
              for k, e in enumerate(extracts)]
    modes = [group_summary(group, labels) for group in group_modes(pooled)]
    ranges = [m["amplitude_range_m"] for m in modes]
    failed = [e.exit_code for e in extracts if e.exit_code]
    code = (2 if all(c == 2 for c in failed) else 1) if failed else 0
    if not failed and (not modes or any("fit_error" in m for m in modes)):
        code = 1
    return {"runs": runs, "runs_with_modes": sum(1 for e in extracts if e.modes),
            "distinct_records": sum(1 for k, e in enumerate(extracts)
                                    if e.modes and k not in same_as),
            "notes": _same_record_notes(labels, same_as) + _unapplied_notes(extracts),
            "exit_code": code,
            "modes": modes,
            "amplitude_range_m": [min(r[0] for r in ranges), max(r[1] for r in ranges)]
            if ranges else None}


def plain(value: Any) -> Any:
    """``value`` with numpy numbers and arrays as Python numbers and lists (for JSON)."""
    if isinstance(value, dict):
        return {key: plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(item) for item in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


#: The datasets of each mode's curves in a stored aggregation (``curves[name][key]``).
def main_mode(agg: dict[str, Any] | None) -> dict[str, Any] | None:
    """The aggregated mode with the most extrema (the best measured: what a sequence's stop
    rule watches by default and the GUI draws), or None when the aggregation has none."""
    modes = (agg or {}).get("modes") or []
    return max(modes, key=lambda m: m.get("extrema", 0)) if modes else None


CURVES = {"backbone": ("amplitude_m", "frequency_hz", "run"),
          "damping": ("amplitude_m", "c_q", "zeta", "run")}


def without_curves(agg: dict[str, Any]) -> dict[str, Any]:
    """The aggregation without each mode's curves (what a sequence record keeps as text)."""
    return plain({**agg, "modes": [{k: v for k, v in mode.items() if k != "curves"}
                                   for mode in agg["modes"]]})


# --------------------------------------------------------------------------- text
def _power(entry: dict[str, Any]) -> str:
    """The power of the velocity the union's fluid term grows with, in words, or nothing
    when it was not tested."""
    if entry.get("fluid_power") is None:
        return ""
    return fluid_power_words(entry["fluid_power"], entry["fluid_power_ci95"])


def _widening(entry: dict[str, Any]) -> str:
    """``; runs weighted by their own widening (x1.4 to x2.9), intervals x1.9 ...``."""
    widened = entry.get("widened") or {}
    parts = []
    runs = [f for f in widened.get("runs", []) if f > 1.05]
    if runs:
        span = f"x{min(runs):.2g}" + (f" to x{max(runs):.2g}" if f"{min(runs):.2g}"
                                      != f"{max(runs):.2g}" else "")
        parts.append(f"{len(runs)} run{'s' * (len(runs) != 1)} weighted down by "
                     f"{'its' if len(runs) == 1 else 'their'} own "
                     f"widening ({span}), intervals x{widened.get('noise', 1.0):.2g}")
    spread = widened.get("spread") or {}
    shown = [f"{name} x{value:.2g}" for name, value in
             (("C_i", spread.get("c_i", 1.0)), ("C_f", spread.get("c_f", 1.0))) if value > 1.05]
    if shown:
        parts.append(f"{', '.join(shown)} by the spread between runs")
    accuracy = widened.get("accuracy") or {}
    # (None: the fit's own interval was 0, the accuracy is all of it)
    shown = [f"x{'inf' if value is None else f'{value:.2g}'} ({name})"
             for name, value in (("C_i", accuracy.get("c_i", 1.0)),
                                 ("C_f", accuracy.get("c_f", 1.0)))
             if value is None or value > 1.05]
    if shown:
        parts.append(f"widened {', '.join(shown)} for the method's accuracy "
                     f"({method_accuracy.describe()})")
    return "; " + "; ".join(parts) if parts else ""


def _amplitude_kind(entry: dict[str, Any]) -> str:
    """What a mode's amplitudes are, from its ``amplitude_convention``: the modal coordinate
    q (the displacement at the measuring point over the mode shape there), or the
    displacement at the measuring point."""
    convention = str(entry.get("amplitude_convention", ""))
    chain = "the measuring chain's gain" in convention   # (its filters taken out)
    if not convention.startswith("modal"):
        return "displacement amplitude at the measuring point" + (
            " over the measuring chain's gain" if chain else "")
    scale = entry.get("modal_scale")
    found = re.match(r"modal: (q_\d+) ", convention)
    name = found.group(1) if found else "q"
    return (f"modal amplitude {name}" + (f" (the displacement at the measuring point / "
                                         f"{abs(scale):.4g}" + (", the mode shape there times "
                                         "the measuring chain's gain" if chain else "") + ")"
                                         if scale else ""))


def format_aggregate(agg: dict[str, Any], indent: str = "") -> str:
    """The aggregation in a few readable lines."""
    lines = []
    total, good = len(agg["runs"]), agg["runs_with_modes"]
    rng = agg.get("amplitude_range_m")
    distinct = agg.get("distinct_records", good)
    kinds = {_amplitude_kind(entry).partition(" (")[0].partition(" q_")[0]
             for entry in agg["modes"]}
    kind = kinds.pop() if len(kinds) == 1 else "amplitude (each mode's, below)"
    lines.append(f"{indent}aggregate of {total} run{'s' * (total != 1)}: {good} with modes"
                 + (f" ({distinct} distinct record{'s' * (distinct != 1)})"
                    if distinct != good else "")
                 + (f"; {kind} {1e3 * rng[0]:.3g} to {1e3 * rng[1]:.3g} mm" if rng else ""))
    for run in agg["runs"]:
        for error in run["errors"]:
            lines.append(f"{indent}  {run['label']}: {error}")
    lines.extend(f"{indent}  note: {note}" for note in agg.get("notes", []))
    for entry in agg["modes"]:
        spread = entry["between_runs"]
        lines.append(f"{indent}mode at {entry['frequency_hz']:.4g} Hz, channel "
                     f"{entry['channel']}: {entry['runs']} run{'s' * (entry['runs'] != 1)}"
                     + (f", {entry['decays']} decays, {entry['extrema']} extrema"
                        if "decays" in entry else "")
                     + f", {_amplitude_kind(entry)} "
                       f"{1e3 * entry['amplitude_range_m'][0]:.3g} to "
                       f"{1e3 * entry['amplitude_range_m'][1]:.3g} mm")
        if "c_i" in entry:
            lines.append(f"{indent}  {coefficient_words(entry)}, preferred law: "
                         f"{entry['preferred_law']}{_power(entry)}{_widening(entry)}")
            if entry.get("pooled_by") == "weighted mean":
                lines.append(f"{indent}  (the runs' own C_i and C_f averaged with their "
                             "inverse covariances: their modes were fitted together with a "
                             "close mode to the records' samples, and their extrema are "
                             "smeared)")
        else:
            lines.append(f"{indent}  C_i and C_f not fitted: {entry['fit_error']}")
        lines.extend(f"{indent}  warning: {w}" for w in entry.get("warnings", []))
        if entry["runs"] > 1:
            parts = []
            for key, label, unit in (("c_i", "C_i", " kg/(m s)"), ("c_f", "C_f", " kg/m^2"),
                                     ("frequency_hz", "f0", " Hz")):
                s = spread[key]
                if s["sd"] is not None:
                    parts.append(f"{label} sd {s['sd']:.3g}{unit} ({s['sd_pct']:.2g} %) "
                                 f"vs within-run 95 % +-{s['median_half_width']:.3g}{unit}")
            lines.append(f"{indent}  between runs (the standard deviation of the runs' own "
                         "values vs the median half-width of their own 95 % intervals): "
                         + "; ".join(parts))
        for run in entry["per_run"]:
            lines.append(f"{indent}    {run['label']}: {run['frequency_hz']:.4f} Hz, "
                         f"{coefficient_words(run)}, amplitude "
                         f"{1e3 * run['amplitude_range_m'][0]:.3g} to "
                         f"{1e3 * run['amplitude_range_m'][1]:.3g} mm")
    return "\n".join(lines)
