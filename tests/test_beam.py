"""The beam-in-fluid model against closed forms and the paper's published figures."""

import json
import math

import numpy as np
import pytest

from fsi_lab.beam import BeamModel, Damping, clamped_free_betas
from fsi_lab.errors import ParameterError
from fsi_lab.specimen import Specimen

SPECIMEN = Specimen.from_mapping({})  # the paper's beam (SCIENCE.md)
L = SPECIMEN.length

#: Roots of cos(b) cosh(b) = -1 to 15 digits (SCIENCE.md).
PUBLISHED_BETAS = [1.875104068711961, 4.694091132974175, 7.854757438237613,
                   10.995540734875467, 14.137168391046471]
#: The paper's Table 1, calculated dry natural frequencies, Hz.
TABLE1_DRY_HZ = [11.5328, 72.2747, 202.3712, 396.5668]


def gauss(points=400):
    """Gauss-Legendre nodes (m) and weights (m) on [0, L]."""
    x, w = np.polynomial.legendre.leggauss(points)
    return 0.5 * L * (x + 1.0), 0.5 * L * w


def beam(**changes):
    values = dict(length=L, width=12.75e-3, thickness=0.08e-3, youngs_modulus=240e9,
                  density=7200.0, fluid="water")
    values.update(changes)
    return BeamModel(**values)


# --------------------------------------------------------------------------- roots
def test_betas_match_published_roots_to_1e12():
    betas = clamped_free_betas(5)
    assert np.max(np.abs(betas - PUBLISHED_BETAS)) < 1e-12


def test_betas_are_those_of_scipys_brentq():
    """The model finds its roots without scipy (checking a profile builds it), by the steps of
    scipy.optimize.brentq: the same roots (to one unit in the last place), so no model or
    simulation changes."""
    from scipy.optimize import brentq

    from fsi_lab.beam import _sech

    def f(b):
        return math.cos(b) + _sech(b)

    expected = [brentq(f, (n - 1) * math.pi, n * math.pi, xtol=1e-15,
                       rtol=4 * np.finfo(float).eps, maxiter=200) for n in range(1, 201)]
    np.testing.assert_array_max_ulp(clamped_free_betas(200), np.array(expected), maxulp=1)


def test_the_root_finder_refuses_a_bracket_without_a_sign_change():
    from fsi_lab.beam import _brent

    with pytest.raises(ValueError, match="same sign"):
        _brent(lambda x: x * x + 1.0, -1.0, 1.0, 1e-12, 1e-15, 100)


def test_betas_for_many_modes_solve_the_characteristic_equation():
    betas = clamped_free_betas(1000)
    n = np.arange(1, 1001)
    # cos(b) + 1/cosh(b) = 0 is cos(b) cosh(b) = -1 divided by cosh(b) (no overflow).
    sech = 2.0 * np.exp(-betas) / (1.0 + np.exp(-2.0 * betas))
    assert np.max(np.abs(np.cos(betas) + sech)) < 1e-12
    assert np.all(np.abs(betas - (2 * n - 1) * np.pi / 2) < np.where(n >= 6, 1e-6, 0.31))
    assert np.all(np.diff(betas) > 2.8)
    # where cosh does not overflow, the original form holds to rounding of cosh(b)
    low = betas[:10]
    assert np.all(np.abs(np.cos(low) * np.cosh(low) + 1.0) < 1e-14 * np.cosh(low) * low)


# --------------------------------------------------------------------------- published figures
def test_dry_natural_frequencies_reproduce_table1_within_0p05_percent():
    dry = BeamModel.from_specimen(SPECIMEN, modes=4, fluid="air")
    error = dry.natural_frequencies_hz / TABLE1_DRY_HZ - 1.0
    assert np.max(np.abs(error)) < 5e-4
    # The paper includes the added mass of air: without it the frequencies are 1.1 % higher,
    # so the agreement above discriminates between the two readings.
    vacuum = dry.natural_frequencies_hz * math.sqrt(
        dry.total_mass_per_length / dry.mass_per_length)
    assert np.min(vacuum / TABLE1_DRY_HZ - 1.0) > 0.01


def test_added_mass_ratio_in_water_is_17p33():
    wet = BeamModel.from_specimen(SPECIMEN)
    assert wet.fluid == "water"
    assert abs(wet.added_mass_ratio - 17.33) < 0.005
    assert wet.added_mass == pytest.approx(997.0 * math.pi * (12.75e-3 / 2) ** 2, rel=1e-14)
    assert wet.mass_per_length == pytest.approx(7200.0 * 12.75e-3 * 0.08e-3, rel=1e-14)


def test_theoretical_quadratic_damping_in_water_is_11p4():
    wet = BeamModel.from_specimen(SPECIMEN)
    assert abs(wet.c_f_theory - 11.4) < 0.05
    assert wet.c_f_theory == pytest.approx(0.5 * 997.0 * 1.8 * 12.75e-3, rel=1e-14)


