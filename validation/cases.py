"""Records with known truth for the validation matrix (``make validate``) and its test slice.

Every record is integrated independently of fsi-lab's own integrators, at a relative tolerance
of 1e-10 (far tighter than any figure validated), piece by piece between the edges of the
impulses that excite it: by ODEPACK's LSODA (scipy's ``odeint``), and where friction's sign
changes end a piece, by scipy's DOP853 with its events. Noise is added per trial (white, RMS a
fraction of the record's largest value), so one simulation serves every trial of a case.

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
from scipy.integrate import odeint, solve_ivp

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
        The damping law the record follows (``"quadratic"``, ``"viscous"``, ``"coulomb"``,
        ``"quadratic_coulomb"``).
    expect
        ``"number"``: C_i and C_f within the targets (or warned); ``"refusal"``: the record
        holds no usable free decay, and the right answer is a clear refusal.
    bench
        For a row of the simulated wet bench (:mod:`validation.bench`): the ``--set``
        overrides of profiles/wet-beam-sim.toml; ``modes`` then holds mode 2's truth only.
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
    expect: str = "number"
    bench: tuple[str, ...] = ()

    @property
    def truth(self) -> Mode:
        return self.modes[0]

    @property
    def second_truth(self) -> float:
        """The truth of the law's second coefficient, the matrix's C_f column: C_f (kg/m^2)
        of the quadratic laws, the friction force per length (N/m) of the Coulomb law; 0 for
        the viscous law, which has none."""
        if self.law == "coulomb":
            return self.mass * self.truth.friction
        return self.truth.c_f if self.law in ("quadratic", "quadratic_coulomb") else 0.0


def _force(mode: Mode, impulses, t: float) -> float:
    """The impulses' force on the mode per unit mass, m/s^2."""
    force = 0.0
    for start, width, peak in impulses:
        if start <= t < start + width:
            force += mode.gain * peak * math.sin(math.pi * (t - start) / width)
    return force


def _rhs(mode: Mode, mass: float, impulses, sliding: float, t: float,
         y: np.ndarray) -> tuple[float, float]:
    """The oscillator with the friction's direction held at ``sliding`` (+1, -1 or 0)."""
    x, v = y
    w = 2.0 * math.pi * mode.frequency
    return (v, -(mode.c_i / mass) * v - (mode.c_f / mass) * abs(v) * v
            - mode.friction * sliding - w * w * x - mode.alpha * x ** 3
            + _force(mode, impulses, t))


def _spring(mode: Mode, impulses, t: float, x: float) -> float:
    """Every force but damping and friction at displacement ``x``, per unit mass, m/s^2."""
    w = 2.0 * math.pi * mode.frequency
    return -w * w * x - mode.alpha * x ** 3 + _force(mode, impulses, t)


