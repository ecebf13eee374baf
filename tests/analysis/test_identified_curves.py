"""The damping curve the chain reports for a component of the ``bands`` decomposition: from its
identification's extrema, corrected for the band filter's smear of the first cycles, from the
first; against the damping ratio of the linear + quadratic law by harmonic balance on exact
releases of the validation matrix's wet mode."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_analysis_plugins import run

from fsi_lab.contract import ChannelData
from validation.cases import clean_record, sdof_grid, trial


def law_zeta(mode, mass: float, amplitude: np.ndarray, frequency: np.ndarray) -> np.ndarray:
    """Damping ratio of ``c_i v + c_f |v| v`` at displacement amplitude ``amplitude`` (m) and
    frequency ``frequency`` (Hz), by harmonic balance: (C_i + 8 C_f w A / (3 pi)) / (2 m w)."""
    w = 2.0 * math.pi * frequency
    return (mode.c_i + 8.0 * mode.c_f * w * amplitude / (3.0 * math.pi)) / (2.0 * mass * w)


@pytest.mark.parametrize("x0", ["0.5 mm", "2 mm"])
def test_the_damping_curve_of_a_release_follows_the_law_from_its_first_period(x0):
    """The wet mode (17 Hz, C_i 0.65, C_f 33) released from 0.5 or 2 mm, noise-free at 10 kHz:
    every damping ratio above a tenth of the release within 3 % of the law's (a decrement over
    a period of a decay whose damping changes within it). Read off the band signal, the first
    ratios alternated up to 15 % about it."""
    case = next(c for c in sdof_grid() if c.name.endswith(f"0.1 %, 10000 Hz, 6 s, x0 {x0}"))
    channel = ChannelData("tip", clean_record(case), case.fs, "velocity", "m/s")
    _, summary = run({"tip": channel}, ("hvd", "damping"), mass_per_length=case.mass)
    curve = summary["tip"]["components"][0]["damping"]
    amplitude, zeta = np.array(curve["amplitude"]), np.array(curve["zeta"])
    frequency = case.truth.frequency * np.ones(zeta.size)
    error = zeta / law_zeta(case.truth, case.mass, amplitude, frequency) - 1.0
    large = amplitude > 0.1 * case.truth.x0
    assert large.sum() >= 6
    assert np.max(np.abs(error[large])) < 0.03, error[large]


def test_the_papers_regression_is_held_to_the_law_fit_of_the_same_extrema():
    """The paper's regression of C_q against amplitude on the 2 mm release (0.1 % noise): its
    C_i reads about 4 % high with an interval of +-1 % (damping ratios over whole periods of a
    decay whose damping halves within one); it carries a warning that names the law fit's
    numbers, which the law method's own entry does not."""
    case = next(c for c in sdof_grid() if c.name.endswith("0.1 %, 10000 Hz, 6 s, x0 2 mm"))
    channel = ChannelData("tip", trial(case, 0), case.fs, "velocity", "m/s")
    entries = {}
    for method in ("regression", "law"):
        _, summary = run({"tip": channel}, ("hvd", "damping", "equivalent-damping"),
                         mass_per_length=case.mass,
                         params={"equivalent-damping": {"method": method}})
        entries[method] = summary["tip"]["components"][0]
    regression = entries["regression"]["equivalent_damping"]
    assert not regression["c_i_ci95"][0] <= case.truth.c_i <= regression["c_i_ci95"][1]
    (said,) = regression["warnings"]
    assert said.startswith("the regression method gives C_i = ")
    law = entries["law"]["equivalent_damping"]
    assert f"the law fit's: {law['c_i']:.4g}" in said
    assert "warnings" not in law and not entries["law"]["warnings"]
