"""The damping-law fits' analytic Jacobians against finite differences of their models.

:func:`fsi_lab.dsp.laws.extremum_derivatives` differentiates the Runge-Kutta model of the extrema
exactly; :func:`fsi_lab.dsp.damping.envelope_law_derivatives` the closed-form envelope of
linear + quadratic damping. Ground truth: central differences of the models themselves, whose
error (truncation and rounding) is about 1e-9 of the largest derivative at the steps used, so a
tolerance of 1e-6 of a column's largest entry tells an exact derivative from a wrong one (a
missing term moves a column by 1e-2 or more).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsi_lab.dsp.damping import envelope_law, envelope_law_derivatives
from fsi_lab.dsp.laws import LAWS, Whitener, extremum_derivatives, extremum_sequence, fit_law

W = 2.0 * math.pi * 17.0
#: Natural size of each parameter (the finite-difference steps are 1e-6 of it).
SIZE = {"a": 1.0, "beta": 1.0, "gamma": 0.1}
COUNT = 60


def finite_differences(law, params, start, quantity, alpha, one_sided=()):
    """Central differences of the extrema in each law parameter and |start| (forward ones,
    into the allowed side, for the parameters in ``one_sided``)."""
    names = LAWS[law]
    base = np.array([*params, abs(start)], dtype=np.float64)
    sizes = np.array([SIZE[n] for n in names] + [abs(start)])
    columns = []
    for i in range(base.size):
        h = 1e-6 * max(abs(base[i]), sizes[i])
        steps = (h, 0.0) if i < len(names) and names[i] in one_sided else (h, -h)
        values = []
        for step in steps:
            q = base.copy()
            q[i] += step
            amp, _ = extremum_sequence(law, q[:-1], W, math.copysign(q[-1], start), COUNT,
                                       alpha=alpha, quantity=quantity)
            values.append(amp)
        n = min(v.size for v in values)
        columns.append((values[0][:n] - values[1][:n]) / (steps[0] - steps[1]))
    n = min(c.size for c in columns)
    return np.stack([c[:n] for c in columns], axis=1)


@pytest.mark.parametrize("quantity", ["velocity", "displacement"])
@pytest.mark.parametrize("law, params, start, alpha", [
    ("viscous", [0.5], 0.1, 0.0),
    ("viscous", [0.0], 0.1, 0.0),                       # undamped
    ("viscous", [5.0], 0.1, 300.0),                     # heavy damping, Duffing
    ("quadratic", [0.4, 1.0], 0.1, 0.0),
    ("quadratic", [0.4, 0.0], 0.1, 0.0),                # no quadratic term
    ("quadratic", [0.4, 30.0], 1.0, 0.0),               # large amplitude: zeta 0.25 at first
    ("quadratic", [-0.1, 2.0], -0.1, 0.0),              # negative a, negative start
    ("quadratic", [0.6, 3.0], 0.1, -2000.0),            # softening Duffing
    ("coulomb", [0.3, 0.4], 0.1, 0.0),                  # stops after about 13 extrema
    ("coulomb", [0.0, 0.4], 0.1, 0.0),                  # friction alone (linear envelope)
    ("coulomb", [1.0, 0.3], 0.5, 0.0),
    ("quadratic_coulomb", [0.3, 1.0, 0.2], 0.1, 0.0),   # the three terms together
    ("quadratic_coulomb", [0.0, 20.0, 0.4], 0.5, 0.0),  # no viscous term, stops
])
def test_the_extrema_derivatives_equal_finite_differences(law, params, start, alpha, quantity):
    if quantity == "displacement":
        start /= W
    amp, times, deriv = extremum_derivatives(law, params, W, start, COUNT, alpha=alpha,
                                             quantity=quantity)
    ref_amp, ref_times = extremum_sequence(law, params, W, start, COUNT, alpha=alpha,
                                           quantity=quantity)
    # The same extrema as the model without derivatives, to the bit.
    np.testing.assert_array_equal(amp, ref_amp)
    np.testing.assert_array_equal(times, ref_times)
    assert deriv.shape == (amp.size, len(params) + 1)
    fd = finite_differences(law, params, start, quantity, alpha)
    n = min(fd.shape[0], amp.size)
    assert n >= 10
    scale = np.abs(fd[:n]).max(axis=0)
    np.testing.assert_allclose(deriv[:n], fd[:n], rtol=0, atol=1e-6 * scale.max())
    for j in range(fd.shape[1]):
        assert np.abs(deriv[:n, j] - fd[:n, j]).max() <= 1e-6 * scale[j], (j, scale[j])


@pytest.mark.parametrize("quantity", ["velocity", "displacement"])
def test_the_friction_derivative_at_zero_friction_is_the_limit_from_above(quantity):
    """At gamma = 0 (the bound a Coulomb fit rests on when a record shows no friction) the
    derivative in gamma is that of the friction model as gamma -> 0+, which restarts its
    steps where the velocity reverses: a forward difference of 1e-4 in gamma agrees within
    1e-4 of the column's largest entry (the restart's own discretisation, 3e-5)."""
    start = 0.1 if quantity == "velocity" else 0.1 / W
    amp, _, deriv = extremum_derivatives("coulomb", [0.3, 0.0], W, start, COUNT,
                                         quantity=quantity)
    up, _ = extremum_sequence("coulomb", [0.3, 1e-4], W, start, COUNT, quantity=quantity)
    fd = (up - amp) / 1e-4
    assert np.abs(deriv[:, 1] - fd).max() <= 1e-4 * np.abs(fd).max()


def test_the_fit_reaches_the_least_squares_optimum_with_a_jacobian_that_matches():
    """A quadratic fit to noisy, correlated extrema of two decays: the Jacobian the fit used
    (reflected in its covariance) equals a central-difference one of the whitened residuals
    at the optimum to 1e-6, and the whitened residuals are orthogonal to it there."""
    a, beta = 0.6, 4.0
    decays, whiteners = [], []
    rng = np.random.default_rng(7)
    for start in (0.2, 0.12):
        amp, times = extremum_sequence("quadratic", [a, beta], W, start, 70)
        decays.append(amp + 2e-4 * rng.standard_normal(amp.size))
        whiteners.append(Whitener(times, (-1.0) ** np.arange(amp.size),
                                  lambda lag: np.exp(-(lag * 40.0) ** 2), None))
    fit = fit_law("quadratic", decays, W, whiteners=whiteners)

    def whitened(q):
        out = []
        for d, w, s in zip(decays, whiteners, np.exp(q[2:])):
            model, _ = extremum_sequence("quadratic", q[:2], W, s, d.size)
            out.append(w.apply(d - model))
        return np.concatenate(out)

    q = np.concatenate((fit.params, np.log(fit.starts)))
    jac = np.empty((sum(d.size for d in decays), q.size))
    for i in range(q.size):
        h = 1e-6 * max(abs(q[i]), 1.0)
        up, down = q.copy(), q.copy()
        up[i] += h
        down[i] -= h
        jac[:, i] = (whitened(up) - whitened(down)) / (2 * h)
    r = whitened(q)
    s2 = float(r @ r) / fit.dof
    cov = np.linalg.inv(jac.T @ jac)[:2, :2] * s2
    np.testing.assert_allclose(fit.cov, cov, rtol=1e-6)
    gradient = jac.T @ r
    assert np.all(np.abs(gradient) <= 1e-8 * np.linalg.norm(jac, axis=0) * np.linalg.norm(r))
    assert fit.params[0] == pytest.approx(a, rel=0.05)
    assert fit.params[1] == pytest.approx(beta, rel=0.1)


def test_whitening_a_matrix_whitens_each_column():
    """Whitener.apply on a matrix equals it on each column (banded forward substitution)."""
    times = np.cumsum(np.full(50, 0.5 / 17.0))
    w = Whitener(times, (-1.0) ** np.arange(50), lambda lag: np.exp(-(lag * 30.0) ** 2),
                 np.linspace(2.0, 1.0, 50))
    assert w.band > 0
    m = np.random.default_rng(3).standard_normal((50, 4))
    both = w.apply(m)
    for j in range(4):
        np.testing.assert_array_equal(both[:, j], w.apply(m[:, j]))
    # L (L^-1 m) = m, L from the band.
    dense = np.zeros((50, 50))
    for k in range(w.band + 1):
        dense[np.arange(k, 50), np.arange(50 - k)] = w.lower[k, :50 - k]
    np.testing.assert_allclose(dense @ both, m, rtol=0, atol=1e-12)


@pytest.mark.parametrize("a, b, a0", [
    (0.5, 2.0, 0.1), (0.5, 0.0, 0.1),          # no quadratic term
    (3.0, 50.0, 1.0),                          # large amplitude, fast decay
    (1e-3, 2.0, 0.1), (1e-7, 2.0, 0.1),        # small a: no cancellation in d/da
    (0.0, 2.0, 0.1), (0.0, 0.0, 0.1),          # a = 0: the law's a = 0 form, d/da its limit
])
def test_the_envelope_law_derivatives_equal_finite_differences(a, b, a0):
    t = np.linspace(0.0, 5.0, 200)
    deriv = envelope_law_derivatives(t, a, b, a0)
    assert deriv.shape == (t.size, 3)
    args = np.array([a, b, a0])
    for i, size in enumerate((1.0, 1.0, a0)):
        h = 1e-5 * max(abs(args[i]), size)
        up, down = args.copy(), args.copy()
        up[i] += h
        if i == 0 and a < 1e-3:
            # Below a = 1e-12 the law changes form, and near it the law's own rounding (1 -
            # e^-at) spoils small steps: a forward difference of 3e-4 from a,
            # Richardson-extrapolated (the second derivative's term cancels).
            h = 3e-4
            up[0] = a + h
            up2 = args.copy()
            up2[0] += 2 * h
            fd = (4 * envelope_law(t, *up) - envelope_law(t, *up2)
                  - 3 * envelope_law(t, *args)) / (2 * h)
        else:
            down[i] -= h
            fd = (envelope_law(t, *up) - envelope_law(t, *down)) / (2 * h)
        assert np.abs(deriv[:, i] - fd).max() <= 1e-6 * np.abs(fd).max(), i


def _union(decays_count, count, seed=11):
    """Noisy, correlated extrema of ``decays_count`` quadratic decays of ``count`` extrema
    each (starts spread over a factor 2), with their whiteners."""
    rng = np.random.default_rng(seed)
    decays, whiteners = [], []
    for start in np.linspace(0.1, 0.2, decays_count):
        amp, times = extremum_sequence("quadratic", [0.6, 4.0], W, start, count)
        decays.append(amp + 2e-4 * rng.standard_normal(amp.size))
        whiteners.append(Whitener(times, (-1.0) ** np.arange(amp.size),
                                  lambda lag: np.exp(-(lag * 40.0) ** 2), None))
    return decays, whiteners


@pytest.mark.parametrize("law", ["quadratic", "viscous", "coulomb"])
def test_a_union_reduced_decay_by_decay_gives_the_dense_fit(law, monkeypatch):
    """Above laws.DENSE_JACOBIAN elements each decay's rows are reduced by its QR
    factorisation: the same fit as with the whole Jacobian (parameters, starts, covariance,
    residual sum and the influence on every extremum) to 1e-8, 12 decays forced both ways."""
    import fsi_lab.dsp.laws as laws

    decays, whiteners = _union(12, 50)
    dense = fit_law(law, decays, W, whiteners=whiteners)
    monkeypatch.setattr(laws, "DENSE_JACOBIAN", 0)
    reduced = fit_law(law, decays, W, whiteners=whiteners)
    np.testing.assert_allclose(reduced.params, dense.params, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(reduced.starts, dense.starts, rtol=1e-8)
    np.testing.assert_allclose(reduced.cov, dense.cov, rtol=1e-6)
    np.testing.assert_allclose(reduced.influence, dense.influence, rtol=1e-6,
                               atol=1e-8 * np.max(np.abs(dense.influence)))
    assert reduced.rss == pytest.approx(dense.rss, rel=1e-8)
    assert reduced.aicc == pytest.approx(dense.aicc, rel=1e-8)
    assert reduced.dof == dense.dof


def test_a_union_of_many_decays_is_fitted_without_its_whole_jacobian():
    """200 decays of 100 extrema: the whole Jacobian (20 000 x 202) alone is 32 MB, and it
    grows as the extrema times the decays (360 decays of 350 extrema took 2.7 GB); reduced to
    4 rows per decay (800 x 202), the fit's own allocations stay under 16 MB (tracemalloc,
    numpy's arrays; the model's compiled kernels warmed up first, so that no compilation is
    counted), and it finds the law (a within 1 %, beta within 2 % at this noise)."""
    import tracemalloc

    decays, whiteners = _union(200, 100)
    fit_law("quadratic", decays[:2], W, whiteners=whiteners[:2])
    tracemalloc.start()
    try:
        fit = fit_law("quadratic", decays, W, whiteners=whiteners)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 16e6
    assert fit.params[0] == pytest.approx(0.6, rel=0.01)
    assert fit.params[1] == pytest.approx(4.0, rel=0.02)
    assert fit.influence.shape == (2, 20000)