def _solve(mode: Mode, case: Case, lo: float, hi: float, y: np.ndarray,
           times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Velocity at ``times`` in [lo, hi) and the state at ``hi``.

    Friction's sign changes with the velocity's: each stretch of one sliding direction is
    integrated on its own (a smooth right-hand side), ended by the event v = 0; there the mass
    sticks while the other forces stay within the friction force, else it slides on (a stuck
    mass stays at rest to the end of the piece: no case has friction and impulses together).
    """
    v = np.empty(times.size)
    if mode.friction == 0.0:
        # One smooth piece: LSODA's steps run in compiled code, DOP853's in Python (the
        # matrix's 40 records took 17.6 s, against 3.7 s; they agree to 6e-8 of their
        # largest value).
        sel = np.flatnonzero((times >= lo) & (times < hi))
        # (a sample at ``lo``, or rounded a few ulps past it, is the start itself: LSODA
        # refuses output times closer together than its resolution)
        inside = times[sel] - lo > 1e-6 / case.fs
        grid = np.concatenate(([lo], times[sel[inside]], [hi]))
        out, info = odeint(lambda yy, s: _rhs(mode, case.mass, case.impulses, 0.0, s, yy), y,
                           grid, rtol=1e-10, atol=1e-14, mxstep=10 ** 7, full_output=True)
        if info["message"] != "Integration successful.":
            raise RuntimeError(f"{case.name}: LSODA failed from {lo} s: {info['message']}")
        v[sel[~inside]] = y[1]
        v[sel[inside]] = out[1:-1, 1]
        return v, out[-1]
    step = 0.05 / mode.frequency
    t, y = lo, np.array(y, dtype=float)
    while True:
        sliding = float(np.sign(y[1]))
        if sliding == 0.0 and mode.friction > 0.0:
            push = _spring(mode, case.impulses, t, y[0])
            if abs(push) <= mode.friction:      # stuck: at rest until the forces grow
                sel = times >= t
                v[sel] = 0.0
                return v, np.array([y[0], 0.0])
            sliding = float(np.sign(push))
        events = None
        if mode.friction > 0.0:
            def stop(s, yy, sliding=sliding, begin=t):
                return yy[1] if s > begin else sliding
            stop.terminal, stop.direction = True, -sliding
            events = stop
        sel = (times >= t) & (times < hi)
        sol = solve_ivp(lambda s, yy, sliding=sliding: _rhs(mode, case.mass, case.impulses,
                                                            sliding, s, yy),
                        (t, hi), y, t_eval=np.append(times[sel], hi) if events is None
                        else times[sel], method="DOP853", rtol=1e-10, atol=1e-14,
                        max_step=step, events=events, dense_output=events is not None)
        if events is None or sol.status == 0:
            if events is None:
                v[sel] = sol.y[1][:-1]
                return v, sol.y[:, -1]
            v[sel] = sol.y[1]
            return v, sol.sol(hi)
        stop_t = float(sol.t_events[0][0])
        sel_done = sel & (times < stop_t)
        v[sel_done] = sol.sol(times[sel_done])[1] if np.any(sel_done) else v[sel_done]
        t, y = stop_t, np.array([float(sol.y_events[0][0][0]), 0.0])


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
        v[sel], y = _solve(mode, case, lo, hi, y, t[sel])
    v[-1] = y[1]
    return v


def harmonic_balance_hz(mode: Mode, mass: float, amplitude: np.ndarray) -> np.ndarray:
    """The backbone of a damped mode by harmonic balance, Hz, at displacement amplitudes
    ``amplitude`` (m): ``sqrt(w^2 - a^2) / (2 pi)`` with ``w^2 = w0^2 + 3 alpha A^2 / 4`` (the
    undamped backbone, within 0.25 % of the exact, elliptic one up to ``3 alpha A^2 / (4 w0^2) =
    0.5``) and ``a = c_i / (2 m) + 4 c_f w A / (3 pi m)`` the decay rate of the averaged envelope
    (1/s) for the mass per length ``mass`` (kg/m): the damped frequency of a decay at that
    rate."""
    amp = np.asarray(amplitude, dtype=float)
    w2 = (2.0 * math.pi * mode.frequency) ** 2 + 0.75 * mode.alpha * amp * amp
    a = mode.c_i / (2.0 * mass) + 4.0 * mode.c_f * np.sqrt(w2) * amp / (3.0 * math.pi * mass)
    return np.sqrt(w2 - a * a) / (2.0 * math.pi)


@functools.lru_cache(maxsize=64)
def clean_record(case: Case) -> np.ndarray:
    """The case's noise-free velocity record, m/s (cached: every trial adds its own noise); a
    bench row's tip velocity and base acceleration (:func:`.bench.bench_record`)."""
    if case.bench:
        from validation.bench import bench_record

        return bench_record(case)
    return np.sum([_mode_velocity(m, case) for m in case.modes], axis=0)


def trial(case: Case, seed: int) -> np.ndarray:
    """One noisy realisation of the case's record (each row of a bench record its own)."""
    clean = clean_record(case)
    rng = np.random.default_rng(seed)
    scale = case.noise * np.max(np.abs(clean), axis=-1, keepdims=True)
    return clean + scale * rng.standard_normal(clean.shape)


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
        # The wet beam's fluid damping on a hardening mode: the large cycles, where C_f shows,
        # are those whose frequency the stiffness moves most.
        Case("Duffing hardening, quadratic damping", (Mode(WET_F, c_f=WET_C_F, alpha=hard,
                                                          x0=x0),), duration=4.0),
        # A strong softening (its frequency 12 % down at the release): the model's crossings,
        # a few per cent off in frequency at first, drift by half a period in a few cycles.
        Case("Duffing strong softening, quadratic damping",
             (Mode(WET_F, c_f=WET_C_F, alpha=-0.75 * hard, x0=x0),), duration=4.0),
        Case("two modes, ratio 1.3", (Mode(WET_F, c_f=WET_C_F, x0=1e-3),
                                      Mode(1.3 * WET_F, c_i=1.0, x0=0.5e-3)), duration=4.0),
        Case("two modes, ratio 2.0", (Mode(WET_F, c_f=WET_C_F, x0=1e-3),
                                      Mode(2.0 * WET_F, c_i=1.0, x0=0.3e-3)), duration=4.0),
        Case("viscous + Coulomb (C_f column: friction force)",
             (Mode(WET_F, c_i=0.3, friction=0.4, x0=1e-3),),
             duration=3.0, law="coulomb"),
        # The wet beam with a clamp that rubs: the fluid's damping and dry friction together.
        Case("quadratic + Coulomb, 2 mm (three-term law)",
             (Mode(WET_F, c_f=WET_C_F, friction=0.1, x0=2e-3),),
             duration=3.0, law="quadratic_coulomb"),
        # Other modes than the wet beam's second: a high one sampled at 10 samples per cycle,
        # and a low one whose linear damping alone is 7.7 % of critical.
        Case("quadratic, noise 1 %, 200 Hz mode at 2000 Hz, 2 s, x0 0.1 mm",
             (Mode(200.0, c_f=WET_C_F, x0=1e-4),), fs=2000.0, duration=2.0),
        Case("quadratic, noise 1 %, 5 Hz mode at 500 Hz, 10 s, x0 2 mm",
             (Mode(5.0, c_f=WET_C_F, x0=2e-3),), fs=500.0, duration=10.0),
    ]
    for spacing in (0.25, 0.5, 1.0, 2.0):
        cases.append(impulse_train(spacing))
    # Impulses 2 cycles apart: each restarts the motion before its decay can be told from the
    # next (the identification must refuse, naming the spacing it needs).
    cases.append(impulse_train(0.12, duration=3.0, expect="refusal"))
    # Impulses 40 times stronger: 22 mm at the tip, where the quadratic drag damps the first
    # half cycle past critical (an equivalent damping ratio of about 2); the decay falls into
    # the 1 % noise (of its peak) within a few cycles and no mode rings freely.
    cases.append(impulse_train(1.0, peak=1500.0, expect="refusal",
                               name="impulse train, 1 s apart, overdriven (22 mm)"))
    return cases


#: Peak acceleration (m/s^2, per unit mass) of the trains' first 10 ms half-sine impulse: the
#: wet beam's mode 2 then starts its decay at about 0.19 m/s (1.8 mm), the SDOF grid's range.
TRAIN_PEAK = 40.0


def impulse_train(spacing: float, *, peak: float = TRAIN_PEAK, duration: float = 6.0,
                  expect: str = "number", name: str | None = None) -> Case:
    """The wet beam's mode 2 struck by half-sine impulses ``spacing`` s apart over about
    ``duration`` s, their peaks falling from ``peak`` to half of it (decays from several
    amplitudes, as the impulse-train excitation's descending order gives)."""
    count = int(round(duration / spacing))
    impulses = tuple((0.1 + k * spacing, 0.01, peak * (1.0 - 0.5 * k / count))
                     for k in range(count))
    return Case(name or f"impulse train, {spacing:g} s apart", (Mode(WET_F, c_f=WET_C_F),),
                duration=0.1 + count * spacing, impulses=impulses, expect=expect)


def matrix() -> list[Case]:
    """Every case of ``make validate``."""
    from validation.bench import bench_cases

    return sdof_grid() + other_cases() + bench_cases()
