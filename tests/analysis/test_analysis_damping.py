"""Damping curves and the equivalent damping fit (C_i, C_f) against exact free decays."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from _analysis_sims import (
    decaying_tone,
    envelope_law,
    noisy,
    quadratic_damping_decay,
    quadratic_record,
    time_axis,
)

from fsi_lab.dsp.damping import (
    MIN_FIT_PEAKS,
    damping,
    damping_decrement,
    damping_envelope_fit,
    damping_eq5,
    damping_eq7,
    damping_from_peaks,
)
from fsi_lab.dsp.equivalent_damping import equivalent_damping, equivalent_damping_from_envelope
from fsi_lab.dsp.hvd import hvd
from fsi_lab.dsp.instantaneous import instantaneous
from fsi_lab.dsp.integrate import integrate
from fsi_lab.errors import AnalysisError


@pytest.mark.parametrize("method", ["decrement", "envelope-fit", "eq5", "eq7"])
def test_viscous_decay_has_constant_damping(method):
    fs = 2000.0
    t = time_axis(10.0, fs)
    x, _, _ = decaying_tone(t, 1.0, 10.0, 0.012, 0.4)
    curve = damping(x, fs, method=method)
    np.testing.assert_allclose(curve.zeta, 0.012, rtol=0.01)


def quadratic_peaks(q, velocity=False):
    """Extrema of the displacement of the quadratic-damping decay (exact record)."""
    inst = instantaneous(q["x"], q["fs"])
    return inst


def test_decrement_follows_the_linear_plus_quadratic_law():
    q = quadratic_record()
    inst = quadratic_peaks(q)
    curve = damping_decrement(inst.peak_times, inst.peak_amplitudes, inst.peak_frequency)
    w = 2 * math.pi * curve.frequency
    a = q["c1"] / (2 * q["m"])
    b = 4 * q["c2"] * w / (3 * math.pi * q["m"])
    np.testing.assert_allclose(curve.decay_rate, a + b * curve.amplitude, rtol=0.01)


def test_envelope_fit_recovers_a_and_b_and_eq7_is_biased():
    q = quadratic_record()
    inst = quadratic_peaks(q)
    w = 2 * math.pi * float(np.mean(inst.peak_frequency))
    a_true = q["c1"] / (2 * q["m"])
    b_true = 4 * q["c2"] * w / (3 * math.pi * q["m"])
    fit = damping_envelope_fit(inst.peak_times, inst.peak_amplitudes, inst.peak_frequency)
    assert fit.params["a"] == pytest.approx(a_true, rel=5e-3)
    assert fit.params["b"] == pytest.approx(b_true, rel=5e-3)
    # The closed form itself (SCIENCE.md): peaks follow it closely.
    env = envelope_law(inst.peak_times - inst.peak_times[0], a_true, b_true,
                       fit.params["A0"])
    assert np.max(np.abs(inst.peak_amplitudes / env - 1)) < 5e-3
    # Eq. 7 (cubic in t) on this 40-fold decay: its damping curve misses the truth by far
    # more than the unbiased estimators.
    cubic = damping_eq7(inst.peak_times, inst.peak_amplitudes, inst.peak_frequency)
    truth = a_true + b_true * cubic.amplitude
    assert np.max(np.abs(cubic.decay_rate / truth - 1)) > 0.05
    c_i, c_f, _, _ = equivalent_damping_from_envelope(
        fit.params["a"], fit.params["b"], fit.params["a_se"], fit.params["b_se"],
        int(fit.params["dof"]), fit.frequency, q["m"])
    assert c_i == pytest.approx(q["c1"], rel=0.01)
    assert c_f == pytest.approx(q["c2"], rel=0.01)


def chain_from_velocity(q, v, use_hvd):
    """velocity -> (HVD) -> displacement -> extrema -> decrement -> C_i, C_f."""
    fs = q["fs"]
    sig = hvd(v, fs, 1).components[0] if use_hvd else v
    inst = instantaneous(integrate(sig, fs), fs)
    period = 1.0 / float(np.median(inst.frequency))
    edge = 2 * period if use_hvd else period
    keep = (inst.peak_times > edge) & (inst.peak_times < q["t"][-1] - edge)
    curve = damping_decrement(inst.peak_times[keep], inst.peak_amplitudes[keep],
                              inst.peak_frequency[keep])
    return equivalent_damping(curve.amplitude, curve.zeta, curve.frequency, q["m"])


@pytest.mark.parametrize("use_hvd", [False, True])
def test_c_i_and_c_f_from_clean_velocity(use_hvd):
    q = quadratic_record()
    res = chain_from_velocity(q, q["v"], use_hvd)
    assert res.c_i == pytest.approx(q["c1"], rel=0.02)
    assert res.c_f == pytest.approx(q["c2"], rel=0.02)
    assert res.r2 > 0.95


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("use_hvd", [False, True])
def test_c_i_and_c_f_from_noisy_velocity(use_hvd, seed):
    """1 % RMS noise (relative to the peak velocity) on the measured velocity."""
    q = quadratic_record()
    res = chain_from_velocity(q, noisy(q["v"], 0.01, seed=seed), use_hvd)
    assert res.c_i == pytest.approx(q["c1"], rel=0.10)
    assert res.c_f == pytest.approx(q["c2"], rel=0.10)
    assert res.c_i_ci95[0] <= q["c1"] <= res.c_i_ci95[1]
    assert res.c_f_ci95[0] <= q["c2"] <= res.c_f_ci95[1]


def test_modal_scale_scales_c_f_only():
    q = quadratic_record()
    inst = quadratic_peaks(q)
    curve = damping_decrement(inst.peak_times, inst.peak_amplitudes, inst.peak_frequency)
    one = equivalent_damping(curve.amplitude, curve.zeta, curve.frequency, q["m"])
    two = equivalent_damping(curve.amplitude, curve.zeta, curve.frequency, q["m"],
                             modal_scale=2.0)
    assert two.c_i == pytest.approx(one.c_i, rel=1e-12)
    assert two.c_f == pytest.approx(2.0 * one.c_f, rel=1e-12)
    np.testing.assert_allclose(two.amplitude, curve.amplitude / 2.0)


def test_eq5_window_regression_on_quadratic_damping():
    q = quadratic_record()
    inst = quadratic_peaks(q)
    curve = damping_eq5(inst.peak_times, inst.peak_amplitudes, inst.peak_frequency, window=6)
    w = 2 * math.pi * curve.frequency
    truth = (q["c1"] / 2 + 4 * q["c2"] * w * curve.amplitude / (3 * math.pi)) / w
    np.testing.assert_allclose(curve.zeta, truth, rtol=0.03)


@functools.lru_cache(maxsize=None)
def decay_train_peaks(x0s: tuple, counts: tuple) -> tuple:
    """Extrema of free decays of the system of ``quadratic_record`` from rest at each of ``x0s``
    (m), one after the other, the first ``counts[k]`` of decay k kept (a decay cut short by
    the next excitation): times (s), amplitudes (m), frequencies (Hz), the decay of each."""
    q = quadratic_record()
    t = time_axis(3.0, q["fs"])
    parts = []
    for k, (x0, n) in enumerate(zip(x0s, counts)):
        x, _ = quadratic_damping_decay(t, q["m"], q["c1"], q["c2"], q["m"] * q["w0"] ** 2, x0)
        inst = instantaneous(x, q["fs"])
        parts.append((inst.peak_times[:n] + 4.0 * k, inst.peak_amplitudes[:n],
                      inst.peak_frequency[:n], np.full(n, k)))
    return tuple(np.concatenate(column) for column in zip(*parts))


def test_envelope_fit_leaves_out_decays_of_too_few_peaks():
    """Three full decays and four cut after one or two extrema: the short ones bring a start
    amplitude each and (next to) nothing on the decay rate, so they are left out of the fit -
    ``dof`` counts the full decays' peaks only - yet the law is evaluated at their peaks too.
    a and b within 0.5 % of the simulated system's."""
    counts = (28, 2, 1, 28, 2, 2, 28)
    t, amp, freq, decay = decay_train_peaks((0.01, 0.008, 0.007, 0.006, 0.005, 0.004, 0.003),
                                            counts)
    curve = damping_from_peaks(t, amp, freq, method="envelope-fit", decay=decay)
    q = quadratic_record()
    w = 2 * math.pi * float(np.mean(freq))
    assert curve.params["a"] == pytest.approx(q["c1"] / (2 * q["m"]), rel=5e-3)
    assert curve.params["b"] == pytest.approx(4 * q["c2"] * w / (3 * math.pi * q["m"]),
                                              rel=5e-3)
    full = [n for n in counts if n >= MIN_FIT_PEAKS]
    assert curve.params["dof"] == sum(full) - 2 - len(full)
    assert np.array_equal(curve.decay, decay)
    np.testing.assert_allclose(curve.amplitude, amp, rtol=2e-3)


