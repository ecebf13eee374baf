"""The validation matrix's verdicts (validation/__main__.py): coverage judged only where the
trials can show it, refusals expected of records with no usable free decay."""

from __future__ import annotations

import pytest

from validation.__main__ import coverage_met, render, verdict
from validation.cases import WET_C_F, WET_C_I, Case, Mode
from validation.run import Estimate, Row

CASE = Case("row", (Mode(17.0, c_f=WET_C_F),), noise=0.01)


def estimate(c_i=WET_C_I, c_f=WET_C_F, warned=False, refused=""):
    """One trial's numbers with intervals of +-1 % around them."""
    return Estimate(c_i=c_i, c_i_ci=(0.99 * c_i, 1.01 * c_i), c_f=c_f,
                    c_f_ci=(0.99 * c_f, 1.01 * c_f), law="quadratic", warned=warned,
                    refused=refused)


def row(estimates, case=CASE):
    return Row(case, estimates, [Estimate(refused="peer") for _ in estimates])


def test_six_trials_that_meet_the_bias_are_too_few_to_judge_the_coverage():
    """Six trials can only show coverages of 0.83 or 1.00: not a miss, too few trials."""
    assert verdict(row([estimate() for _ in range(6)]), 0) == "too few trials"


@pytest.mark.parametrize("covered, trials, met", [
    (40, 40, True),        # 40 of 40 is likely at a true 98 %
    (36, 40, True),
    (34, 40, True),        # likely enough at 90 %
    (30, 40, False),       # unlikely for any coverage of 90 to 98 %
    (20, 20, True),
    (15, 20, False),
])
def test_coverage_is_judged_by_whether_its_count_fits_90_to_98_percent(covered, trials, met):
    assert coverage_met(covered / trials, trials) is met


def test_forty_trials_covered_are_met_and_a_biased_row_is_missed():
    assert verdict(row([estimate() for _ in range(40)]), 0) == "met"
    biased = row([estimate(c_i=1.1 * WET_C_I, warned=True) for _ in range(40)])
    assert verdict(biased, 0) == "missed, warned"
    assert verdict(biased, 3) == "MISSED SILENTLY"


def test_a_record_without_a_free_decay_is_judged_by_its_refusals():
    case = Case("random", (Mode(17.0, c_f=WET_C_F),), expect="refusal")
    assert verdict(row([estimate(refused="identify: no") for _ in range(4)], case), 0) \
        == "refused, as it should"
    mixed = [estimate(refused="identify: no"), estimate(warned=True)]
    assert verdict(row(mixed, case), 0) == "numbers given, warned"
    table = render([row([estimate(refused="identify: 3 cycles at 17.2 Hz")] * 2, case)])
    assert "refused, as it should" in table
    assert "random (2 of 2): identify: # cycles at # Hz" in table
