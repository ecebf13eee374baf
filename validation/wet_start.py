"""Where the wet bench's C_f error comes from: mode 2's extrema against the simulated modal truth.

For a wet-bench row of the matrix (:mod:`validation.bench`), the bench is simulated with its
modal coordinates kept, and the record (noise-free, or with a trial's noise) is analysed as
``fsi-lab run`` analyses it. Each free decay of mode 2 that the identification used is then
compared, extremum by extremum, with two truths in the measured coordinate (``W_2(x_m) q_2'``):

- the *forced* truth: the simulated modal velocity itself, which still holds the response to
  the base's last motion (the shaker's suspension rings on after the excitation);
- the *free* truth: the same mode released from its simulated state a quarter period before
  the decay's first extremum and left alone (the per-mode equation with the bench's C_i and
  C_f, no base motion): the decay the damping law describes.

Printed per decay: the relative error (%) of each extremum as measured on the band signal
(raw), after the filter correction (corrected), and of the forced truth, all against the free
truth; then C_i and C_f fitted (:func:`fsi_lab.dsp.laws.fit_law`, unweighted) to each set of
amplitudes at the same times, beside what the chain reports.

Usage: ``python -m validation.wet_start [SEED,SEED...] [NAME FILTER...]`` (seed ``-1``, the
default: noise-free).
"""

from __future__ import annotations

import contextlib
import math
import sys

import numpy as np
from scipy.integrate import solve_ivp

from validation.bench import MODE, _profile, _registry, bench_cases, bench_estimate
from validation.cases import Case


def modal_record(case: Case) -> dict[str, object]:
    """The row's tip velocity and base acceleration (as :func:`validation.bench.bench_record`)
    with mode 2's modal displacement and velocity, the beam model and ``W_2(x_m)``."""
    from fsi_lab.modal_integrator import ModalSimulator
    from fsi_lab.modelling import beam_model
    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.shaker import ShakerModel

    profile = _profile(case.bench)
    waveform, rate = prepare_excitation(profile, _registry())
    model = beam_model(profile.specimen, profile.model, None)
    point = profile.specimen.measurement_point
    shaker = ShakerModel.from_profile(case.fs, profile.shaker)
    beam = ModalSimulator(model, case.fs, [point], outputs=("absolute_velocity",), modal=True)
    gain = float(profile.roles["amplifier"].settings.get("gain", 1.0))
    n = int(round(case.duration * case.fs))
    t = np.arange(n) / case.fs
    drive = np.interp(t, np.arange(waveform.size) / rate, waveform, right=0.0)
    block = int(case.fs)
    tip, acc, q, v = [], [], [], []
    for s in range(0, n, block):
        _, a = shaker.advance(drive[s:s + block] * gain)
        out = beam.advance(a)
        tip.append(out["absolute_velocity"][:, 0])
        acc.append(a)
        q.append(out["modal_displacement"][:, MODE - 1])
        v.append(out["modal_velocity"][:, MODE - 1])
    return {"tip": np.concatenate(tip), "base": np.concatenate(acc), "q": np.concatenate(q),
            "v": np.concatenate(v), "model": model,
            "shape": float(model.mode_shape(point, MODE))}


def free_decay(rec: dict, start: int, stop: int, fs: float) -> np.ndarray:
    """Mode 2 released from its simulated state at sample ``start`` without base motion, as
    ``W_2(x_m) q_2'`` (m/s) on samples ``start..stop`` (DOP853, rtol 1e-10)."""
    model = rec["model"]
    m = model.total_mass_per_length
    w = float(model.natural_frequencies_rad[MODE - 1])
    c1, c2 = model.damping.c_i / m, model.damping.c_f / m
    t = np.arange(start, stop) / fs
    sol = solve_ivp(lambda _, y: [y[1], -w * w * y[0] - c1 * y[1] - c2 * abs(y[1]) * y[1]],
                    (t[0], t[-1]), [rec["q"][start], rec["v"][start]], t_eval=t,
                    method="DOP853", rtol=1e-10, atol=1e-14)
    return rec["shape"] * sol.y[1]