@pytest.mark.parametrize("counts", [(2, 2, 2, 2, 2, 2), (3, 2, 2, 1, 2)])
def test_envelope_fit_with_nothing_left_to_fit_is_refused(counts):
    """Decays of one or two extrema only (or one of three: as many peaks as its three
    parameters): a clear error, not the fit's start values."""
    x0s = tuple(0.01 * 0.8 ** k for k in range(len(counts)))
    t, amp, freq, decay = decay_train_peaks(x0s, counts)
    with pytest.raises(AnalysisError, match=r"damping \(envelope-fit\): .*free decays have 3 "
                                            r"peaks or more.*more peaks than parameters"):
        damping_from_peaks(t, amp, freq, method="envelope-fit", decay=decay)


@pytest.mark.parametrize("func, n, match", [
    (damping_decrement, 3, "needs at least 4 peaks"),
    (damping_envelope_fit, 3, "needs at least 4 peaks"),
    (damping_eq7, 4, "needs at least 5 peaks"),
    (lambda t, a, f: damping_eq5(t, a, f, window=6), 5, "needs at least 6 peaks"),
])
def test_too_few_peaks_are_refused(func, n, match):
    t = np.arange(n) * 0.05
    with pytest.raises(AnalysisError, match=match):
        func(t, np.exp(-t), np.full(n, 10.0))