def test_natural_frequencies_follow_eq23():
    wet = beam(modes=6)
    ei = 240e9 * 12.75e-3 * 0.08e-3 ** 3 / 12
    expected = np.sqrt(ei * wet.betas ** 4 / (wet.total_mass_per_length * L ** 4))
    np.testing.assert_allclose(wet.natural_frequencies_rad, expected, rtol=1e-14)


def test_summary_is_json_ready():
    summary = json.loads(json.dumps(BeamModel.from_specimen(SPECIMEN, modes=3).summary()))
    assert summary["fluid"] == "water"
    assert len(summary["natural_frequencies_hz"]) == 3
    assert summary["natural_frequencies_hz"][0] == pytest.approx(2.7228, abs=1e-4)
    assert set(summary) == {"fluid", "added_mass_ratio", "natural_frequencies_hz", "c_f_theory"}


# --------------------------------------------------------------------------- mode shapes
def test_mode_shapes_satisfy_clamped_free_conditions_up_to_mode_60():
    model = beam(modes=60)
    scale = (model.betas / L)
    w0 = model.mode_shapes(0.0)
    w1 = model.mode_shapes(0.0, derivative=1) / scale
    w2 = model.mode_shapes(L, derivative=2) / scale ** 2
    w3 = model.mode_shapes(L, derivative=3) / scale ** 3
    for values in (w0, w1, w2, w3):
        assert np.max(np.abs(values)) < 1e-11
    np.testing.assert_allclose(np.abs(model.mode_shapes(L)), 2.0, atol=1e-12)


def test_mode_shapes_equal_the_textbook_form_for_low_modes():
    model = beam(modes=6)
    x = np.linspace(0.0, L, 101)
    for n, b in enumerate(model.betas, start=1):
        sigma = (np.sinh(b) - np.sin(b)) / (np.cosh(b) + np.cos(b))
        z = b * x / L
        naive = np.cosh(z) - np.cos(z) - sigma * (np.sinh(z) - np.sin(z))
        # the naive form itself loses about eps * cosh(b) to cancellation
        np.testing.assert_allclose(model.mode_shape(x, n), naive, rtol=0, atol=2e-14 * np.cosh(b))


def test_printed_eq16_would_violate_the_free_end():
    """Eq. (16) as printed (denominator cosh - cos) leaves a bending moment at the tip."""
    b = clamped_free_betas(1)[0]
    sigma_printed = (np.sinh(b) - np.sin(b)) / (np.cosh(b) - np.cos(b))
    moment = np.cosh(b) + np.cos(b) - sigma_printed * (np.sinh(b) + np.sin(b))  # W''(L) L^2/b^2
    assert abs(moment) > 0.5
    assert beam(modes=1).sigmas[0] == pytest.approx(0.7340955137, abs=1e-9)


def test_mode_integrals_norm_and_orthogonality_by_quadrature():
    model = beam(modes=30)
    x, w = gauss(600)
    shapes = model.mode_shapes(x)
    gram = (shapes * w[:, None]).T @ shapes
    np.testing.assert_allclose(gram, model.norm * np.eye(30), atol=1e-10 * L)
    assert model.norm == L  # Eq. (22): b = L for every mode
    np.testing.assert_allclose(w @ shapes, model.mode_integrals, rtol=1e-11, atol=1e-13)
    assert model.mode_integrals[0] / L == pytest.approx(0.7830, abs=1e-4)
    # Eq. (19): int W'''' W = beta^4 / L^3
    fourth = model.mode_shapes(x, derivative=4)
    np.testing.assert_allclose((fourth * shapes * w[:, None]).sum(0), model.betas ** 4 / L ** 3,
                               rtol=1e-9)


def test_modal_static_deflection_converges_to_the_exact_cantilever():
    a = 3.0  # m/s^2, constant base acceleration
    exact = beam().static_tip_deflection(a)
    assert exact == pytest.approx(-beam().total_mass_per_length * a * L ** 4
                                  / (8 * 240e9 * 12.75e-3 * 0.08e-3 ** 3 / 12), rel=1e-14)
    for modes, tol in ((4, 1e-4), (20, 1e-7)):
        model = beam(modes=modes)
        q_static = -model.participation * a / model.natural_frequencies_rad ** 2
        tip = model.reconstruct(q_static, [L])[0]
        assert abs(tip / exact - 1.0) < tol


