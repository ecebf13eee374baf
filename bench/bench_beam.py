"""The modal beam simulation against scipy's solve_ivp on the same problem.

Problem: the paper's wet beam (C_i = 0.65, C_f = 33.0, per-mode quadratic damping), 4 modes,
random base acceleration (1 m/s^2 rms, linear between samples) sampled at 10 kHz for 10 s,
displacement, velocity and acceleration (relative and absolute) at 5 points.

Reference: ``solve_ivp`` (RK45, rtol 1e-8, atol 1e-12) with a numpy right-hand side, its step
held at the sample interval (``first_step = max_step = 1/fs``) so that both take the same steps,
outputs reconstructed with one matrix product per quantity. It runs on the first 0.5 s only and its
time is scaled by 20 (the cost is linear in the number of steps); the row names say so.

The third row shows that both solve the same problem. Its difference (about 1e-6) is the RK4
truncation error of the fixed step: white-noise forcing excites mode 4 (93.6 Hz, omega dt = 0.06),
whose phase error (omega dt)^4 / 120 per radian accumulates over the 0.5 s; the reference, with the
same steps at fifth order and error control, is within 2e-9 of a DOP853 rtol 1e-12 run.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from bench.table import Row, best_time
from fsi_lab.beam import BeamModel, Damping
from fsi_lab.modal_integrator import ModalSimulator
from fsi_lab.specimen import Specimen

RATE = 10_000.0
DURATION = 10.0
REFERENCE_SPAN = 0.5


def _problem():
    model = BeamModel.from_specimen(Specimen.from_mapping({}), modes=4,
                                    damping=Damping.paper_wet())
    points = np.linspace(0.016, model.length, 5)
    acc = np.random.default_rng(2024).normal(size=int(DURATION * RATE))
    return model, points, acc


def _reference(model, points, acc):
    """solve_ivp run of the same equations, with the same outputs."""
    n = model.modes
    om2 = model.natural_frequencies_rad ** 2
    lin = model.linear_damping_rates
    quad = model.quadratic_damping_rate
    part = model.participation
    t = np.arange(acc.size) / RATE

    def rhs(tt, y):
        q, v = y[:n], y[n:]
        a = np.interp(tt, t, acc)
        return np.concatenate([v, -om2 * q - lin * v - quad * np.abs(v) * v - part * a])

    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), method="RK45", t_eval=t, rtol=1e-8,
                    atol=1e-12, first_step=1 / RATE, max_step=1 / RATE)
    q, v = sol.y[:n].T, sol.y[n:].T
    qdd = -om2 * q - lin * v - quad * np.abs(v) * v - part * acc[:, None]
    shapes = model.mode_shapes(points).T
    base_v = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) / RATE)])
    rel = {"displacement": q @ shapes, "velocity": v @ shapes, "acceleration": qdd @ shapes}
    rel["absolute_velocity"] = rel["velocity"] + base_v[:, None]
    rel["absolute_acceleration"] = rel["acceleration"] + acc[:, None]
    return rel


def rows() -> list[Row]:
    model, points, acc = _problem()
    sim = ModalSimulator(model, RATE, points)
    sim.advance(acc[:10])  # numba compilation or cache load

    def ours():
        sim.reset()
        return sim.advance(acc)

    ours_s = best_time(ours, repeat=5)

    span = int(REFERENCE_SPAN * RATE)
    started = time.perf_counter()
    ref = _reference(model, points, acc[:span])
    ref_s = (time.perf_counter() - started) * (acc.size / span)
    ratio = ref_s / ours_s

    out = ours()
    agree = max(np.max(np.abs(out[k][:span] - ref[k])) / np.max(np.abs(ref[k]))
                for k in ("displacement", "velocity"))

    name = "modal sim 10 s @ 10 kHz, 4 modes, 5 points"
    return [
        Row(f"{name} (after warm-up)", f"{ours_s * 1e3:.1f} ms",
            f"solve_ivp {ref_s:.1f} s", "<= 20 ms", ours_s <= 0.020),
        Row("  speed-up vs solve_ivp RK45, same steps (ref. run 0.5 s, x20)",
            f"{ratio:.0f}x", f"solve_ivp {ref_s:.1f} s", ">= 300x", ratio >= 300),
        Row("modal sim vs solve_ivp on those 0.5 s: max rel. diff (disp., vel.)",
            f"{agree:.1e}", "solve_ivp rtol 1e-8", "<= 1e-5", agree <= 1e-5),
    ]
