"""The power of the quadratic law's fluid term (fsi_lab.dsp.laws.fluid_power), against decays
simulated with a known power of the velocity."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.stats as sstats
from scipy.integrate import solve_ivp

from fsi_lab.dsp.laws import extremum_sequence, fit_law, fluid_power
from fsi_lab.errors import AnalysisError

W0 = 2 * math.pi * 20.0


def power_law_extrema(power: float, viscous: float = 0.5, fluid: float = 2.0,
                      x0: float = 0.01) -> np.ndarray:
    """Displacement extrema of x'' + viscous x' + fluid |x'|^(power - 1) x' + W0^2 x = 0 from
    rest at x0 (fluid scaled so that the term is the same size at a velocity amplitude of
    W0 x 0.01 m for every power), by an adaptive integration to 1e-10."""
    scale = fluid * (W0 * 0.01) ** (2.0 - power)

    def motion(_, y):
        return [y[1], -viscous * y[1] - scale * abs(y[1]) ** (power - 1.0) * y[1]
                - W0 * W0 * y[0]]

    path = solve_ivp(motion, (0.0, 2.0), [x0, 0.0], events=lambda _, y: y[1], rtol=1e-10,
                     atol=1e-13)
    return np.abs(path.y_events[0][1:, 0])


@pytest.mark.parametrize("power", [1.5, 2.0, 2.5])
def test_the_power_of_a_noise_free_decay_is_found(power):
    """One Gauss-Newton step from the quadratic fit lands within 0.03 of the power the decay
    was simulated with; at power 2 the quadratic law is the truth and nothing changes."""
    extrema = power_law_extrema(power)
    test = fluid_power(fit_law("quadratic", [extrema], W0, quantity="displacement"))
    assert test.power == pytest.approx(power, abs=0.03)
    if power == 2.0:
        assert test.change < 1e-3
    else:
        assert abs(test.z) > 10 and test.change > 0.03


def test_on_a_quadratic_law_the_test_rejects_at_its_level():
    """300 decays of the quadratic law with independent extremum errors (1 % of the first):
    the power's z-score is standard normal, and its 95 % interval leaves out 2 in about 5 % of
    them (2 to 9 %, the binomial spread of 300 trials)."""
    rng = np.random.default_rng(7)
    clean, _ = extremum_sequence("quadratic", [0.5, 3.0], W0, 0.05, 120)
    z, missed = [], 0
    for _ in range(300):
        noisy = clean + rng.normal(0.0, 0.01 * clean[0], clean.size)
        above = noisy > 0.05 * clean[0]
        count = int(np.argmin(above)) if not above.all() else clean.size
        test = fluid_power(fit_law("quadratic", [noisy[:count]], W0))
        z.append(test.z)
        low, high = test.interval(0.95)
        missed += not low <= 2.0 <= high
    assert abs(np.mean(z)) < 0.2 and 0.85 < np.std(z) < 1.15
    assert 6 <= missed <= 27
    assert sstats.kstest(z, "norm").pvalue > 0.01


def test_several_decays_and_their_whitening_are_taken():
    """Three decays of the |v|^1.5 law from different starts, fitted together: the power is
    that of the law, and each decay's own start is a parameter of the test (its dof)."""
    decays = [power_law_extrema(1.5, x0=x0) for x0 in (0.01, 0.007, 0.004)]
    test = fluid_power(fit_law("quadratic", decays, W0, quantity="displacement"))
    assert test.power == pytest.approx(1.5, abs=0.03)
    assert test.dof == sum(d.size for d in decays) - 3 - 3


def test_laws_without_a_fluid_term_are_refused():
    extrema = power_law_extrema(2.0)
    with pytest.raises(AnalysisError, match="quadratic one"):
        fluid_power(fit_law("viscous", [extrema], W0, quantity="displacement"))
    viscous_only, _ = extremum_sequence("viscous", [1.0], W0, 0.01, 60, quantity="displacement")
    quadratic = fit_law("quadratic", [viscous_only * (1 + 1e-4 * np.cos(np.arange(60)))], W0,
                        quantity="displacement")
    if quadratic.params[1] <= 0.0:
        with pytest.raises(AnalysisError, match="no fluid term"):
            fluid_power(quadratic)
    else:
        assert abs(fluid_power(quadratic).z) < 1e3
