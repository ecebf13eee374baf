"""``make validate``: the validation matrix, one row per case with known truth.

Columns: bias and RMS error of C_i and C_f (% of the truth) and the coverage of their 95 %
intervals over the trials; the natural frequency's RMS error (%); the share of trials whose
preferred damping law is the record's own, warned, and refused; the silent misses (a number off
by more than the target with an interval that excludes the truth and no warning: what must
never happen); and the peer method's bias and coverage in the same trials (on the wet bench's
rows the peer's C_f is that of the measured amplitude, without the modal conversion, and its
C_i and C_f see every mode of the record at once: read it as a reference only). A dry-friction
record is read as a user reads it: the C_i of the law fsi-lab prefers, and in the C_f column
the Coulomb law's friction force per length (:attr:`validation.cases.Case.second_truth`); a
viscous record's C_i is the quadratic law's, which nests the viscous one. The mode's warnings
are on the quadratic law's numbers: read by its preferred law's, a trial counts as unwarned.

Targets (the issue's): at 1 % noise C_i within 2 % and C_f within 5 % (bias), at 3 % within 5 %
and 10 %; coverage 90 to 98 %; natural frequencies within 0.2 %.

For a mode with a cubic stiffness (the Duffing rows), the backbone column holds the chain's
displacement backbone's largest bias from harmonic balance over amplitude bands, % (target
:data:`BACKBONE_TARGET`; :meth:`validation.run.Row.backbone_bias`).

Verdict: ``met``; ``missed, warned`` (off a target, every trial off by more than its target
warned or refused); ``MISSED SILENTLY``; ``backbone missed`` (the backbone off its target);
``too few trials`` when fewer than :data:`MIN_COVERAGE_TRIALS` trials gave numbers (the bias
met, the coverage not judged: six trials can only show 0.83 or 1.00); ``refused, as it
should`` for a record with no usable free decay refused in every trial. Coverage is judged by
its count: it misses when it is out of 90 to 98 % and the count is unlikely (below 5 %,
binomial) for every true coverage in that range (40 of 40 is likely at 98 %, 34 of 40 at 90 %).

Real recordings that PyPI packages ship follow, against their documented reference values
(:mod:`validation.real_data`; the filter ``real`` selects them alone).

Usage: ``python -m validation [TRIALS] [NAME FILTER...]`` (default 40 trials).
"""

from __future__ import annotations

import math
import re
import sys
import time
from collections import Counter

from validation import real_data
from validation.cases import matrix
from validation.run import Row, evaluate

#: Fewest trials with numbers for the coverage to be judged.
MIN_COVERAGE_TRIALS = 20
#: Coverage target, and the significance of a count outside it.
COVERAGE, COVERAGE_ALPHA = (0.90, 0.98), 0.05
#: The backbone's largest bias from harmonic balance, %.
BACKBONE_TARGET = 0.5


def coverage_met(coverage: float, trials: int) -> bool:
    """Whether ``coverage`` over ``trials`` is consistent with a true coverage of 90 to 98 %
    (see the module notes)."""
    from scipy.stats import binom

    if math.isnan(coverage):
        return False
    low, high = COVERAGE
    if low <= coverage <= high:
        return True
    k = int(round(coverage * trials))
    if coverage < low:
        return float(binom.cdf(k, trials, low)) >= COVERAGE_ALPHA
    return float(binom.sf(k - 1, trials, high)) >= COVERAGE_ALPHA


def verdict(row: Row, misses: int) -> str:
    """The verdict of one row (see the module notes)."""
    n = len(row.ours)
    refused = sum(1 for e in row.ours if e.refused)
    if row.case.expect == "refusal":
        if refused == n:
            return "refused, as it should"
        return "MISSED SILENTLY" if misses else "numbers given, warned"
    ci, cf = row.stats("ours", "c_i"), row.stats("ours", "c_f")
    t_i, t_f = targets(row.case.noise)
    second = row.case.second_truth != 0.0
    if n - refused == 0:
        return "refused"
    bias_met = abs(ci["bias"]) <= t_i and (not second or abs(cf["bias"]) <= t_f)
    missed = "missed, warned" if misses == 0 else "MISSED SILENTLY"
    if not bias_met:
        return missed
    if abs(row.backbone_bias()) > BACKBONE_TARGET:
        return "backbone missed"
    if n - refused < MIN_COVERAGE_TRIALS:
        return "too few trials"
    covered = coverage_met(ci["coverage"], n - refused) and (
        not second or coverage_met(cf["coverage"], n - refused))
    return "met" if covered else missed


