"""The wet bench's modal truth (validation/wet_start.py): what mode 2's free decay is, against
which the identification's extrema are measured.

Ground truth: the bench's beam model has C_i = 0.65 kg/(m s) and C_f = 33.0 kg/m^2 in each
per-mode equation; its tip velocity holds mode 2 as ``W_2(x_m) q_2'`` with ``|W_2(L)| = 2``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsi_lab.dsp.laws import fit_law
from validation.bench import bench_cases
from validation.cases import WET_C_F, WET_C_I
from validation.wet_start import at, extrema, free_decay, modal_record


@pytest.fixture(scope="module")
def step():
    """The matrix's 'wet bench, step 0.5 V' row, simulated with its modal coordinates."""
    case = next(c for c in bench_cases() if c.name == "wet bench, step 0.5 V")
    return case, modal_record(case)


def test_the_free_decay_in_the_measured_coordinate_gives_back_the_bench_coefficients(step):
    """Mode 2 released at 0.45 s (the step came at 0.1 s) and converted to the tip's velocity:
    the quadratic law fitted to its extrema, converted back with the mode shape and the mass per
    length, is the bench's C_i and C_f within 0.5 % - the conversion the chain's
    equivalent-damping uses is not where the wet bench's C_f error comes from."""
    case, rec = step
    fs = case.fs
    start, stop = int(0.45 * fs), int(3.0 * fs)
    t, v = extrema(free_decay(rec, start, stop, fs), fs, start / fs)
    assert abs(rec["shape"]) == pytest.approx(2.0, rel=1e-6)
    fit = fit_law("quadratic", [np.abs(v[1:])], 2.0 * math.pi * 17.06)
    m = rec["model"].total_mass_per_length
    assert 2.0 * m * fit.value("a") == pytest.approx(WET_C_I, rel=5e-3)
    assert m * abs(rec["shape"]) * fit.value("beta") == pytest.approx(WET_C_F, rel=5e-3)


def test_the_base_still_forces_mode_2_where_its_free_decay_is_taken_to_start(step):
    """At the start the identification takes for this record's first decay (0.44-0.47 s, the
    base calmed to 1 % of its peak in mode 2's band), the modal velocity still differs from the
    free decay from the same state by 2 to 6 % on its first extrema (the shaker's suspension
    rings on at 30 Hz): an error of the data's start, not of the filters, which the law
    fit sees as C_f (35.5 instead of 33.0 fitted to the modal velocity itself)."""
    case, rec = step
    fs = case.fs
    start, stop = int(0.445 * fs), int(0.8 * fs)
    ft, fv = extrema(free_decay(rec, start, stop, fs), fs, start / fs)
    ft, fv = ft[1:9], np.abs(fv[1:9])
    t, v = extrema(rec["shape"] * rec["v"], fs)
    forced = at(t, v, ft)
    worst = float(np.max(np.abs(forced / fv - 1.0)))
    assert 0.02 < worst < 0.08
