"""The modal beam simulation against scipy's solve_ivp on the same problem.

Problem: the paper's wet beam (C_i = 0.65, C_f = 33.0, per-mode quadratic damping), 4 modes,
random base acceleration (1 m/s^2 rms, linear between samples) sampled at 10 kHz for 10 s,
displacement, velocity and acceleration (relative and absolute) at 5 points.

References: ``solve_ivp`` (RK45, rtol 1e-8, atol 1e-12) with a numpy right-hand side, outputs
reconstructed with one matrix product per quantity, twice: its step held at the sample interval
(``first_step = max_step = 1/fs``) so that both take the same steps, and adaptive as a user
would call it (no step imposed). They run on the first 0.5 s only and their time is scaled by 20
(the cost is linear in the record's length); the rows say so.

Every time is measured :data:`~bench.table.REPEAT` times, ours and each reference's alike, and
given as median (min-max). Warm: after one untimed call (numba compiled). Cold: the
simulator's construction and first record in a fresh process with an empty numba cache (the
compilation included), its imports timed apart.

The last rows time ``fsi-lab simulate`` for 600 s at 10 kHz (4 modes) as a user runs it, the
whole process from start to exit (imports, profile, excitation, integration, writing the run
file), against the adaptive solve_ivp (RK45, rtol 1e-8) on the same problem - the profile's
beam driven by the base acceleration the run file holds, output at the measuring point - and
its solving time alone (no imports, no file). With the random drive (``--set
excitation.plugin=random``: the beam forced all the time, as in the rows above) the reference
runs on the first 0.5 s and is scaled by 1200; with the profile's own drive (a pulse, then 599 s
of free decay) it runs once on the whole record, where its step grows as the decay dies (its
absolute tolerance, 1e-12, then dominates), so that row says how far an adaptive step gains on
a record that is mostly silence.

The third row shows that both solve the same problem. Its difference (about 1e-6) is the RK4
truncation error of the fixed step: white-noise forcing excites mode 4 (93.6 Hz, omega dt = 0.06),
whose phase error (omega dt)^4 / 120 per radian accumulates over the 0.5 s; the reference, with the
same steps at fifth order and error control, is within 2e-9 of a DOP853 rtol 1e-12 run.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from bench.table import ROOT, Row, cold_times, figure, median, process_times, times
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


def _reference(model, points, acc, fixed_step=True, rate=RATE):
    """solve_ivp run of the same equations, with the same outputs (its step held at the sample
    interval, or adaptive)."""
    n = model.modes
    om2 = model.natural_frequencies_rad ** 2
    lin = model.linear_damping_rates
    quad = model.quadratic_damping_rate
    part = model.participation
    t = np.arange(acc.size) / rate

    def rhs(tt, y):
        q, v = y[:n], y[n:]
        a = np.interp(tt, t, acc)
        return np.concatenate([v, -om2 * q - lin * v - quad * np.abs(v) * v - part * a])

    steps = {"first_step": 1 / rate, "max_step": 1 / rate} if fixed_step else {}
    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), method="RK45", t_eval=t, rtol=1e-8,
                    atol=1e-12, **steps)
    q, v = sol.y[:n].T, sol.y[n:].T
    qdd = -om2 * q - lin * v - quad * np.abs(v) * v - part * acc[:, None]
    shapes = model.mode_shapes(points).T
    base_v = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) / rate)])
    rel = {"displacement": q @ shapes, "velocity": v @ shapes, "acceleration": qdd @ shapes}
    rel["absolute_velocity"] = rel["velocity"] + base_v[:, None]
    rel["absolute_acceleration"] = rel["acceleration"] + acc[:, None]
    return rel


def _integrator_rows() -> list[Row]:
    model, points, acc = _problem()
    sim = ModalSimulator(model, RATE, points)
    sim.advance(acc[:10])  # numba compilation or cache load

    def ours():
        sim.reset()
        return sim.advance(acc)

    ours_s = times(ours)
    imports, cold = cold_times(
        "from bench.bench_beam import RATE, _problem\n"
        "from fsi_lab.modal_integrator import ModalSimulator",
        "ModalSimulator(model, RATE, points).advance(acc)",
        prepare="model, points, acc = _problem()")

    span = int(REFERENCE_SPAN * RATE)
    scale = acc.size / span
    ref = _reference(model, points, acc[:span])
    fixed_s = times(lambda: _reference(model, points, acc[:span]))
    adaptive = _reference(model, points, acc[:span], fixed_step=False)
    adaptive_s = times(lambda: _reference(model, points, acc[:span], fixed_step=False))

    out = ours()
    agree = max(np.max(np.abs(out[k][:span] - ref[k])) / np.max(np.abs(ref[k]))
                for k in ("displacement", "velocity"))
    agree_adaptive = max(np.max(np.abs(out[k][:span] - adaptive[k])) / np.max(np.abs(adaptive[k]))
                         for k in ("displacement", "velocity"))
    fixed_ratio = median(fixed_s) * scale / median(ours_s)
    adaptive_ratio = median(adaptive_s) * scale / median(ours_s)

    name = "modal sim 10 s @ 10 kHz, 4 modes, 5 points"
    references = (f"solve_ivp same steps {figure(fixed_s, scale=scale, digits=1)}; adaptive "
                  f"{figure(adaptive_s, scale=scale, digits=1)} (0.5 s runs, x20)")
    return [
        Row(f"{name}, warm", figure(ours_s, "ms", 1e3, 1), references, "<= 20 ms",
            median(ours_s) <= 0.020),
        Row(f"{name}, cold: first record, fresh process, empty numba cache",
            f"{figure(cold, digits=2)}; imports {figure(imports, digits=2)}", references, "-",
            None),
        Row("  speed-up vs solve_ivp RK45 rtol 1e-8 (ratio of medians, warm)",
            f"{fixed_ratio:.0f}x same steps, {adaptive_ratio:.0f}x adaptive; cold "
            f"{median(adaptive_s) * scale / median(cold):.1f}x adaptive", "1x",
            ">= 300x same steps", fixed_ratio >= 300),
        Row("modal sim vs solve_ivp on those 0.5 s: max rel. diff (disp., vel.)",
            f"{agree:.1e} same steps, {agree_adaptive:.1e} adaptive", "solve_ivp rtol 1e-8",
            "<= 1e-5", agree <= 1e-5),
    ]


#: ``fsi-lab simulate`` rows: record length (s), rate (Hz), and the span (s) the reference
#: solves under the random drive (scaled to the record).
SIMULATE_S, SIMULATE_RATE, SIMULATE_SPAN = 600.0, 10_000.0, 0.5
PROFILE = ROOT / "profiles" / "wet-beam-sim.toml"
RANDOM_DRIVE = ("--set", "excitation.plugin=random", "--set", f"excitation.duration={SIMULATE_S:g}")


def _fsi_lab() -> list[str]:
    """The ``fsi-lab`` console script of this environment, or the module if there is none."""
    script = Path(sys.executable).with_name("fsi-lab")
    return [str(script)] if script.exists() else [sys.executable, "-m", "fsi_lab.cli"]


def _simulated_problem(run_file: Path):
    """The beam model of the wet profile, its measuring point, and the base acceleration and
    tip velocity ``simulate`` wrote to ``run_file``."""
    from fsi_lab.modelling import beam_model
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.runfile import read_run

    profile = load_profile(PROFILE, load_registry())
    run = read_run(run_file)
    return (beam_model(profile.specimen, profile.model), profile.specimen.measurement_point,
            run.channels["base_acceleration"].data, run.channels["tip_velocity"].data)


def _simulate_row(label: str, extra: tuple[str, ...], span: float | None,
                  folder: Path) -> list[Row]:
    """Whole-process ``fsi-lab simulate`` against solve_ivp on what it wrote (``span`` s of it,
    scaled, or the whole record once when None)."""
    out = folder / f"{label.split()[0]}.h5"
    argv = [*_fsi_lab(), "simulate", str(PROFILE), "--duration", f"{SIMULATE_S:g}", "--rate",
            f"{SIMULATE_RATE:g}", *extra, "-o", str(out), "--quiet"]
    process_times(argv, repeat=1, before=lambda: out.unlink(missing_ok=True))  # numba cache
    ours = process_times(argv, before=lambda: out.unlink(missing_ok=True))
    model, point, acc, tip = _simulated_problem(out)
    n = acc.size if span is None else int(span * SIMULATE_RATE)
    scale = acc.size / n

    def reference():
        return _reference(model, np.array([point]), acc[:n], fixed_step=False,
                          rate=SIMULATE_RATE)

    if span is None:
        started = time.perf_counter()
        ref = reference()
        ref_s = [time.perf_counter() - started]
    else:
        ref = reference()
        ref_s = times(reference)
    ratio = median(ref_s) * scale / median(ours)
    diff = float(np.max(np.abs(tip[:n] - ref["absolute_velocity"][:, 0]))
                 / np.max(np.abs(ref["absolute_velocity"])))
    where = (f"first {span:g} s, x{scale:.0f}" if span is not None
             else "whole record, n=1")
    name = f"fsi-lab simulate {SIMULATE_S:g} s @ {SIMULATE_RATE / 1e3:g} kHz, 4 modes, {label}"
    target = ">= 100x" if span is not None else "-"
    return [Row(f"{name}, whole process", figure(ours, digits=2),
                f"solve_ivp RK45 rtol 1e-8 (solving only, {where}): "
                f"{figure(ref_s, scale=scale, digits=1)}", target,
                ratio >= 100 if span is not None else None),
            Row("  speed-up (ratio of medians); tip velocity vs solve_ivp, max rel. diff",
                f"{ratio:.0f}x; {diff:.1e}", "1x", "diff <= 1e-4 (RK4 at 10 kHz)", diff <= 1e-4)]


def _simulate_rows() -> list[Row]:
    with tempfile.TemporaryDirectory() as folder:
        return [*_simulate_row("random drive (forced throughout)", RANDOM_DRIVE, SIMULATE_SPAN,
                               Path(folder)),
                *_simulate_row("the profile's pulse, then free decay", (), None, Path(folder))]


def rows() -> list[Row]:
    return [*_integrator_rows(), *_simulate_rows()]