def extrema(x: np.ndarray, fs: float, t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Times (s, from ``t0``) and values of the extremum of each half cycle of ``x``,
    parabolically refined."""
    cuts = np.flatnonzero(np.diff(np.signbit(x)))
    i = np.array([lo + 1 + int(np.argmax(np.abs(x[lo + 1:hi + 1])))
                  for lo, hi in zip(cuts[:-1], cuts[1:])], dtype=np.int64)
    i = i[(i > 0) & (i < x.size - 1)]
    y0, y1, y2 = x[i - 1], x[i], x[i + 1]
    den = y0 - 2.0 * y1 + y2
    shift = np.where(den != 0, 0.5 * (y0 - y2) / np.where(den != 0, den, 1.0), 0.0)
    return t0 + (i + shift) / fs, y1 - 0.25 * (y0 - y2) * shift


def at(times: np.ndarray, values: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """``|values|`` at the entries of ``times`` nearest each of ``wanted``."""
    j = np.clip(np.searchsorted(times, wanted), 1, times.size - 1)
    j = np.where(np.abs(times[j - 1] - wanted) < np.abs(times[j] - wanted), j - 1, j)
    return np.abs(values[j])


@contextlib.contextmanager
def captured_identification():
    """Keep the :class:`fsi_lab.dsp.identify.Identification` the chain's hvd computes."""
    import fsi_lab.plugins.analysis._hvd as hvd

    found: dict[str, object] = {}
    original = hvd.identify

    def keep(*args, **kwargs):
        found["identification"] = original(*args, **kwargs)
        return found["identification"]

    hvd.identify = keep
    try:
        yield found
    finally:
        hvd.identify = original


def diagnose(case: Case, seed: int, rec: dict | None = None) -> str:
    """The report described in the module notes for one row and seed (-1: noise-free)."""
    from fsi_lab.dsp.laws import fit_law

    rec = rec or modal_record(case)
    fs = case.fs
    x = np.stack([rec["tip"], rec["base"]])
    if seed >= 0:
        rng = np.random.default_rng(seed)
        x = x + case.noise * np.max(np.abs(x), axis=-1, keepdims=True) \
            * rng.standard_normal(x.shape)
    with captured_identification() as found:
        est = bench_estimate(case, x)
    lines = [f"{case.name}, seed {seed}: reported C_i {est.c_i:.3f} C_f {est.c_f:.2f}"
             + (" (warned)" if est.warned else "")
             + (f" refused: {est.refused}" if est.refused else "")]
    ident = found.get("identification")
    if ident is None or est.refused:
        return "\n".join(lines)
    truth_f = float(rec["model"].natural_frequencies_hz[MODE - 1])
    mode = min(ident.modes, key=lambda m: abs(math.log(m.frequency_hz / truth_f)))
    sets: dict[str, list[np.ndarray]] = {"free truth": [], "forced truth": [], "raw": [],
                                         "corrected": []}
    ft, fv = extrema(rec["shape"] * rec["v"], fs)
    for d in mode.decays:
        start = int(round((d.times[0] - 0.25 / truth_f) * fs))
        stop = min(rec["v"].size, int(round((d.times[-1] + 0.1) * fs)))
        free = at(*extrema(free_decay(rec, start, stop, fs), fs, start / fs), d.times)
        parts = {"free truth": free, "forced truth": at(ft, fv, d.times),
                 "raw": np.abs(d.values), "corrected": d.amplitude}
        for key, value in parts.items():
            sets[key].append(value)
        lines.append(f"  decay from {d.times[0]:.3f} s (window {d.window[0] / fs:.3f} s), "
                     f"{d.times.size} extrema; first 8, % against the free truth:")
        for key in ("raw", "corrected", "forced truth"):
            lines.append(f"    {key:>12}: " + " ".join(
                f"{v:+6.1f}" for v in 100.0 * (parts[key][:8] / free[:8] - 1.0)))
    m, scale = rec["model"].total_mass_per_length, abs(rec["shape"])
    w0 = 2.0 * math.pi * mode.frequency_hz
    fits = []
    for key, amps in sets.items():
        fit = fit_law("quadratic", amps, w0)
        fits.append(f"{key} {2 * m * fit.value('a'):.3f} / {m * scale * fit.value('beta'):.2f}")
    lines.append("  C_i / C_f fitted to: " + "; ".join(fits))
    return "\n".join(lines)


def main() -> int:
    args = sys.argv[1:]
    seeds = [-1]
    if args and all(part.lstrip("-").isdigit() for part in args[0].split(",")):
        seeds = [int(part) for part in args.pop(0).split(",")]
    for case in bench_cases():
        if case.expect != "number" or (args and not any(a in case.name for a in args)):
            continue
        rec = modal_record(case)
        for seed in seeds:
            print(diagnose(case, seed, rec), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