def test_too_short_decay_is_refused():
    fs = 1000.0
    t = time_axis(0.25, fs)
    x, _, _ = decaying_tone(t, 1.0, 6.0, 0.01, 0.0)          # 1.5 cycles: 3 extrema
    with pytest.raises(AnalysisError, match="peak"):
        damping(x, fs, method="eq7")


@pytest.mark.parametrize("kwargs, match", [
    (dict(amplitude=[1e-3, 2e-3], zeta=[0.01, 0.01], frequency=[5.0, 5.0]), "at least 3"),
    (dict(mass_per_length=0.0), "mass_per_length"),
    (dict(mass_per_length=-1.0), "mass_per_length"),
    (dict(amplitude=[1e-3, 1e-3, 1e-3]), "do not vary"),
    (dict(zeta=[0.01, float("nan"), 0.01]), "NaN"),
    (dict(amplitude=[1e-3, -2e-3, 3e-3]), "> 0"),
    (dict(modal_scale=0.0), "modal_scale"),
])
def test_equivalent_damping_bad_input(kwargs, match):
    args = dict(amplitude=[1e-3, 2e-3, 3e-3], zeta=[0.01, 0.012, 0.014],
                frequency=[5.0, 5.0, 5.0], mass_per_length=1.0)
    args.update(kwargs)
    mass = args.pop("mass_per_length")
    with pytest.raises(AnalysisError, match=match):
        equivalent_damping(args.pop("amplitude"), args.pop("zeta"), args.pop("frequency"),
                           mass, **args)


def test_damping_bad_method():
    t = time_axis(2.0, 1000.0)
    x, _, _ = decaying_tone(t, 1.0, 10.0, 0.01, 0.0)
    with pytest.raises(AnalysisError, match="method"):
        damping(x, 1000.0, method="half-power")
