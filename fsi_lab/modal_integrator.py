"""Fixed-step RK4 integration of the modal equations (Eq. 20) under sampled base acceleration.

Divided by (mu + M), the equations of :mod:`fsi_lab.beam` read, for n = 1..N::

    q_n'' = -omega_n^2 q_n - r_n q_n' - D_n(q') - p_n a(t)

with the linear damping rate r_n (C_i / (mu + M) or 2 zeta_n omega_n), the participation
p_n = int W_n / b and the quadratic damping D_n: ``(C_f / (mu + M)) |q_n'| q_n'`` (the paper's
per-mode approximation) or its Galerkin projection
``(C_f / (mu + M)) (1/b) int_0^L |w'| w' W_n dx`` with ``w' = sum_m W_m q_m'`` (Gauss-Legendre
quadrature; this couples the modes).

Excitation model: the base acceleration is known at the sample times t_k = k / fs and is taken
as **linear between samples** (a first-order hold). One RK4 step goes from t_{k-1} to t_k; its
half-step stages use (a_{k-1} + a_k) / 2. The integrator therefore solves the ODE driven by the
piecewise-linear excitation to fourth order, and needs no look-ahead: the output at t_k depends
on samples up to k only, so splitting a record into blocks gives bit-identical results.

The base velocity and displacement (for the absolute quantities) are integrated with the same
steps, which is exact for a piecewise-linear acceleration; both start at zero unless set.

The loop over steps is compiled with numba (``cache=True``: the first call in a fresh
environment compiles for a few seconds; later processes load the cache).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from fsi_lab.beam import BeamModel
from fsi_lab.errors import ParameterError
from fsi_lab.modal_step import MAX_OMEGA_DT, check_step  # noqa: F401 - this module's interface

#: Names of the arrays :meth:`ModalSimulator.advance` can return, each (n_samples, n_points).
OUTPUTS = ("displacement", "velocity", "acceleration",
           "absolute_displacement", "absolute_velocity", "absolute_acceleration")
#: Units of those arrays.
UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2",
         "absolute_displacement": "m", "absolute_velocity": "m/s",
         "absolute_acceleration": "m/s^2", "modal_displacement": "m", "modal_velocity": "m/s"}


# --------------------------------------------------------------------------- compiled kernels
@njit(cache=True, inline="always")
def _rhs(q, v, a, omega2, lin, qdiag, quad, part, gshape, gweight, out):
    """Modal accelerations q'' for state (q, v) and base acceleration a, written into ``out``."""
    n = q.shape[0]
    for i in range(n):
        out[i] = -omega2[i] * q[i] - lin[i] * v[i] - qdiag * abs(v[i]) * v[i] - part[i] * a
    for j in range(gshape.shape[0]):
        s = 0.0
        for i in range(n):
            s += gshape[j, i] * v[i]
        f = quad * abs(s) * s
        for i in range(n):
            out[i] -= f * gweight[j, i]


@njit(cache=True)
def _run(acc, a_prev, first, h, q, v, base, omega2, lin, qdiag, quad, part, gshape, gweight, shapes,
         disp, vel, accel, adisp, avel, aacc, mq, mv):
    """Advance over the samples ``acc``; fill the outputs (empty arrays are skipped).

    Returns (last sample used, index of the first non-finite sample or -1).
    """
    n = q.shape[0]
    npts = shapes.shape[0]
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tq = np.empty(n)
    tv = np.empty(n)
    v2 = np.empty(n)
    v3 = np.empty(n)
    qdd = np.empty(n)
    want_d = disp.shape[0] > 0
    want_v = vel.shape[0] > 0
    want_a = accel.shape[0] > 0
    want_ad = adisp.shape[0] > 0
    want_av = avel.shape[0] > 0
    want_aa = aacc.shape[0] > 0
    want_m = mq.shape[0] > 0
    if not first:
        _rhs(q, v, a_prev, omega2, lin, qdiag, quad, part, gshape, gweight, qdd)
    for s in range(acc.shape[0]):
        a1 = acc[s]
        if not (first and s == 0):
            a0 = a_prev
            am = 0.5 * (a0 + a1)
            half = 0.5 * h
            # k1 = f(t, y): its velocity part is qdd from the previous sample (same state and a).
            for i in range(n):
                k1[i] = qdd[i]
                tq[i] = q[i] + half * v[i]
                tv[i] = v[i] + half * k1[i]
                v2[i] = tv[i]
            _rhs(tq, tv, am, omega2, lin, qdiag, quad, part, gshape, gweight, k2)
            for i in range(n):
                tq[i] = q[i] + half * v2[i]
                tv[i] = v[i] + half * k2[i]
                v3[i] = tv[i]
            _rhs(tq, tv, am, omega2, lin, qdiag, quad, part, gshape, gweight, k3)
            for i in range(n):
                tq[i] = q[i] + h * v3[i]
                tv[i] = v[i] + h * k3[i]
            _rhs(tq, tv, a1, omega2, lin, qdiag, quad, part, gshape, gweight, k4)
            for i in range(n):
                q[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + tv[i])
                v[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            base[1] += h * base[0] + h * h / 6.0 * (2.0 * a0 + a1)
            base[0] += 0.5 * h * (a0 + a1)
        a_prev = a1
        _rhs(q, v, a1, omega2, lin, qdiag, quad, part, gshape, gweight, qdd)
        check = 0.0
        for i in range(n):
            check += q[i] + v[i]
        if not math.isfinite(check):
            return a_prev, s
        for p in range(npts):
            d = 0.0
            ve = 0.0
            ac = 0.0
            for i in range(n):
                d += shapes[p, i] * q[i]
                ve += shapes[p, i] * v[i]
                ac += shapes[p, i] * qdd[i]
            if want_d:
                disp[s, p] = d
            if want_v:
                vel[s, p] = ve
            if want_a:
                accel[s, p] = ac
            if want_ad:
                adisp[s, p] = d + base[1]
            if want_av:
                avel[s, p] = ve + base[0]
            if want_aa:
                aacc[s, p] = ac + a1
        if want_m:
            for i in range(n):
                mq[s, i] = q[i]
                mv[s, i] = v[i]
    return a_prev, -1


# --------------------------------------------------------------------------- checks
def _check_excitation(acc: Any, start_time: float, sample_rate: float) -> np.ndarray:
    a = np.asarray(acc, dtype=float)
    if a.ndim != 1:
        raise ParameterError(
            f"base acceleration: got an array of shape {a.shape}; expected a 1-D block of "
            f"samples in m/s^2")
    finite = np.isfinite(a)
    if not finite.all():
        i = int(np.argmin(finite))
        raise ParameterError(
            f"base acceleration: sample {i} of the block (t = {start_time + i / sample_rate:g} s)"
            f" is {float(a[i])!r}; expected finite values in m/s^2")
    return np.ascontiguousarray(a)


# --------------------------------------------------------------------------- simulator
class ModalSimulator:
    """Stateful simulation of a :class:`~fsi_lab.beam.BeamModel` under base acceleration.

    Parameters
    ----------
    model
        The beam, its modes and damping.
    sample_rate
        Sample rate of the excitation blocks and of the outputs, Hz. One RK4 step per sample.
    points_m
        Positions along the beam where outputs are reconstructed, m from the clamp
        (0 <= x <= L), shape ``(n_points,)``.
    outputs
        Which of :data:`OUTPUTS` :meth:`advance` returns (all by default).
    modal
        Also return ``"modal_displacement"`` and ``"modal_velocity"``, (n_samples, modes).
    galerkin_points
        Gauss-Legendre points for the Galerkin projection (``damping.projection ==
        "galerkin"`` only).

    Raises
    ------
    ParameterError
        Sample rate too low for the highest mode (see :func:`check_step`), points off the beam,
        unknown output name.

    Notes
    -----
    The state is q = q' = 0 and base velocity = displacement = 0 at the first sample (t = 0) unless
    :meth:`set_state` says otherwise; the first output sample is that state.
    """

    def __init__(self, model: BeamModel, sample_rate: float, points_m: Any, *,
                 outputs: tuple[str, ...] = OUTPUTS, modal: bool = False,
                 galerkin_points: int = 64) -> None:
        if not isinstance(model, BeamModel):
            raise ParameterError(
                f"model: got {type(model).__name__}; expected fsi_lab.beam.BeamModel")
        check_step(model, sample_rate)
        unknown = [o for o in outputs if o not in OUTPUTS]
        if unknown:
            raise ParameterError(
                f"outputs: unknown {unknown[0]!r}; expected some of {', '.join(OUTPUTS)}")
        points = np.atleast_1d(np.asarray(points_m, dtype=float))
        if points.ndim != 1 or points.size == 0:
            raise ParameterError(
                f"points_m: got shape {points.shape}; expected a 1-D list of positions in m")
        self.model = model
        self.sample_rate = float(sample_rate)
        self.points = points
        self.outputs = tuple(outputs)
        self.modal = bool(modal)
        self._shapes = np.ascontiguousarray(model.mode_shapes(points))
        self._omega2 = model.natural_frequencies_rad ** 2
        self._lin = np.ascontiguousarray(model.linear_damping_rates, dtype=float)
        self._quad = float(model.quadratic_damping_rate)
        self._part = np.ascontiguousarray(model.participation)
        n = model.modes
        if model.damping.projection == "galerkin" and self._quad > 0:
            if isinstance(galerkin_points, bool) or not isinstance(galerkin_points, int) \
                    or galerkin_points < 2:
                raise ParameterError(
                    f"galerkin_points: got {galerkin_points!r}; expected an integer >= 2")
            xg, wg = np.polynomial.legendre.leggauss(galerkin_points)
            x = 0.5 * model.length * (xg + 1.0)
            shape = model.mode_shapes(x)
            self._gshape = np.ascontiguousarray(shape)
            self._gweight = np.ascontiguousarray(
                (0.5 * model.length * wg / model.norm)[:, None] * shape)
            self._qdiag = 0.0
        else:
            self._gshape = np.zeros((0, n))
            self._gweight = np.zeros((0, n))
            self._qdiag = self._quad
        self.reset()

    # ---------------------------------------------------------------- state
    def reset(self) -> None:
        """Back to rest at t = 0 (q = q' = 0, base at rest)."""
        n = self.model.modes
        self._q = np.zeros(n)
        self._v = np.zeros(n)
        self._base = np.zeros(2)  # base velocity m/s, base displacement m
        self._a_prev = 0.0
        self._samples = 0

    def set_state(self, q: Any = None, v: Any = None, base_velocity: float | None = None,
                  base_displacement: float | None = None) -> None:
        """Set the state at the next output sample (before the first :meth:`advance`: t = 0).

        Parameters
        ----------
        q, v
            Modal displacements (m) and velocities (m/s), shape ``(modes,)``.
        base_velocity, base_displacement
            Base motion, m/s and m.
        """
        n = self.model.modes
        for name, value in (("q", q), ("v", v)):
            if value is None:
                continue
            arr = np.asarray(value, dtype=float)
            if arr.shape != (n,) or not np.all(np.isfinite(arr)):
                raise ParameterError(
                    f"{name}: got {value!r}; expected {n} finite modal values")
            setattr(self, "_" + name, arr.copy())
        for i, value in ((0, base_velocity), (1, base_displacement)):
            if value is not None:
                if not math.isfinite(value):
                    raise ParameterError(f"base state: got {value!r}; expected a finite number")
                self._base[i] = float(value)

    @property
    def state(self) -> dict[str, Any]:
        """Current state (copies): ``q`` (m), ``v`` (m/s), ``base_velocity``,
        ``base_displacement``, ``time`` of the last output sample (s; -dt before any)."""
        return {"q": self._q.copy(), "v": self._v.copy(),
                "base_velocity": float(self._base[0]), "base_displacement": float(self._base[1]),
                "time": (self._samples - 1) / self.sample_rate}

    @property
    def samples_done(self) -> int:
        """Number of output samples produced since the last reset."""
        return self._samples

    # ---------------------------------------------------------------- integration
    def advance(self, base_acceleration: Any) -> dict[str, np.ndarray]:
        """Integrate over the next block of base-acceleration samples.

        Parameters
        ----------
        base_acceleration
            Base acceleration w_b'' at the next ``n_samples`` sample times, m/s^2, 1-D.

        Returns
        -------
        dict of numpy.ndarray
            For each requested output name, an array ``(n_samples, n_points)`` at the same sample
            times (units in :data:`UNITS`); relative quantities are with respect to the base,
            absolute ones add the base motion. With ``modal=True`` also ``modal_displacement``
            and ``modal_velocity`` (n_samples, modes).

        Raises
        ------
        ParameterError
            Non-finite or non-1-D samples (checked before integrating); the state becoming
            non-finite (quadratic damping too stiff for the step at this amplitude).
        """
        acc = _check_excitation(base_acceleration, self._samples / self.sample_rate,
                                self.sample_rate)
        ns = acc.shape[0]
        npts = self.points.shape[0]
        n = self.model.modes
        # One allocation for all outputs (returned as views): much cheaper than one per output
        # when blocks are large, because the allocator returns a single block to the system.
        block = np.empty((len(self.outputs), ns, npts))
        empty = np.zeros((0, npts))
        arrays = {name: block[self.outputs.index(name)] if name in self.outputs else empty
                  for name in OUTPUTS}
        modal = np.empty((2 if self.modal else 0, ns, n))
        mq, mv = (modal[0], modal[1]) if self.modal else (np.zeros((0, n)), np.zeros((0, n)))
        if ns == 0:
            result = {k: arrays[k] for k in self.outputs}
        else:
            a_prev, bad = _run(acc, self._a_prev, self._samples == 0, 1.0 / self.sample_rate,
                               self._q, self._v, self._base, self._omega2, self._lin,
                               self._qdiag, self._quad, self._part, self._gshape,
                               self._gweight, self._shapes,
                               *(arrays[k] for k in OUTPUTS), mq, mv)
            if bad >= 0:
                t = (self._samples + bad) / self.sample_rate
                raise ParameterError(
                    f"the modal state became non-finite at t = {t:g} s: the quadratic damping "
                    f"C_f |q'| = {self.model.damping.c_f:g} |q'| is too stiff for a step of "
                    f"1/{self.sample_rate:g} s at this amplitude; raise the sample rate or lower "
                    f"the excitation (call reset() before reusing this simulator)")
            self._a_prev = float(a_prev)
            self._samples += ns
            result = {k: arrays[k] for k in self.outputs}
        if self.modal:
            result["modal_displacement"] = mq
            result["modal_velocity"] = mv
        return result


def simulate(model: BeamModel, base_acceleration: Any, sample_rate: float, points_m: Any,
             **options: Any) -> dict[str, np.ndarray]:
    """One-shot simulation from rest: ``ModalSimulator(...).advance(base_acceleration)``.

    ``options`` are passed to :class:`ModalSimulator`.
    """
    return ModalSimulator(model, sample_rate, points_m, **options).advance(base_acceleration)