def test_reconstruct_sums_modes_at_each_point():
    model = beam(modes=3)
    q = np.array([[1.0, 0.5, -0.2], [0.0, 1.0, 0.0]])
    x = np.array([0.0, 0.04, L])
    out = model.reconstruct(q, x)
    assert out.shape == (2, 3)
    manual = sum(q[:, n, None] * model.mode_shape(x, n + 1)[None, :] for n in range(3))
    np.testing.assert_allclose(out, manual, rtol=1e-14, atol=1e-15)
    with pytest.raises(ParameterError, match=r"\(\.\.\., 3\)"):
        model.reconstruct(np.ones((2, 4)), x)


# --------------------------------------------------------------------------- damping
def test_rayleigh_damping_keeps_the_paper_dry_ratios_on_modes_1_and_2():
    dry = BeamModel.from_specimen(SPECIMEN, modes=4, fluid="air", damping=Damping.paper_dry())
    np.testing.assert_allclose(dry.damping_ratios[:2], [0.002, 0.001], rtol=1e-12)
    omega = dry.natural_frequencies_rad
    # Rayleigh: zeta = alpha / (2 w) + beta w / 2, growing with w beyond mode 2
    assert np.all(np.diff(dry.damping_ratios[1:]) > 0)
    rates = dry.linear_damping_rates
    beta = (rates[3] - rates[2]) / (omega[3] ** 2 - omega[2] ** 2)
    np.testing.assert_allclose(rates, rates[0] + beta * (omega ** 2 - omega[0] ** 2), rtol=1e-10)


def test_linear_damping_per_length_and_per_mode():
    wet = BeamModel.from_specimen(SPECIMEN, damping=Damping.paper_wet())
    np.testing.assert_allclose(wet.linear_damping_rates, 0.65 / wet.total_mass_per_length)
    assert wet.quadratic_damping_rate == 33.0 / wet.total_mass_per_length
    ratios = beam(modes=2, damping=Damping(ratios=(0.01, 0.02)))
    np.testing.assert_allclose(ratios.damping_ratios, [0.01, 0.02], rtol=1e-14)
    default = BeamModel.from_specimen(SPECIMEN)
    assert default.damping == Damping(c_f=default.c_f_theory)


def test_galerkin_factor_of_mode_1():
    # kappa_1 = int |W_1|^3 / L; W_1 >= 0 so a fine trapezoid rule is an independent check.
    x = np.linspace(0.0, L, 200001)
    w1 = beam(modes=1).mode_shape(x, 1)
    assert beam(modes=1).galerkin_factors()[0] == pytest.approx(
        np.trapezoid(w1 ** 3, x) / L, rel=1e-8)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("key", ["length", "width", "thickness", "youngs_modulus", "density"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf")])
def test_non_positive_or_non_finite_geometry_is_refused(key, value):
    with pytest.raises(ParameterError, match=rf"beam\.{key}: got .*expected a finite number > 0"):
        beam(**{key: value})


def test_unknown_fluid_is_refused_with_the_accepted_names():
    with pytest.raises(ParameterError,
                       match=r"beam\.fluid: got 'oil'; expected one of 'air', 'water'"):
        beam(fluid="oil")
    with pytest.raises(ParameterError, match="beam.fluid"):
        BeamModel.from_specimen(SPECIMEN, fluid="mercury")


@pytest.mark.parametrize("modes", [0, -2, 2.0, True])
def test_bad_number_of_modes_is_refused(modes):
    with pytest.raises(ParameterError, match=r"beam\.modes: .*expected an integer >= 1"):
        beam(modes=modes)
    if not isinstance(modes, bool) and isinstance(modes, int):
        with pytest.raises(ParameterError, match="expected an integer >= 1"):
            clamped_free_betas(modes)


def test_bad_damping_is_refused():
    with pytest.raises(ParameterError,
                       match="damping.c_f: got -1.0; expected a finite number >= 0"):
        Damping(c_f=-1.0)
    with pytest.raises(ParameterError, match="either as c_i .* or as ratios"):
        Damping(c_i=0.5, ratios=(0.01,))
    with pytest.raises(ParameterError, match="damping.projection: got 'exact'"):
        Damping(projection="exact")
    with pytest.raises(ParameterError, match=r"damping.ratios\[1\]: got nan"):
        Damping(ratios=(0.01, float("nan")))
    with pytest.raises(ParameterError, match="Rayleigh damping needs exactly 2 ratios"):
        Damping(ratios=(0.01, 0.02, 0.03), rayleigh=True)
    with pytest.raises(ParameterError, match="2 ratios for 4 modes; give one ratio per mode"):
        beam(modes=4, damping=Damping(ratios=(0.002, 0.001)))


def test_positions_off_the_beam_are_refused():
    with pytest.raises(ParameterError,
                       match=r"x = 0.1 m is not on the beam; expected 0 <= x <= 0.08 m"):
        beam().mode_shapes([0.0, 0.1])
    with pytest.raises(ParameterError, match="is not on the beam"):
        beam().mode_shape(float("nan"), 1)
