"""Exact simulators used as ground truth by the analysis tests (fixed seeds, no shortcuts).

Free decays are integrated by ODEPACK's LSODA at rtol 1e-11 (far tighter than any tolerance
tested); decaying tones and linear decays are closed forms.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.signal import lsim
from scipy.special import ellipk
from support import ode_path


def time_axis(duration: float, fs: float) -> np.ndarray:
    return np.arange(int(round(duration * fs))) / fs


def decaying_tone(t: np.ndarray, amplitude: float, freq: float, zeta: float, phase: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Damped tone A e^{-zeta w t} cos(w_d t + phase): signal, envelope, frequency (Hz)."""
    w = 2 * math.pi * freq
    wd = w * math.sqrt(1 - zeta * zeta)
    env = amplitude * np.exp(-zeta * w * t)
    return env * np.cos(wd * t + phase), env, np.full_like(t, wd / (2 * math.pi))


def linear_decay(t: np.ndarray, amplitude: float, freq: float, zeta: float, phase: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Displacement and velocity of a viscously damped mode (exact)."""
    w = 2 * math.pi * freq
    s = zeta * w
    wd = w * math.sqrt(1 - zeta * zeta)
    e = amplitude * np.exp(-s * t)
    x = e * np.cos(wd * t + phase)
    v = e * (-s * np.cos(wd * t + phase) - wd * np.sin(wd * t + phase))
    return x, v


def duffing_decay(t: np.ndarray, w0: float, zeta: float, alpha: float, x0: float
                  ) -> np.ndarray:
    """x'' + 2 zeta w0 x' + w0^2 x + alpha x^3 = 0 from x(0) = x0, x'(0) = 0."""
    path = ode_path(lambda _, y: (y[1], -2 * zeta * w0 * y[1] - w0 * w0 * y[0]
                                  - alpha * y[0] ** 3),
                    (x0, 0.0), t, start=0.0, rtol=1e-11, atol=1e-14 * x0)
    return path[:, 0]


def duffing_hb_backbone(amplitude: np.ndarray, w0: float, alpha: float) -> np.ndarray:
    """Harmonic-balance backbone, Hz: w0 sqrt(1 + 3 alpha A^2 / (4 w0^2)) / (2 pi)."""
    return w0 * np.sqrt(1 + 3 * alpha * amplitude ** 2 / (4 * w0 * w0)) / (2 * math.pi)


def duffing_exact_backbone(amplitude: np.ndarray, w0: float, alpha: float) -> np.ndarray:
    """Exact (elliptic) frequency of the undamped Duffing oscillator of peak A, Hz."""
    a2 = alpha * amplitude ** 2
    m = a2 / (2 * (w0 * w0 + a2))
    return math.pi * np.sqrt(w0 * w0 + a2) / (2 * ellipk(m)) / (2 * math.pi)


def quadratic_damping_decay(t: np.ndarray, m: float, c1: float, c2: float, k: float,
                            x0: float) -> tuple[np.ndarray, np.ndarray]:
    """m x'' + (c1 + c2 |x'|) x' + k x = 0 from rest at x0: displacement and velocity."""
    path = ode_path(lambda _, y: (y[1], -(c1 + c2 * abs(y[1])) * y[1] / m - k * y[0] / m),
                    (x0, 0.0), t, start=0.0, rtol=1e-11, atol=1e-14 * x0)
    return path[:, 0], path[:, 1]


def envelope_law(t: np.ndarray, a: float, b: float, a0: float) -> np.ndarray:
    """Closed-form envelope of dA/dt = -a A - b A^2."""
    e = np.exp(-a * t)
    return a * a0 * e / (a + b * a0 * (1 - e))


def noisy(x: np.ndarray, relative_rms: float, seed: int, reference: float | None = None
          ) -> np.ndarray:
    """x plus white noise of RMS ``relative_rms`` times ``reference`` (default: max |x|)."""
    rng = np.random.default_rng(seed)
    ref = float(np.max(np.abs(x))) if reference is None else reference
    return x + relative_rms * ref * rng.standard_normal(x.size)


def middle(n: int, fraction: float = 0.9) -> slice:
    """Slice of the middle ``fraction`` of n samples."""
    cut = int(round(n * (1 - fraction) / 2))
    return slice(cut, n - cut)


def rel_rms(estimate: np.ndarray, truth: np.ndarray) -> float:
    return float(np.sqrt(np.mean((estimate - truth) ** 2) / np.mean(truth ** 2)))


# Shared simulated records, computed once per session. (Plain cached functions rather than
# conftest fixtures: a conftest.py here would shadow the top-level ``tests/conftest.py`` that
# other test modules import by name.)
@functools.lru_cache(maxsize=None)
def duffing_record() -> dict:
    """Lightly damped hardening Duffing decay: 3 alpha A^2 / (4 w0^2) = 0.5 at the start."""
    fs = 2000.0
    w0 = 2 * math.pi * 10.0
    x0 = 1e-3
    alpha = 0.5 * 4 * w0 * w0 / (3 * x0 * x0)
    t = time_axis(12.0, fs)
    return {"t": t, "fs": fs, "w0": w0, "alpha": alpha,
            "x": duffing_decay(t, w0, 0.004, alpha, x0)}


@functools.lru_cache(maxsize=None)
def quadratic_record() -> dict:
    """m x'' + (c1 + c2 |x'|) x' + k x = 0 decaying about 40-fold, linear and quadratic damping
    of similar weight at the start (a = c1 / 2m = 0.2 /s, b A0 = 4 c2 w A0 / (3 pi m) = 0.2 /s).
    """
    fs = 2000.0
    m = 1.0
    w0 = 2 * math.pi * 5.0
    c1 = 0.4
    c2 = 1.5
    x0 = 0.01
    t = time_axis(15.0, fs)
    x, v = quadratic_damping_decay(t, m, c1, c2, m * w0 * w0, x0)
    return {"t": t, "fs": fs, "m": m, "w0": w0, "c1": c1, "c2": c2, "x0": x0, "x": x, "v": v}


def impulse_train_response(t: np.ndarray, accel, forces: np.ndarray, starts: np.ndarray,
                           width: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """x'' = accel(x, x') + f(t) from rest, f a train of half-sine impulses (peak ``forces``,
    per unit mass, starting at ``starts`` s, ``width`` s long), as the impulse-train excitation
    shapes them. Integrated piece by piece between the impulse edges (LSODA, rtol 1e-11, atol
    1e-14 ``scale``): displacement and velocity at ``t``."""
    edges = np.unique(np.concatenate(([t[0], t[-1]], starts, starts + width)))
    edges = edges[(edges >= t[0]) & (edges <= t[-1])]
    x = np.empty_like(t)
    v = np.empty_like(t)
    y = np.zeros(2)
    for lo, hi in zip(edges[:-1], edges[1:]):
        on = np.flatnonzero((starts <= lo) & (lo < starts + width))
        force = ((lambda s, i=int(on[0]): forces[i] * math.sin(math.pi * (s - starts[i]) / width))
                 if on.size else (lambda s: 0.0))
        sel = np.flatnonzero((t >= lo) & (t < hi))
        path = ode_path(lambda s, yy: (yy[1], accel(yy[0], yy[1]) + force(s)), y,
                        np.append(t[sel], hi), start=lo, rtol=1e-11, atol=1e-14 * scale)
        x[sel], v[sel] = path[:-1, 0], path[:-1, 1]
        y = path[-1]
    x[-1], v[-1] = y
    return x, v


def modal_chirp_response(t: np.ndarray, f_start: float, f_stop: float,
                         modes: tuple[tuple[float, float, float], ...]) -> np.ndarray:
    """Displacement of uncoupled modes x_j'' + 2 zeta_j w_j x_j' + w_j^2 x_j = g_j u(t), summed,
    from rest, under the linear sweep u = sin(2 pi (f_start t + (f_stop - f_start) t^2 / 2T))
    over the record's duration T; ``modes`` holds (frequency Hz, zeta, gain g_j). Exact for the
    sweep interpolated linearly between samples (scipy.signal.lsim's matrix exponential)."""
    duration = float(t[-1])
    u = np.sin(2 * math.pi * (f_start * t + (f_stop - f_start) * t ** 2 / (2 * duration)))
    x = np.zeros_like(t)
    for f, zeta, gain in modes:
        w = 2 * math.pi * f
        x += lsim(([gain], [1.0, 2 * zeta * w, w * w]), u, t)[1]
    return x