def targets(noise: float) -> tuple[float, float]:
    """Bias targets (%) of C_i and C_f at a noise level."""
    return (2.0, 5.0) if noise <= 0.01 else (5.0, 10.0)


def silent_misses(row: Row) -> int:
    """Trials off by more than the target, with an interval that excludes the truth and no
    warning."""
    t_i, t_f = targets(row.case.noise)
    count = 0
    for e in row.ours:
        if e.refused or e.warned:
            continue
        truth = row.case.truth
        for value, (lo, hi), true, tol in ((e.c_i, e.c_i_ci, truth.c_i, t_i),
                                          (e.c_f, e.c_f_ci, row.case.second_truth, t_f)):
            if not true:
                continue                 # no second coefficient (the viscous law)
            if not (abs(value / true - 1) * 100 <= tol or lo <= true <= hi):
                count += 1
                break
    return count


def fmt(value: float, spec: str) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) \
        else format(value, spec)


def render(rows: list[Row]) -> str:
    head = ("| case | C_i bias / rms % | C_i cov | C_f bias / rms % | C_f cov | f0 err % | "
            "backbone vs HB % | law ok | warned | refused | silent misses | peer C_i bias / cov | "
            "peer C_f bias / cov | verdict |")
    lines = [head, "|" + "|".join("---" for _ in range(head.count("|") - 1)) + "|"]
    for row in rows:
        ci, cf = row.stats("ours", "c_i"), row.stats("ours", "c_f")
        pi, pf = row.stats("peer", "c_i"), row.stats("peer", "c_f")
        f = row.stats("ours", "frequency")
        n = len(row.ours)
        refused = sum(1 for e in row.ours if e.refused)
        law_ok = sum(1 for e in row.ours if e.law == row.case.law) / max(n - refused, 1)
        warned = sum(1 for e in row.ours if e.warned) / n
        misses = silent_misses(row)
        quadratic = row.case.law == "quadratic"
        second = row.case.second_truth != 0.0
        lines.append(
            f"| {row.case.name} | {fmt(ci['bias'], '+.2f')} / {fmt(ci['rms'], '.2f')} | "
            f"{fmt(ci['coverage'], '.2f')} | "
            f"{fmt(cf['bias'], '+.2f') if second else '-'} / "
            f"{fmt(cf['rms'], '.2f') if second else '-'} | "
            f"{fmt(cf['coverage'], '.2f') if second else '-'} | {fmt(f['rms'], '.3f')} | "
            f"{fmt(row.backbone_bias(), '+.2f')} | {law_ok:.2f} | {warned:.2f} | {refused} | "
            f"{misses} | "
            f"{fmt(pi['bias'], '+.1f')} / {fmt(pi['coverage'], '.2f')} | "
            f"{fmt(pf['bias'], '+.1f') if quadratic else '-'} / "
            f"{fmt(pf['coverage'], '.2f') if quadratic else '-'} | {verdict(row, misses)} |")
    refusals = []
    for row in rows:
        said = Counter(_gist(e.refused) for e in row.ours if e.refused)
        for message, count in said.most_common(2):
            refusals.append(f"- {row.case.name} ({count} of {len(row.ours)}): {message}")
    if refusals:
        lines += ["", "Refusals (the commonest message of each case, numbers elided):", *refusals]
    return "\n".join(lines)


def _gist(message: str) -> str:
    """A refusal's message with its numbers elided, so that trials that refused for the same
    reason count together."""
    return re.sub(r"-?\d+(\.\d+)?(e-?\d+)?", "#", message)


def main() -> int:
    args = sys.argv[1:]
    trials = int(args.pop(0)) if args and args[0].isdigit() else 40
    cases = [c for c in matrix() if not args or any(a in c.name for a in args)]
    real = [n for n in real_data.RECORDS if not args or any(a in f"real {n}" for a in args)]
    started = time.perf_counter()
    print(f"validation: {len(cases)} cases x {trials} trials ...", file=sys.stderr, flush=True)
    if cases:
        print(render(evaluate(cases, trials)))
    if real:
        print(f"\nReal recordings ({', '.join(real)}; validation/real_data.py):\n")
        print(real_data.render(real_data.evaluate(real)))
        count = min(trials, real_data.REPLICA_TRIALS)
        print(f"\nReplicas of the real recordings ({count} trials per channel; "
              "validation/real_data.py):\n")
        print(real_data.render_replicas(real_data.replica_rows(real, count)))
    print(f"\n{len(cases) * trials} trials in {time.perf_counter() - started:.0f} s",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
