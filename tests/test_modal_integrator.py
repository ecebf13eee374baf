"""The fixed-step modal integrator against solve_ivp, closed forms and its own order."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fsi_lab.beam import BeamModel, Damping
from fsi_lab.errors import ParameterError
from fsi_lab.modal_integrator import MAX_OMEGA_DT, OUTPUTS, ModalSimulator, check_step, simulate
from fsi_lab.specimen import Specimen

SPECIMEN = Specimen.from_mapping({})
L = SPECIMEN.length
POINTS = np.linspace(0.016, L, 5)
WET = BeamModel.from_specimen(SPECIMEN, modes=4, damping=Damping.paper_wet())

# Piecewise-linear base acceleration (m/s^2): 40 knots 5 ms apart. Every sample rate used below
# puts samples on the knots, so the integrator sees exactly this excitation at every rate.
KNOT_STEP = 0.005
KNOTS = np.arange(41) * KNOT_STEP
KNOT_VALUES = 5.0 * np.random.default_rng(7).normal(size=KNOTS.size)


def reference(model, per_knot):
    """solve_ivp (DOP853, rtol 1e-10) of Eq. 20 knot interval by knot interval.

    Returns modal q, q', q'' at the sample times of a rate with ``per_knot`` samples per knot.
    """
    om2 = model.natural_frequencies_rad ** 2
    lin = model.linear_damping_rates
    quad = model.quadratic_damping_rate
    part = model.participation
    n = model.modes

    def rhs(t, y, t0, a0, slope):
        q, v = y[:n], y[n:]
        a = a0 + slope * (t - t0)
        return np.concatenate([v, -om2 * q - lin * v - quad * np.abs(v) * v - part * a])

    y = np.zeros(2 * n)
    rows = []
    for i in range(KNOTS.size - 1):
        slope = (KNOT_VALUES[i + 1] - KNOT_VALUES[i]) / KNOT_STEP
        args = (KNOTS[i], KNOT_VALUES[i], slope)
        sol = solve_ivp(rhs, (KNOTS[i], KNOTS[i + 1]), y, method="DOP853", rtol=1e-10,
                        atol=1e-16, dense_output=True, args=args)
        t = KNOTS[i] + np.arange(per_knot) * KNOT_STEP / per_knot
        states = sol.sol(t).T
        accel = np.array([rhs(tk, s, *args)[n:] for tk, s in zip(t, states)])
        rows.append(np.hstack([states, accel]))
        y = sol.y[:, -1]
    last = np.hstack([y, rhs(KNOTS[-1], y, KNOTS[-2], KNOT_VALUES[-2],
                             (KNOT_VALUES[-1] - KNOT_VALUES[-2]) / KNOT_STEP)[n:]])
    out = np.vstack(rows + [last[None]])
    return out[:, :n], out[:, n:2 * n], out[:, 2 * n:]


def excitation(per_knot):
    rate = per_knot / KNOT_STEP
    t = np.arange((KNOTS.size - 1) * per_knot + 1) / rate
    return rate, np.interp(t, KNOTS, KNOT_VALUES)


def relative_error(ours, ref):
    return np.max(np.abs(ours - ref)) / np.max(np.abs(ref))


# --------------------------------------------------------------------------- accuracy
def test_matches_solve_ivp_within_1e6_with_quadratic_damping():
    rate, acc = excitation(50)  # 10 kHz, 0.2 s
    out = ModalSimulator(WET, rate, POINTS, modal=True).advance(acc)
    q, v, a = reference(WET, 50)
    shapes = WET.mode_shapes(POINTS)
    assert np.max(np.abs(v)) > 0.05  # quadratic term C_f |q'| is comparable to C_i: nonlinear
    assert relative_error(out["displacement"], q @ shapes.T) < 1e-6
    assert relative_error(out["velocity"], v @ shapes.T) < 1e-6
    assert relative_error(out["acceleration"], a @ shapes.T) < 1e-5
    assert relative_error(out["modal_displacement"][:, 0], q[:, 0]) < 1e-6


def test_fourth_order_convergence_when_the_step_is_halved():
    errors = []
    for per_knot in (10, 20, 40, 80):  # 2, 4, 8, 16 kHz
        rate, acc = excitation(per_knot)
        out = ModalSimulator(WET, rate, [L], modal=True).advance(acc)
        q, v, _ = reference(WET, per_knot)
        errors.append(np.max(np.abs(out["modal_velocity"] - v)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 3.8) & (orders < 4.2)), orders


def test_free_decay_envelope_follows_the_linear_plus_quadratic_closed_form():
    """dA/dt = -a A - b A^2, a = r/2, b = 4 (C_f/m) omega / (3 pi) (SCIENCE.md)."""
    model = BeamModel.from_specimen(SPECIMEN, modes=1, damping=Damping(c_i=0.02, c_f=33.0))
    rate, a0 = 2000.0, 2e-4
    sim = ModalSimulator(model, rate, [L], modal=True)
    sim.set_state(q=[a0])
    q = sim.advance(np.zeros(40000))["modal_displacement"][:, 0]
    i = np.where((q[1:-1] > q[:-2]) & (q[1:-1] >= q[2:]))[0] + 1
    y0, y1, y2 = q[i - 1], q[i], q[i + 1]
    d = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    peaks, t = y1 - 0.25 * (y0 - y2) * d, (i + d) / rate
    a = model.linear_damping_rates[0] / 2
    b = 4 * model.quadratic_damping_rate * model.natural_frequencies_rad[0] / (3 * math.pi)
    closed = a * a0 * np.exp(-a * t) / (a + b * a0 * (1 - np.exp(-a * t)))
    assert peaks.size > 40 and peaks[-1] < 0.1 * a0  # a long decay, quadratic then linear
    assert np.max(np.abs(peaks / closed - 1)) < 1e-4


def test_dry_damping_ratio_from_the_log_decrement():
    dry = BeamModel.from_specimen(SPECIMEN, modes=2, fluid="air", damping=Damping.paper_dry())
    sim = ModalSimulator(dry, 5000.0, [L], modal=True)
    sim.set_state(q=[0.0, 1e-4])
    q2 = sim.advance(np.zeros(5000))["modal_displacement"][:, 1]
    peaks = np.array([q2[j - 1:j + 2].max() for j in
                      np.where((q2[1:-1] > q2[:-2]) & (q2[1:-1] >= q2[2:]))[0] + 1])
    cycles = peaks.size - 1
    zeta = np.log(peaks[0] / peaks[-1]) / (2 * math.pi * cycles)
    assert zeta == pytest.approx(0.001, rel=0.03)


def test_steady_response_to_constant_base_acceleration_is_the_static_deflection():
    model = BeamModel.from_specimen(SPECIMEN, modes=4, damping=Damping(ratios=(0.7,) * 4))
    rate, a = 2000.0, 2.5
    out = simulate(model, np.full(8000, a), rate, [L])
    exact = model.static_tip_deflection(a)
    assert out["displacement"][-1, 0] == pytest.approx(exact, rel=1e-4)  # modal truncation
    assert abs(out["acceleration"][-1, 0]) < 1e-9 * abs(exact) * rate ** 2
    t = np.arange(8000) / rate
    # absolute = relative + base motion; the base integrates the constant acceleration exactly
    np.testing.assert_allclose(out["absolute_velocity"][:, 0] - out["velocity"][:, 0], a * t,
                               rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(out["absolute_displacement"][:, 0] - out["displacement"][:, 0],
                               0.5 * a * t ** 2, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(out["absolute_acceleration"] - out["acceleration"], a,
                               rtol=1e-12)


def test_base_motion_is_exact_for_piecewise_linear_acceleration():
    rate, c = 2000.0, 40.0  # base acceleration c t, m/s^2
    t = np.arange(3000) / rate
    out = simulate(WET, c * t, rate, [0.03, L], outputs=OUTPUTS[3:] + OUTPUTS[:3])
    np.testing.assert_allclose(out["absolute_velocity"] - out["velocity"],
                               np.repeat(c * t[:, None] ** 2 / 2, 2, axis=1), rtol=1e-12)
    np.testing.assert_allclose(out["absolute_displacement"] - out["displacement"],
                               np.repeat(c * t[:, None] ** 3 / 6, 2, axis=1), rtol=1e-12)


def test_blocks_give_bit_identical_results_and_state_carries_over():
    rate, acc = excitation(20)
    whole = ModalSimulator(WET, rate, POINTS).advance(acc)
    sim = ModalSimulator(WET, rate, POINTS)
    cuts = [0, 1, 2, 57, 58, 300, 555, acc.size]
    parts = [sim.advance(acc[i:j]) for i, j in zip(cuts[:-1], cuts[1:])]
    for name in OUTPUTS:
        assert np.array_equal(np.vstack([p[name] for p in parts]), whole[name])
    assert sim.samples_done == acc.size
    assert sim.state["time"] == pytest.approx((acc.size - 1) / rate)
    sim.reset()
    assert np.array_equal(sim.advance(acc)["velocity"], whole["velocity"])


def test_outputs_selection_and_empty_block():
    sim = ModalSimulator(WET, 2000.0, POINTS, outputs=("velocity",), modal=True)
    out = sim.advance(np.ones(7))
    assert set(out) == {"velocity", "modal_displacement", "modal_velocity"}
    assert out["velocity"].shape == (7, 5) and out["modal_velocity"].shape == (7, 4)
    empty = sim.advance([])
    assert empty["velocity"].shape == (0, 5)
    assert sim.samples_done == 7


# --------------------------------------------------------------------------- Galerkin projection
def test_galerkin_single_mode_is_the_per_mode_law_scaled_by_kappa():
    wet1 = BeamModel.from_specimen(SPECIMEN, modes=1,
                                   damping=Damping.paper_wet(projection="galerkin"))
    kappa = wet1.galerkin_factors()[0]
    assert kappa == pytest.approx(1.4778, abs=1e-4)  # per-mode underestimates it by 32 %
    per_mode = wet1.with_damping(Damping(c_i=0.65, c_f=33.0 * kappa))
    acc = 3.0 * np.random.default_rng(0).normal(size=4000)
    a = simulate(wet1, acc, 2000.0, [L])["displacement"]
    b = simulate(per_mode, acc, 2000.0, [L])["displacement"]
    assert relative_error(a, b) < 1e-10


def test_galerkin_couples_the_modes_and_differs_from_per_mode_at_large_amplitude():
    differences, coupling = {}, {}
    for q0 in (1e-6, 1e-3):
        runs = {}
        for projection in ("per-mode", "galerkin"):
            model = WET.with_damping(Damping.paper_wet(projection=projection))
            sim = ModalSimulator(model, 2000.0, [L], modal=True)
            sim.set_state(q=[q0, 0.0, 0.0, 0.0])
            runs[projection] = sim.advance(np.zeros(2000))
        # the per-mode law never moves a mode that starts at rest; the projection does
        assert np.all(runs["per-mode"]["modal_displacement"][:, 1:] == 0.0)
        coupling[q0] = np.max(np.abs(runs["galerkin"]["modal_displacement"][:, 1])) / q0
        differences[q0] = relative_error(runs["galerkin"]["displacement"],
                                         runs["per-mode"]["displacement"])
    assert differences[1e-6] < 2e-4  # linear damping dominates: the two agree
    assert differences[1e-3] > 3e-2  # quadratic damping dominates: they differ
    # the energy passed to mode 2 grows with the amplitude (quadratic coupling)
    assert 0 < coupling[1e-6] < 1e-5 and coupling[1e-3] > 1e-3


def test_galerkin_quadrature_is_converged_at_the_default():
    model = WET.with_damping(Damping.paper_wet(projection="galerkin"))
    rate, acc = excitation(10)
    default = ModalSimulator(model, rate, POINTS).advance(30 * acc)["velocity"]
    fine = ModalSimulator(model, rate, POINTS, galerkin_points=512).advance(30 * acc)["velocity"]
    # |w'| w' has a kink where w' changes sign along the beam: Gauss converges as N^-3
    assert relative_error(default, fine) < 1e-5


# --------------------------------------------------------------------------- bad input
def test_a_step_that_cannot_resolve_the_highest_mode_is_refused_with_what_would_do():
    dry = BeamModel.from_specimen(SPECIMEN, modes=4, fluid="air")
    f4 = dry.natural_frequencies_hz[3]
    needed = 2 * math.pi * f4 / MAX_OMEGA_DT
    with pytest.raises(ParameterError) as info:
        ModalSimulator(dry, 2000.0, [L])
    message = str(info.value)
    assert "2000 Hz cannot resolve mode 4 (396.558 Hz" in message
    assert f">= {math.ceil(needed)} Hz" in message
    assert "at most 2 modes are accepted" in message  # mode 3 at 202 Hz needs 2543 Hz
    check_step(dry, math.ceil(needed))  # the suggested rate is accepted
    with pytest.raises(ParameterError, match="not even mode 1"):
        check_step(dry, 100.0)


@pytest.mark.parametrize("rate", [0.0, -10.0, float("nan"), float("inf")])
def test_bad_sample_rate_is_refused(rate):
    with pytest.raises(ParameterError, match="sample_rate: got .*expected a finite number > 0 Hz"):
        ModalSimulator(WET, rate, [L])


def test_non_finite_excitation_is_refused_before_integrating():
    sim = ModalSimulator(WET, 2000.0, [L])
    sim.advance(np.ones(10))
    before = sim.state
    acc = np.ones(100)
    acc[42] = np.nan
    with pytest.raises(ParameterError, match=r"sample 42 of the block \(t = 0.026 s\) is nan"):
        sim.advance(acc)
    with pytest.raises(ParameterError, match="expected a 1-D block"):
        sim.advance(np.ones((3, 2)))
    after = sim.state
    assert sim.samples_done == 10
    assert np.array_equal(before["q"], after["q"]) and np.array_equal(before["v"], after["v"])


def test_bad_points_outputs_and_state_are_refused():
    with pytest.raises(ParameterError, match="is not on the beam"):
        ModalSimulator(WET, 2000.0, [0.05, -0.01])
    with pytest.raises(ParameterError, match="outputs: unknown 'strain'"):
        ModalSimulator(WET, 2000.0, [L], outputs=("strain",))
    sim = ModalSimulator(WET, 2000.0, [L])
    with pytest.raises(ParameterError, match="q: .*expected 4 finite modal values"):
        sim.set_state(q=[1.0, 2.0])
    with pytest.raises(ParameterError, match="model: got dict"):
        ModalSimulator({}, 2000.0, [L])


def test_divergence_is_reported_not_returned():
    stiff = WET.with_damping(Damping(c_f=1e7))
    with pytest.raises(ParameterError, match="became non-finite at t = .* raise the sample rate"):
        simulate(stiff, np.full(2000, 1e6), 2000.0, [L])
