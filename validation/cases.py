"""Records with known truth for the validation matrix (``make validate``) and its test slice.

Every record is integrated independently of fsi-lab's own integrators: scipy's DOP853 at a
relative tolerance of 1e-10 (far tighter than any figure validated), piece by piece between the
edges of the impulses that excite it. Noise is added per trial (white, RMS a fraction of the
record's largest value), so one simulation serves every trial of a case.

The oscillators, per unit modal mass and in the measured coordinate (metres)::

    x'' + (c1/m) x' + (c2/m) |x'| x' + F sgn(x') + w0^2 x + alpha x^3 = f(t)

with the truth expressed as the coefficients fsi-lab reports: C_i = c1 and C_f = c2 for the
mass per length ``m`` (kg/m) given to the analysis (the paper's wet beam: m = mu + M).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

#: The paper's wet beam, mode 2 in water: mass per length (mu + M), C_i and C_f.
WET_MASS = 7200.0 * 12.75e-3 * 0.08e-3 + 997.0 * math.pi * (12.75e-3 / 2) ** 2
WET_C_I, WET_C_F, WET_F = 0.65, 33.0, 17.0


@dataclass(frozen=True)
class Mode:
    """One uncoupled mode of a synthetic record (coefficients per length, see the notes)."""

    frequency: float                  # Hz (linear, undamped)
    c_i: float = WET_C_I              # kg/(m s)
    c_f: float = 0.0                  # kg/m^2
    friction: float = 0.0             # Coulomb force per unit mass, m/s^2
    alpha: float = 0.0                # cubic stiffness per unit mass, 1/(m^2 s^2)
    x0: float = 0.0                   # released from this displacement, m
    gain: float = 1.0                 # share of each impulse it receives


@dataclass(frozen=True)
class Case:
    """A record with known truth.

    Attributes
    ----------
    name
        Row label of the matrix.
    modes
        The modes summed into the record (the first is the one validated).
    fs, duration
        Sample rate (Hz) and length (s).
    mass
        Mass per length given to the analysis, kg/m.
    impulses
        ``(start s, width s, peak acceleration m/s^2)`` of half-sine impulses, or ().
    noise
        Noise RMS as a fraction of the record's largest value.
    law
        The damping law the record follows (``"quadratic"``, ``"viscous"``, ``"coulomb"``).
    """

    name: str
    modes: tuple[Mode, ...]
    fs: float = 10000.0
    duration: float = 3.0
    mass: float = WET_MASS
    impulses: tuple[tuple[float, float, float], ...] = ()
    noise: float = 0.01
    law: str = "quadratic"
    tags: tuple[str, ...] = field(default=())

    @property
    def truth(self) -> Mode:
        return self.modes[0]


def _rhs(mode: Mode, mass: float, impulses, t: float, y: np.ndarray) -> tuple[float, float]:
    x, v = y
    w = 2.0 * math.pi * mode.frequency
    force = 0.0
    for start, width, peak in impulses:
        if start <= t < start + width:
            force += mode.gain * peak * math.sin(math.pi * (t - start) / width)
    friction = mode.friction * (1.0 if v > 0 else -1.0 if v < 0 else 0.0)
    return (v, -(mode.c_i / mass) * v - (mode.c_f / mass) * abs(v) * v - friction
            - w * w * x - mode.alpha * x ** 3 + force)


def _mode_velocity(mode: Mode, case: Case) -> np.ndarray:
    """Velocity of one mode at the case's samples, m/s."""
    n = int(round(case.duration * case.fs))
    t = np.arange(n) / case.fs
    edges = sorted({0.0, t[-1], *(s for s, _, _ in case.impulses),
                    *(s + w for s, w, _ in case.impulses)})
    edges = [e for e in edges if 0.0 <= e <= t[-1]]
    y = np.array([mode.x0, 0.0])
    v = np.empty(n)
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = np.flatnonzero((t >= lo) & (t < hi))
        sol = solve_ivp(lambda s, yy: _rhs(mode, case.mass, case.impulses, s, yy), (lo, hi), y,
                        t_eval=np.append(t[sel], hi), method="DOP853", rtol=1e-10,
                        atol=1e-14, max_step=0.05 / mode.frequency)
        v[sel] = sol.y[1][:-1]
        y = sol.y[:, -1]
    v[-1] = y[1]
    return v


@functools.lru_cache(maxsize=64)
def clean_record(case: Case) -> np.ndarray:
    """The case's noise-free velocity record, m/s (cached: every trial adds its own noise)."""
    return np.sum([_mode_velocity(m, case) for m in case.modes], axis=0)


def trial(case: Case, seed: int) -> np.ndarray:
    """One noisy realisation of the case's record."""
    clean = clean_record(case)
    rng = np.random.default_rng(seed)
    return clean + case.noise * float(np.max(np.abs(clean))) * rng.standard_normal(clean.size)


# ----------------------------------------------------------------------------- the matrix
def sdof_grid() -> list[Case]:
    """Mode 2 of the wet beam released from rest: noise, rate, duration and amplitude."""
    cases = []
    for noise in (0.001, 0.01, 0.03):
        for fs in (500.0, 10000.0):
            for duration in (1.0, 6.0):
                for x0 in (0.5e-3, 2e-3):
                    cases.append(Case(
                        f"quadratic, noise {100 * noise:g} %, {fs:g} Hz, {duration:g} s, "
                        f"x0 {1e3 * x0:g} mm",
                        (Mode(WET_F, c_f=WET_C_F, x0=x0),), fs=fs, duration=duration,
                        noise=noise, tags=(f"noise={noise}",)))
    return cases


def other_cases() -> list[Case]:
    """Duffing, two modes, Coulomb and impulse trains."""
    w = 2.0 * math.pi * WET_F
    x0 = 1e-3
    hard = 0.3 * 4.0 * w * w / (3.0 * x0 * x0)        # 3 alpha x0^2 / (4 w^2) = 0.3
    cases = [
        Case("Duffing hardening (viscous)", (Mode(WET_F, alpha=hard, x0=x0),), duration=4.0,
             law="viscous"),
        Case("Duffing softening (viscous)", (Mode(WET_F, alpha=-0.4 * hard, x0=x0),),
             duration=4.0, law="viscous"),
        Case("two modes, ratio 1.3", (Mode(WET_F, c_f=WET_C_F, x0=1e-3),
                                      Mode(1.3 * WET_F, c_i=1.0, x0=0.5e-3)), duration=4.0),
        Case("two modes, ratio 2.0", (Mode(WET_F, c_f=WET_C_F, x0=1e-3),
                                      Mode(2.0 * WET_F, c_i=1.0, x0=0.3e-3)), duration=4.0),
        Case("viscous + Coulomb", (Mode(WET_F, c_i=0.3, friction=0.4, x0=1e-3),),
             duration=3.0, law="coulomb"),
    ]
    for spacing in (0.5, 1.0, 2.0):
        count = int(6.0 // spacing)
        impulses = tuple((0.1 + k * spacing, 0.01, 1500.0 * (1.0 - 0.5 * k / count))
                         for k in range(count))
        cases.append(Case(f"impulse train, {spacing:g} s apart", (Mode(WET_F, c_f=WET_C_F),),
                          duration=0.1 + count * spacing, impulses=impulses))
    return cases


def matrix() -> list[Case]:
    """Every case of ``make validate``."""
    return sdof_grid() + other_cases()
