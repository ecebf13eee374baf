"""Damping laws of one mode, and their fit to the extrema of its free decays.

One mode of the structure, per unit modal mass and in the coordinate that is measured, is the
oscillator::

    x'' + 2 a x' + beta |x'| x' + gamma sgn(x') + w0^2 x + alpha x^3 = 0

The candidate damping laws (:data:`LAWS`) keep some of the three damping terms:

``"viscous"``
    ``a`` only (1/s): the envelope falls exponentially, ``ln A`` is linear in time.
``"quadratic"``
    ``a`` and ``beta`` (1/unit of x): the paper's linear + fluid damping
    ``(C_i + C_f |q'|) q'`` per length, with ``a = C_i / (2 m)`` and ``beta = C_f / m``
    (``m = mu + M``); the averaged envelope obeys ``dA/dt = -a A - b A^2``.
``"coulomb"``
    ``a`` and ``gamma`` (unit of x'' ): dry friction; with ``a = 0`` the envelope falls
    linearly and the motion stops.
``"quadratic_coulomb"``
    ``a``, ``beta`` and ``gamma``: the fluid's damping with dry friction beside it (a clamp
    or a joint that rubs); fitted with either two-term law alone, the friction is read as
    viscous damping, or the fluid term as friction.

Why not fit the averaged envelope's closed form: the averaging is first order in the damping.
In water the fluid damping reaches damping ratios of 10 to 25 % over the first cycles, where
the closed form misses the peaks by up to a few percent and biases ``a`` and ``beta`` by as
much. :func:`extremum_sequence` instead integrates the oscillator itself from one extremum to
the next (fourth-order Runge-Kutta, :data:`STEPS_PER_HALF_CYCLE` steps per half cycle, its
frequency and damping matched so that the steps' own phase lag and amplitude loss do not add
up over thousands of cycles: :func:`_rk4_matched`), which follows an exact simulation's
extrema to about 1e-5, at any damping.

:func:`fit_law` fits a law to the extrema of one or more free decays of the mode (common law
parameters, one start amplitude per decay) by generalised least squares: the errors of
extrema measured on a band-limited signal are correlated over about one over the bandwidth,
and a ``correlation`` function of the time lag (:func:`fsi_lab.dsp.filters.noise_correlation`)
whitens them; the covariance of the parameters, their standard errors and the information
criteria follow from the whitened residuals. The fit's Jacobian is exact, not a finite
difference: :func:`extremum_derivatives` carries the derivatives of the state along the same
Runge-Kutta steps (the tangent of the discrete model, extremum interpolation and friction stops
included), for about the cost of one integration. :func:`compare_laws` ranks fits of several
laws by the corrected Akaike criterion. :func:`fluid_power` tests, on a quadratic fit,
whether its fluid term grows with the square of the velocity or with another power.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numba
import numpy as np
import scipy.linalg
import scipy.optimize as sopt
import scipy.stats as sstats

from fsi_lab.dsp._signal import fail

#: Parameters of each damping law, in order.
LAWS: dict[str, tuple[str, ...]] = {
    "viscous": ("a",),
    "quadratic": ("a", "beta"),
    "coulomb": ("a", "gamma"),
    "quadratic_coulomb": ("a", "beta", "gamma"),
}
#: Units of the law parameters, with U the unit of x (m for displacement).
PARAM_UNITS = {"a": "1/s", "beta": "1/U", "gamma": "U/s^2"}
#: Quantities whose extrema can be followed: the measured coordinate or its velocity.
QUANTITIES = ("displacement", "velocity")
#: Runge-Kutta steps per half cycle of the linear oscillator (the extrema then follow the
#: exact motion to about 3e-6 of the start amplitude).
STEPS_PER_HALF_CYCLE = 24
#: Widest band (in extrema) of the whitened errors' correlation.
MAX_BAND = 200
#: Relative resolution of a measured extremum: the information criteria see no finer misfit,
#: and the covariance of a fit takes no smaller error.
RESOLUTION = 1e-6
#: Above this many elements (extrema x parameters), a fit's Jacobian is reduced decay by decay
#: (:func:`_reduced`) rather than held whole.
DENSE_JACOBIAN = 1 << 21
#: Within this much AICc of the best, the law with the fewest parameters is preferred.
AICC_TIE = 2.0
#: A law with dry friction is preferred only where the friction gives at least this share of
#: its decay rate at the smallest extremum fitted: a friction force that makes a small part of
#: the damping even there (a misfit at the noise floor, a filter's edge) is no law of its own
#: (nor is one whose other terms are negative beyond their noise: friction offset by negative
#: damping describes the noise of a lightly damped decay, not a rubbing structure).
FRICTION_SHARE = 0.2
#: ... where "beyond their noise" is this many standard errors.
NEGATIVE_Z = 2.0
#: ... and only where its AICc is lower than every law's without friction by more than this:
#: a friction force at the noise floor of a record without one wins by 2 to 5 in about 1 of
#: 40 records (a misfit of the smallest extrema looks like friction), one that is there by
#: tens.
FRICTION_GAIN = 6.0
#: A model extremum larger than this multiple of the start amplitude ends the sequence (a law
#: with negative damping grows; the fit then moves away from it).
MAX_GROWTH = 1e3


# ----------------------------------------------------------------------------- kernel
@numba.njit(cache=True)
def _accel(x, v, s, w0sq, alpha, a2, beta, gamma):
    return -w0sq * x - alpha * x * x * x - a2 * v - beta * abs(v) * v - gamma * s


@numba.njit(cache=True)
def _rk4(x, v, s, h, w0sq, alpha, a2, beta, gamma):
    k1x = v
    k1v = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
    k2x = v + 0.5 * h * k1v
    k2v = _accel(x + 0.5 * h * k1x, v + 0.5 * h * k1v, s, w0sq, alpha, a2, beta, gamma)
    k3x = v + 0.5 * h * k2v
    k3v = _accel(x + 0.5 * h * k2x, v + 0.5 * h * k2v, s, w0sq, alpha, a2, beta, gamma)
    k4x = v + h * k3v
    k4v = _accel(x + h * k3x, v + h * k3v, s, w0sq, alpha, a2, beta, gamma)
    return (x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))


@numba.njit(cache=True)
def _rk4_turn(t):
    """Real and imaginary parts of ``R(i t)``, what one Runge-Kutta step of ``w0 h = t`` does to
    the undamped oscillator's complex amplitude."""
    t2 = t * t
    return 1.0 - 0.5 * t2 + t2 * t2 / 24.0, t - t2 * t / 6.0


@numba.njit(cache=True)
def _rk4_matched(w0sq, a2, h):
    """``(w0sq, a2)`` to integrate with so that the Runge-Kutta steps of length ``h`` (s; < 0
    backwards) turn and shrink a linear oscillator of ``w0sq`` (1/s^2) and ``a2`` (1/s) as the
    ODE does. A step of ``theta = w0 h`` turns the undamped motion by ``arg R(i theta)``, about
    ``theta (1 - theta^4 / 120)``, and multiplies its amplitude by ``|R(i theta)|``, about
    ``1 - theta^6 / 144`` (``R``: the method's stability polynomial): at 24 steps per half cycle
    the model's frequency was 2.1e-6 low and its decay rate 2.7e-7 w0 high, which read a
    fitted frequency 2 ppm high and, on a lightly damped mode, ``a`` low by as much (0.4 % of
    C_i at 800 Hz). Integrating with ``w0 kappa``, where ``arg R(i kappa theta) = theta``, and
    the damping less the steps' own loss cancels both to the damping's first order."""
    w0 = math.sqrt(w0sq)
    theta = w0 * abs(h)
    if theta <= 0.0:
        return w0sq, a2
    t = theta
    for _ in range(8):   # Newton on arg R(i t) = theta
        re, im = _rk4_turn(t)
        t2 = t * t
        slope = (re * (1.0 - 0.5 * t2) - im * (-t + t2 * t / 6.0)) / (re * re + im * im)
        step = (math.atan2(im, re) - theta) / slope
        t -= step
        if abs(step) <= 1e-15 * theta:
            break
    re, im = _rk4_turn(t)
    loss = -0.5 * math.log(re * re + im * im) / abs(h)   # amplitude decay rate of the steps, 1/s
    kappa = t / theta
    # forwards the steps add their loss to the damping, backwards they take it away
    return w0sq * kappa * kappa, a2 - 2.0 * loss if h > 0.0 else a2 + 2.0 * loss


@numba.njit(cache=True)
def _hermite_root_of_derivative(p0, p1, m0, m1):
    """Position s in [0, 1] where the cubic Hermite through (p0, m0), (p1, m1) (m scaled to the
    step) has zero slope, and its value there."""
    c3 = 2.0 * p0 - 2.0 * p1 + m0 + m1
    c2 = -3.0 * p0 + 3.0 * p1 - 2.0 * m0 - m1
    c1 = m0
    qa = 3.0 * c3
    qb = 2.0 * c2
    s = 0.5
    if abs(qa) < 1e-300:
        if qb != 0.0:
            s = -c1 / qb
    else:
        disc = qb * qb - 4.0 * qa * c1
        if disc < 0.0:
            disc = 0.0
        r = math.sqrt(disc)
        s1 = (-qb + r) / (2.0 * qa)
        s2 = (-qb - r) / (2.0 * qa)
        s = s1 if 0.0 <= s1 <= 1.0 else s2
    s = min(max(s, 0.0), 1.0)
    return s, ((c3 * s + c2) * s + c1) * s + p0


@numba.njit(cache=True)
def _hermite_root(p0, p1, m0, m1):
    """Position s in [0, 1] where the cubic Hermite through (p0, m0), (p1, m1) crosses zero
    (a few Newton steps from the secant)."""
    c3 = 2.0 * p0 - 2.0 * p1 + m0 + m1
    c2 = -3.0 * p0 + 3.0 * p1 - 2.0 * m0 - m1
    s = p0 / (p0 - p1) if p0 != p1 else 0.5
    for _ in range(8):
        f = ((c3 * s + c2) * s + m0) * s + p0
        d = (3.0 * c3 * s + 2.0 * c2) * s + m0
        if d == 0.0:
            break
        s -= f / d
        s = min(max(s, 0.0), 1.0)
    return s


@numba.njit(cache=True)
def _sequence(x, v, w0, alpha, a2, beta, gamma, count, steps, follow_velocity,
              out_amp, out_time):
    """Fill ``out_amp`` / ``out_time`` with the successive extrema of x (follow_velocity False)
    or v from the state (x, v) at t = 0, itself an extremum; returns how many were found."""
    h = math.pi / w0 / steps
    w0sq, a2 = _rk4_matched(w0 * w0, a2, h)
    s = 1.0 if v > 0.0 else -1.0 if v < 0.0 else (-1.0 if x > 0.0 else 1.0)
    if gamma > 0.0 and v == 0.0 and abs(w0sq * x + alpha * x * x * x) <= gamma:
        out_amp[0] = abs(x)
        out_time[0] = 0.0
        return 1
    start = abs(v) if follow_velocity else abs(x)
    out_amp[0] = start
    out_time[0] = 0.0
    k = 1
    t = 0.0
    acc = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
    limit = (count + 4) * steps * 8
    n = 0
    while k < count and n < limit:
        n += 1
        xn, vn = _rk4(x, v, s, h, w0sq, alpha, a2, beta, gamma)
        hh = h
        if gamma > 0.0 and vn * s < 0.0:
            # The velocity changes sign inside the step: stop at v = 0, where the friction
            # force reverses (or the motion sticks).
            an = _accel(xn, vn, s, w0sq, alpha, a2, beta, gamma)
            frac = _hermite_root(v, vn, acc * h, an * h)
            hh = max(frac * h, 1e-12 * h)
            xn, vn = _rk4(x, v, s, hh, w0sq, alpha, a2, beta, gamma)
            if not follow_velocity:
                out_amp[k] = abs(xn)
                out_time[k] = t + hh
                k += 1
            s = -s
            vn = 0.0
            if abs(w0sq * xn + alpha * xn * xn * xn) <= gamma:
                return k                   # the restoring force cannot overcome friction
            t += hh
            x, v = xn, vn
            acc = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
            continue
        an = _accel(xn, vn, s, w0sq, alpha, a2, beta, gamma)
        if follow_velocity:
            if n > 1 and (acc * an < 0.0 or (acc != 0.0 and an == 0.0)):
                frac, value = _hermite_root_of_derivative(v, vn, acc * h, an * h)
                out_amp[k] = abs(value)
                out_time[k] = t + frac * h
                k += 1
                if abs(value) > MAX_GROWTH * start:
                    return k
        else:
            if gamma <= 0.0 and v * vn < 0.0:
                frac, value = _hermite_root_of_derivative(x, xn, v * h, vn * h)
                out_amp[k] = abs(value)
                out_time[k] = t + frac * h
                k += 1
                if abs(value) > MAX_GROWTH * start:
                    return k
        t += hh
        x, v, acc = xn, vn, an
    return k


# Tangent of the kernel: the derivatives of the extrema :func:`_sequence` finds with respect to
# the law's terms and the start, carried through the same Runge-Kutta steps (the exact
# derivative of the discrete model, not of the ODE). Directions (columns): ``a``, ``beta``,
# ``gamma`` and the start state's own direction (given as its tangent ``X0, V0``).
DIRECTIONS = 4


@numba.njit(cache=True)
def _accel_tangent(x, v, s, xd, vd, j, w0sq, alpha, a2, beta):
    """Derivative of :func:`_accel` along direction ``j`` for a state tangent ``(xd, vd)``."""
    out = -(w0sq + 3.0 * alpha * x * x) * xd - (a2 + 2.0 * beta * abs(v)) * vd
    if j == 0:
        out -= 2.0 * v
    elif j == 1:
        out -= abs(v) * v
    elif j == 2:
        out -= s
    return out


@numba.njit(cache=True)
def _rk4_tangent(x, v, s, h, dirs, xd, vd, hd, w0sq, alpha, a2, beta, gamma, xo, vo):
    """:func:`_rk4`'s step (returned, the same to the bit) and its tangent (state tangents
    ``xd``, ``vd`` and step tangent ``hd`` along each of the directions ``dirs``) into
    ``xo``, ``vo``."""
    k1x = v
    k1v = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
    x2 = x + 0.5 * h * k1x
    v2 = v + 0.5 * h * k1v
    k2x = v2
    k2v = _accel(x2, v2, s, w0sq, alpha, a2, beta, gamma)
    x3 = x + 0.5 * h * k2x
    v3 = v + 0.5 * h * k2v
    k3x = v3
    k3v = _accel(x3, v3, s, w0sq, alpha, a2, beta, gamma)
    x4 = x + h * k3x
    v4 = v + h * k3v
    k4x = v4
    k4v = _accel(x4, v4, s, w0sq, alpha, a2, beta, gamma)
    for j in range(xd.shape[0]):
        dj = dirs[j]
        d1x = vd[j]
        d1v = _accel_tangent(x, v, s, xd[j], vd[j], dj, w0sq, alpha, a2, beta)
        d2x_ = xd[j] + 0.5 * (h * d1x + hd[j] * k1x)
        d2v_ = vd[j] + 0.5 * (h * d1v + hd[j] * k1v)
        d2x = d2v_
        d2v = _accel_tangent(x2, v2, s, d2x_, d2v_, dj, w0sq, alpha, a2, beta)
        d3x_ = xd[j] + 0.5 * (h * d2x + hd[j] * k2x)
        d3v_ = vd[j] + 0.5 * (h * d2v + hd[j] * k2v)
        d3x = d3v_
        d3v = _accel_tangent(x3, v3, s, d3x_, d3v_, dj, w0sq, alpha, a2, beta)
        d4x_ = xd[j] + h * d3x + hd[j] * k3x
        d4v_ = vd[j] + h * d3v + hd[j] * k3v
        d4x = d4v_
        d4v = _accel_tangent(x4, v4, s, d4x_, d4v_, dj, w0sq, alpha, a2, beta)
        xo[j] = xd[j] + h / 6.0 * (d1x + 2.0 * d2x + 2.0 * d3x + d4x) \
            + hd[j] / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        vo[j] = vd[j] + h / 6.0 * (d1v + 2.0 * d2v + 2.0 * d3v + d4v) \
            + hd[j] / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
    return (x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))


@numba.njit(cache=True)
def _hermite_weights(s):
    """Weights of (p0, p1, m0, m1) in the cubic Hermite's value at s."""
    s2 = s * s
    s3 = s2 * s
    return 2.0 * s3 - 3.0 * s2 + 1.0, -2.0 * s3 + 3.0 * s2, s3 - 2.0 * s2 + s, s3 - s2


@numba.njit(cache=True)
def _sequence_tangent(x, v, dirs, xd0, vd0, w0, alpha, a2, beta, gamma, count, steps,
                      follow_velocity, out_amp, out_time, out_d):
    """:func:`_sequence` (the same extrema, to the bit) with ``out_d[k, j]``, the derivative of
    the k-th ``|extremum|`` along direction ``dirs[j]`` (0: ``a``, 1: ``beta``, 2: ``gamma``,
    3: the start), from the start state's tangents ``xd0``, ``vd0`` (per direction)."""
    m = xd0.shape[0]
    friction = -1
    for j in range(m):
        if dirs[j] == 2:
            friction = j
    xd = xd0.copy()
    vd = vd0.copy()
    xnd = np.zeros(m)
    vnd = np.zeros(m)
    hz = np.zeros(m)
    hd = np.zeros(m)
    h = math.pi / w0 / steps
    w0sq, a2 = _rk4_matched(w0 * w0, a2, h)
    s = 1.0 if v > 0.0 else -1.0 if v < 0.0 else (-1.0 if x > 0.0 else 1.0)
    if gamma > 0.0 and v == 0.0 and abs(w0sq * x + alpha * x * x * x) <= gamma:
        out_amp[0] = abs(x)
        out_time[0] = 0.0
        sg = 1.0 if x >= 0.0 else -1.0
        for j in range(m):
            out_d[0, j] = sg * xd[j]
        return 1
    start = abs(v) if follow_velocity else abs(x)
    out_amp[0] = start
    out_time[0] = 0.0
    for j in range(m):
        out_d[0, j] = (1.0 if v >= 0.0 else -1.0) * vd[j] if follow_velocity \
            else (1.0 if x >= 0.0 else -1.0) * xd[j]
    k = 1
    t = 0.0
    acc = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
    limit = (count + 4) * steps * 8
    n = 0
    while k < count and n < limit:
        n += 1
        if gamma <= 0.0 and v != 0.0:
            # Without friction s does not enter the motion; it is the direction the friction
            # term's derivative pushes against (that of gamma -> 0+).
            s = 1.0 if v > 0.0 else -1.0
        xn, vn = _rk4_tangent(x, v, s, h, dirs, xd, vd, hz, w0sq, alpha, a2, beta, gamma, xnd,
                              vnd)
        hh = h
        if gamma > 0.0 and vn * s < 0.0:
            an = _accel(xn, vn, s, w0sq, alpha, a2, beta, gamma)
            frac = _hermite_root(v, vn, acc * h, an * h)
            hh = max(frac * h, 1e-12 * h)
            # d frac from H(frac) = 0 (none when the root sits on a bound of the step).
            c3 = 2.0 * v - 2.0 * vn + acc * h + an * h
            c2 = -3.0 * v + 3.0 * vn - 2.0 * acc * h - an * h
            slope = (3.0 * c3 * frac + 2.0 * c2) * frac + acc * h
            w00, w01, w10, w11 = _hermite_weights(frac)
            free = 0.0 < frac < 1.0 and frac * h > 1e-12 * h and slope != 0.0
            for j in range(m):
                if free:
                    dacc = _accel_tangent(x, v, s, xd[j], vd[j], dirs[j], w0sq, alpha, a2, beta)
                    dan = _accel_tangent(xn, vn, s, xnd[j], vnd[j], dirs[j], w0sq, alpha, a2, beta)
                    dh = w00 * vd[j] + w01 * vnd[j] + h * (w10 * dacc + w11 * dan)
                    hd[j] = -h * dh / slope
                else:
                    hd[j] = 0.0
            xn, vn = _rk4_tangent(x, v, s, hh, dirs, xd, vd, hd, w0sq, alpha, a2, beta, gamma,
                                  xnd, vnd)
            if not follow_velocity:
                out_amp[k] = abs(xn)
                out_time[k] = t + hh
                sg = 1.0 if xn >= 0.0 else -1.0
                for j in range(m):
                    out_d[k, j] = sg * xnd[j]
                k += 1
            s = -s
            vn = 0.0
            if abs(w0sq * xn + alpha * xn * xn * xn) <= gamma:
                return k
            t += hh
            x, v = xn, vn
            for j in range(m):
                xd[j] = xnd[j]
                vd[j] = 0.0
            acc = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
            continue
        an = _accel(xn, vn, s, w0sq, alpha, a2, beta, gamma)
        if gamma <= 0.0 and v * vn < 0.0 and friction >= 0:
            # The friction term reverses where v does, inside the step: its derivative pushes
            # the other way for the rest of the step.
            rest = (1.0 - _hermite_root(v, vn, acc * h, an * h)) * h
            vnd[friction] += 2.0 * s * rest
            xnd[friction] += s * rest * rest
        if follow_velocity:
            if n > 1 and (acc * an < 0.0 or (acc != 0.0 and an == 0.0)):
                frac, value = _hermite_root_of_derivative(v, vn, acc * h, an * h)
                out_amp[k] = abs(value)
                out_time[k] = t + frac * h
                w00, w01, w10, w11 = _hermite_weights(frac)
                sg = 1.0 if value >= 0.0 else -1.0
                for j in range(m):
                    dacc = _accel_tangent(x, v, s, xd[j], vd[j], dirs[j], w0sq, alpha, a2, beta)
                    dan = _accel_tangent(xn, vn, s, xnd[j], vnd[j], dirs[j], w0sq, alpha, a2, beta)
                    out_d[k, j] = sg * (w00 * vd[j] + w01 * vnd[j]
                                        + h * (w10 * dacc + w11 * dan))
                k += 1
                if abs(value) > MAX_GROWTH * start:
                    return k
        else:
            if gamma <= 0.0 and v * vn < 0.0:
                frac, value = _hermite_root_of_derivative(x, xn, v * h, vn * h)
                out_amp[k] = abs(value)
                out_time[k] = t + frac * h
                w00, w01, w10, w11 = _hermite_weights(frac)
                sg = 1.0 if value >= 0.0 else -1.0
                for j in range(m):
                    out_d[k, j] = sg * (w00 * xd[j] + w01 * xnd[j]
                                        + h * (w10 * vd[j] + w11 * vnd[j]))
                k += 1
                if abs(value) > MAX_GROWTH * start:
                    return k
        t += hh
        x, v, acc = xn, vn, an
        for j in range(m):
            xd[j] = xnd[j]
            vd[j] = vnd[j]
    return k


def _start_state(value: float, quantity: str, w0: float, alpha: float, a: float, beta: float,
                 gamma: float) -> tuple[float, float]:
    """State (x, v) at an extremum of ``quantity`` whose value is ``value``."""
    if quantity == "displacement":
        return value, 0.0
    v = value
    s = math.copysign(1.0, v) if v != 0.0 else 0.0
    rhs = -(2.0 * a * v + beta * abs(v) * v + gamma * s)
    x = rhs / (w0 * w0)
    for _ in range(20):                      # w0^2 x + alpha x^3 = rhs
        f = w0 * w0 * x + alpha * x ** 3 - rhs
        d = w0 * w0 + 3.0 * alpha * x * x
        if d <= 0.0:
            break
        step = f / d
        x -= step
        if abs(step) <= 1e-15 * (abs(x) + 1e-300):
            break
    return x, v


def _start_tangent(x: float, v: float, quantity: str, w0: float, alpha: float, a: float,
                   beta: float) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of :func:`_start_state`'s (x, v) along the :data:`DIRECTIONS` (``a``,
    ``beta``, ``gamma``, the start value)."""
    xd, vd = np.zeros(DIRECTIONS), np.zeros(DIRECTIONS)
    if quantity == "displacement":
        xd[3] = 1.0
        return xd, vd
    vd[3] = 1.0
    stiff = w0 * w0 + 3.0 * alpha * x * x
    if stiff > 0.0:
        s = math.copysign(1.0, v) if v != 0.0 else 0.0
        xd[:] = (-2.0 * v, -abs(v) * v, -s, -(2.0 * a + 2.0 * beta * abs(v)))
        xd /= stiff
    return xd, vd


def _law_terms(law: str, params: Sequence[float]) -> tuple[float, float, float]:
    """(a, beta, gamma) of ``law`` with ``params``."""
    values = dict(zip(LAWS[law], params))
    return float(values.get("a", 0.0)), float(values.get("beta", 0.0)), \
        float(values.get("gamma", 0.0))


def _check_law(law: str, params: Sequence[float], func: str) -> None:
    if law not in LAWS:
        raise fail(func, f"law = {law!r}; expected one of {', '.join(LAWS)}")
    if len(params) != len(LAWS[law]):
        raise fail(func, f"the {law} law takes {len(LAWS[law])} parameter(s) "
                         f"({', '.join(LAWS[law])}); {len(params)} given")


def extremum_sequence(law: str, params: Sequence[float], w0: float, start: float, count: int, *,
                      alpha: float = 0.0, quantity: str = "velocity",
                      steps: int = STEPS_PER_HALF_CYCLE) -> tuple[np.ndarray, np.ndarray]:
    """Successive extrema of a free decay of the oscillator with damping ``law``.

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    params
        The law's parameters in the order of :data:`LAWS` (``a`` in 1/s, ``beta`` in 1/U,
        ``gamma`` in U/s^2 for a coordinate x in U).
    w0
        Linear natural angular frequency, rad/s (> 0).
    start
        Value of the first extremum (signed), U for a displacement, U/s for a velocity.
    count
        Number of extrema wanted (the first included).
    alpha
        Cubic stiffness per unit mass, 1/(U^2 s^2) (0: linear).
    quantity
        ``"velocity"`` (extrema of x') or ``"displacement"`` (extrema of x).
    steps
        Runge-Kutta steps per half cycle of the linear oscillator.

    Returns
    -------
    amplitude : numpy.ndarray
        ``|extremum|`` of each half cycle, U or U/s; shorter than ``count`` when the motion
        stops (Coulomb friction) or grows past :data:`MAX_GROWTH` times the start.
    time : numpy.ndarray
        Time of each extremum from the first, s.

    Raises
    ------
    AnalysisError
        Unknown law or quantity, wrong number of parameters, non-finite or non-positive
        ``w0``, ``count < 1``.

    Examples
    --------
    Linear viscous damping: successive extrema fall by ``exp(-a pi / w_d)``.

    >>> import math
    >>> from fsi_lab.dsp.laws import extremum_sequence
    >>> amp, t = extremum_sequence("viscous", [2.0], 2 * math.pi * 10, 1.0, 3,
    ...                            quantity="displacement")
    >>> print(f"{amp[1] / amp[0]:.5f} {math.exp(-2.0 * t[1]):.5f}")
    0.90479 0.90479
    """
    func = "extremum_sequence"
    _check_sequence(func, law, params, quantity, w0, count)
    a, beta, gamma = _law_terms(law, params)
    x, v = _start_state(float(start), quantity, w0, float(alpha), a, beta, gamma)
    amp = np.zeros(int(count))
    times = np.zeros(int(count))
    found = _sequence(x, v, float(w0), float(alpha), 2.0 * a, beta, gamma, int(count),
                      int(steps), quantity == "velocity", amp, times)
    return amp[:found], times[:found]


def _check_sequence(func: str, law: str, params: Sequence[float], quantity: str, w0: float,
                    count: int) -> None:
    """The argument checks of :func:`extremum_sequence` and :func:`extremum_derivatives`."""
    _check_law(law, params, func)
    if quantity not in QUANTITIES:
        raise fail(func, f"quantity = {quantity!r}; expected one of {', '.join(QUANTITIES)}")
    if not (math.isfinite(w0) and w0 > 0):
        raise fail(func, f"w0 = {w0!r}; expected a finite angular frequency > 0 rad/s")
    if count < 1:
        raise fail(func, f"count = {count!r}; expected at least 1 extremum")


def extremum_derivatives(law: str, params: Sequence[float], w0: float, start: float,
                         count: int, *, alpha: float = 0.0, quantity: str = "velocity",
                         steps: int = STEPS_PER_HALF_CYCLE
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`extremum_sequence` with the derivatives of its amplitudes.

    The derivatives are those of the Runge-Kutta model itself (its steps differentiated
    exactly, the extremum's interpolation included), so they equal the limit of finite
    differences of :func:`extremum_sequence`, for about the cost of one more integration
    instead of one per parameter.

    Parameters
    ----------
    law, params, w0, start, count, alpha, quantity, steps
        As in :func:`extremum_sequence`.

    Returns
    -------
    amplitude, time : numpy.ndarray
        As :func:`extremum_sequence` returns them (the same values).
    derivative : numpy.ndarray
        Shape ``(amplitude.size, len(params) + 1)``: the derivative of each amplitude with
        respect to each law parameter (in the order of :data:`LAWS`; U per unit of the
        parameter) and, last, to ``|start|`` (dimensionless).

    Raises
    ------
    AnalysisError
        As :func:`extremum_sequence`.
    """
    func = "extremum_derivatives"
    _check_sequence(func, law, params, quantity, w0, count)
    a, beta, gamma = _law_terms(law, params)
    amp, times, deriv = _tangent_run(law, a, beta, gamma, float(start), quantity, float(w0),
                                     float(alpha), int(count), int(steps))
    deriv[:, -1] *= math.copysign(1.0, float(start))
    return amp, times, deriv


#: The tangent's directions of each law: its parameters' (0: ``a``, 1: ``beta``, 2: ``gamma``),
#: then the start's (3).
_DIRECTIONS = {law: np.array([{"a": 0, "beta": 1, "gamma": 2}[name] for name in names] + [3])
               for law, names in LAWS.items()}


def _tangent_run(law: str, a: float, beta: float, gamma: float, start: float, quantity: str,
                 w0: float, alpha: float, count: int, steps: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Extrema, times and derivatives from a signed ``start``: columns the law's parameters
    (in the order of :data:`LAWS`), then the start value."""
    x, v = _start_state(start, quantity, w0, alpha, a, beta, gamma)
    dirs = _DIRECTIONS[law]
    xd, vd = _start_tangent(x, v, quantity, w0, alpha, a, beta)
    amp = np.zeros(count)
    times = np.zeros(count)
    deriv = np.zeros((count, dirs.size))
    found = _sequence_tangent(x, v, dirs, xd[dirs], vd[dirs], w0, alpha, 2.0 * a, beta, gamma,
                              count, steps, quantity == "velocity", amp, times, deriv)
    return amp[:found], times[:found], deriv[:found]


def decay_rate(law: str, params: Sequence[float], amplitude: np.ndarray, w0: float,
               quantity: str = "velocity") -> np.ndarray:
    """Averaged decay rate ``-d ln A / dt`` (1/s) of the envelope at ``amplitude`` (first-order
    averaging): ``a`` plus ``4 beta V / (3 pi)`` (quadratic, V the velocity amplitude) or
    ``2 gamma / (pi V)`` (Coulomb). Divided by ``w0`` it is the damping ratio at that
    amplitude."""
    a, beta, gamma = _law_terms(law, params)
    amp = np.asarray(amplitude, dtype=np.float64)
    vel = amp if quantity == "velocity" else amp * w0
    with np.errstate(divide="ignore"):
        return a + 4.0 * beta * vel / (3.0 * math.pi) + 2.0 * gamma / (math.pi * vel)


# ----------------------------------------------------------------------------- fit
@dataclass(frozen=True)
class LawFit:
    """A damping law fitted to the extrema of the free decays of one mode.

    Attributes
    ----------
    law
        Name of the law (:data:`LAWS`).
    params
        Fitted law parameters, in the order of :data:`LAWS`.
    cov
        Covariance of ``params`` (from the residuals' variance, at least that of an error of
        :data:`RESOLUTION` of the largest extremum).
    starts
        Fitted first extremum of each decay (U or U/s).
    dof
        Degrees of freedom: extrema fitted minus parameters (law and starts).
    rss
        Whitened residual sum of squares (U^2).
    aicc
        Corrected Akaike information criterion.
    residuals
        Measured minus model extrema, per decay (unwhitened, U).
    model
        Model extrema at the measured half cycles, per decay.
    w0, alpha, quantity
        The oscillator the law was fitted with.
    influence
        How the law parameters move with the extrema, to first order: ``influence @ e`` is
        their change when the decays' whitened extremum errors (each decay's errors put
        through its :class:`Whitener`, concatenated; U) change by ``e``. Shape
        ``(len(params), count)``; None when not computed.
    converged
        False when the least-squares search stopped at its limit of evaluations with the
        parameters still moving: ``params`` are then not the best fit, nor ``cov`` its
        covariance.
    """

    law: str
    params: np.ndarray
    cov: np.ndarray
    starts: np.ndarray
    dof: int
    rss: float
    aicc: float
    residuals: list[np.ndarray]
    model: list[np.ndarray]
    w0: float
    alpha: float = 0.0
    quantity: str = "velocity"
    names: tuple[str, ...] = field(default=())
    influence: np.ndarray | None = field(default=None, repr=False)
    converged: bool = True

    @property
    def se(self) -> np.ndarray:
        """Standard errors of ``params``."""
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float]:
        """Confidence interval of one parameter (t-distribution with :attr:`dof`)."""
        i = LAWS[self.law].index(name)
        q = float(sstats.t.ppf(0.5 + 0.5 * level, max(self.dof, 1)))
        return float(self.params[i] - q * self.se[i]), float(self.params[i] + q * self.se[i])

    def value(self, name: str) -> float:
        """One fitted parameter by name (0 for a term the law does not have)."""
        laws = LAWS[self.law]
        return float(self.params[laws.index(name)]) if name in laws else 0.0

    @property
    def count(self) -> int:
        """Number of extrema fitted."""
        return int(sum(r.size for r in self.residuals))


class Whitener:
    """Whitens the errors of a decay's extrema: ``apply(r)`` is ``L^-1 r`` with ``L L^T`` their
    covariance in units of the noise variance (correlation between extrema, each scaled by its
    relative error). The correlation of band-limited noise dies out within a few half cycles,
    so ``L`` is banded and each application costs O(n band).

    Parameters
    ----------
    times, signs
        Time (s) and sign of each extremum (None: uncorrelated).
    correlation
        Correlation of the noise as a function of the time lag (s), or None.
    scale
        Relative error of each extremum (None: all 1).
    """

    def __init__(self, times: np.ndarray | None, signs: np.ndarray | None,
                 correlation: Callable[[np.ndarray], np.ndarray] | None,
                 scale: np.ndarray | None) -> None:
        n = int(times.size if times is not None else scale.size)
        s = np.ones(n) if scale is None else np.asarray(scale, dtype=np.float64)
        bands = [s * s]
        if correlation is not None and times is not None and n > 1:
            sg = signs if signs is not None else (-1.0) ** np.arange(n)
            for k in range(1, min(n, MAX_BAND + 1)):
                rho = correlation(times[k:] - times[:-k]) * sg[k:] * sg[:-k]
                bands.append(np.concatenate((rho * s[k:] * s[:-k], np.zeros(k))))
            # The correlation's envelope has sidelobes: cut after the last lag that matters,
            # not at its first zero.
            keep = [k for k in range(1, len(bands)) if np.max(np.abs(bands[k])) >= 1e-4]
            bands = bands[:max(keep, default=0) + 1]
        self.band = len(bands) - 1
        ab = np.array(bands)
        diagonal = ab[0].copy()
        # Cut to a band, the correlation at the extrema's irregular lags may fall short of
        # positive definite (extrema close together, a large scale beside a small one): an
        # uncorrelated error of a growing share of each extremum's variance is added until it
        # is (at most the variance itself, where the fit is all but unweighted by correlation).
        for loading in (0.0, 1e-6, 1e-4, 1e-2, 1e-1, 1.0):
            ab[0] = diagonal * (1.0 + loading)
            try:
                self.lower = scipy.linalg.cholesky_banded(ab, lower=True)
                break
            except np.linalg.LinAlgError:
                continue
        else:
            self.band = 0
            self.lower = np.sqrt(diagonal)[None, :]

    def apply(self, r: np.ndarray) -> np.ndarray:
        """``L^-1 r`` (``r`` a vector or a matrix of columns)."""
        if self.band == 0:
            return r / (self.lower[0] if np.ndim(r) == 1 else self.lower[0][:, None])
        r = np.asarray(r, dtype=np.float64)
        out = np.array(r if r.ndim == 2 else r[:, None], dtype=np.float64, order="C")
        _forward_banded(self.lower, out)
        return out if r.ndim == 2 else out[:, 0]


@numba.njit(cache=True)
def _forward_banded(lower, y):
    """Solve ``L z = y`` in place (``y`` of shape (n, m)) for the lower-triangular band ``L``
    stored as ``lower[i, j] = L[j + i, j]``, by forward substitution."""
    band = lower.shape[0] - 1
    n, m = y.shape
    for i in range(n):
        for k in range(1, min(band, i) + 1):
            c = lower[k, i - k]
            if c != 0.0:
                for j in range(m):
                    y[i, j] -= c * y[i - k, j]
        d = lower[0, i]
        for j in range(m):
            y[i, j] /= d


def _start_values(law: str, decays: Sequence[np.ndarray], w0: float,
                  quantity: str = "velocity") -> np.ndarray:
    """Starting law parameters from the mean log decrement of the decays: half the rate
    viscous, half from the other term at the largest velocity amplitude (``w0`` times the
    largest extremum for extrema of the displacement)."""
    rates = []
    for amp in decays:
        if amp.size >= 2:
            k = np.arange(amp.size)
            slope = np.polyfit(k * math.pi / w0, np.log(np.maximum(amp, 1e-300)), 1)[0]
            rates.append(-slope)
    rate = max(float(np.median(rates)) if rates else 1e-3 * w0, 1e-4 * w0)
    top = max(float(np.max(a)) for a in decays) * (w0 if quantity == "displacement" else 1.0)
    if law == "viscous":
        return np.array([rate])
    if law == "quadratic":
        return np.array([0.5 * rate, 0.5 * rate * 3.0 * math.pi / (4.0 * top)])
    if law == "coulomb":
        return np.array([0.5 * rate, 0.5 * rate * math.pi * top / 2.0])
    third = rate / 3.0                      # each term a third of the rate at the largest
    return np.array([third, third * 3.0 * math.pi / (4.0 * top), third * math.pi * top / 2.0])


def _reduced(blocks: Sequence[np.ndarray], p: int) -> tuple[np.ndarray, np.ndarray]:
    """The residuals and Jacobian of a fit of ``p`` law parameters and a start per decay,
    each decay's rows (``blocks``: columns residual, law derivatives, start derivative) put
    through the orthogonal ``Q^T`` of the QR factorisation of its [derivatives | residuals]:
    at most p + 2 rows per decay (with more than p + 1 extrema, the last holds the part of the
    residuals no step can reduce, with no derivative). ``|f|``, ``J^T f`` and ``J^T J`` are
    those of the full rows, so a trust-region solver takes the same steps to the same fit; the
    orthogonal factor changes with the parameters, so the reduced rows are not a Jacobian to
    differentiate further."""
    k = len(blocks)
    r = [np.linalg.qr(both[:, list(range(1, p + 2)) + [0]], mode="r") for both in blocks]
    count = np.cumsum([0] + [x.shape[0] for x in r])
    out = np.empty(count[-1])
    jac = np.zeros((count[-1], p + k))
    for j, x in enumerate(r):
        out[count[j]:count[j + 1]] = x[:, p + 1]
        jac[count[j]:count[j + 1], :p] = x[:, :p]
        jac[count[j]:count[j + 1], p + j] = x[:, p]
    return out, jac


def fit_law(law: str, decays: Sequence[np.ndarray], w0: float, *, alpha: float = 0.0,
            quantity: str = "velocity", times: Sequence[np.ndarray] | None = None,
            signs: Sequence[np.ndarray] | None = None,
            correlation: Callable[[np.ndarray], np.ndarray] | None = None,
            scales: Sequence[np.ndarray] | None = None,
            start: Sequence[float] | None = None,
            whiteners: Sequence[Whitener | None] | None = None,
            max_evaluations: int | None = None) -> LawFit:
    """Fit a damping law to the extrema of one or more free decays of a mode.

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    decays
        Per free decay, the amplitudes (> 0, U or U/s) of its successive extrema, one per half
        cycle from its first free extremum on (at least 3 per decay).
    w0
        Linear natural angular frequency of the mode, rad/s.
    alpha
        Cubic stiffness per unit mass, 1/(U^2 s^2) (from the backbone; 0: linear).
    quantity
        ``"velocity"`` or ``"displacement"``: what the extrema are extrema of.
    times, signs
        Per decay, the time (s) and sign of each extremum; with ``correlation``, for the
        correlation of their errors.
    correlation
        Correlation of the measurement errors of two extrema as a function of their time lag
        (s), e.g. that of white noise through the band filter the extrema were measured on;
        None when the errors are independent.
    scales
        Per decay, the error standard deviation of each extremum relative to the others' (1 for
        most; more near a window's edge, where the filters see less of the record); None for
        equal errors.
    start
        Starting law parameters (default: from the mean log decrement).
    whiteners
        Per decay, a :class:`Whitener` already built from ``times``, ``signs``,
        ``correlation`` and ``scales`` (several laws fitted to the same extrema share them).
    max_evaluations
        Most evaluations of the model the least-squares search may make (default: 200 per
        parameter, law and start amplitudes together); a search stopped there returns a fit
        whose :attr:`LawFit.converged` is False.

    Returns
    -------
    LawFit

    Raises
    ------
    AnalysisError
        Unknown law, a decay with fewer than 3 extrema or non-positive or non-finite
        amplitudes, no more extrema than parameters, a ``max_evaluations`` below 1.
    """
    func = "fit_law"
    if law not in LAWS:
        raise fail(func, f"law = {law!r}; expected one of {', '.join(LAWS)}")
    decays = [np.asarray(d, dtype=np.float64) for d in decays]
    if not decays or any(d.ndim != 1 or d.size < 3 for d in decays):
        raise fail(func, "every free decay needs at least 3 extrema (1-D arrays); got sizes "
                         f"{[int(np.size(d)) for d in decays]}")
    if any(not np.all(np.isfinite(d)) or np.any(d <= 0) for d in decays):
        raise fail(func, "extremum amplitudes must be finite and > 0")
    if max_evaluations is not None and not (isinstance(max_evaluations, (int, np.integer))
                                            and not isinstance(max_evaluations, bool)
                                            and max_evaluations >= 1):
        raise fail(func, f"max_evaluations = {max_evaluations!r}; expected a whole number >= 1 "
                         "or None (200 per parameter)")
    p = len(LAWS[law])
    k = len(decays)
    n = sum(d.size for d in decays)
    if n <= p + k + 1:
        raise fail(func, f"{n} extrema for {p + k} parameters ({p} of the {law} law and a start "
                         "amplitude per decay); the fit needs more extrema than parameters")
    scale = max(float(np.max(d)) for d in decays)
    if whiteners is None:
        whiteners = [Whitener(None if times is None else np.asarray(times[j], dtype=np.float64),
                              None if signs is None else np.asarray(signs[j], dtype=np.float64),
                              correlation,
                              np.ones(decays[j].size) if scales is None
                              else np.asarray(scales[j], dtype=np.float64))
                     if correlation is not None or scales is not None else None
                     for j in range(len(decays))]
    whiten = whiteners

    rows = np.cumsum([0] + [d.size for d in decays])
    # Each extremum depends on the law and on its own decay's start alone: a row of the
    # Jacobian holds p + 1 non-zeros of p + k. Dense, it grows as the square of the decays (a
    # long record's union of 360 decays of 350 extrema: 2.7 GB and 100 s of CPU); above
    # DENSE_JACOBIAN elements, each decay's rows are reduced to p + 2 (:func:`_reduced`): the
    # Jacobian is then (p + 2) k x (p + k), 4 MB for those 360 decays.
    reduce = n * (p + k) > DENSE_JACOBIAN
    cache: dict[str, np.ndarray] = {}

    def model(q: np.ndarray, deriv: list | None = None) -> list[np.ndarray]:
        """Model extrema at ``q``; with ``deriv`` (a list), each decay's derivatives (columns:
        the law's parameters, then its own log start) are appended to it."""
        out = []
        a, beta, gamma = _law_terms(law, q[:p])
        for j, d in enumerate(decays):
            v0 = float(np.exp(q[p + j]))
            amp, _, dm = _tangent_run(law, a, beta, gamma, v0, quantity, float(w0),
                                      float(alpha), d.size, STEPS_PER_HALF_CYCLE)
            got = amp.size
            if got < d.size:                  # stopped (friction) or blew up: hold there
                stopped = got and amp[got - 1] < v0
                held = np.zeros(p + 1) if stopped else dm[max(got - 1, 0)]
                amp = np.concatenate((amp, np.full(d.size - got, 0.0 if stopped
                                                   else amp[max(got - 1, 0)])))
                dm = np.concatenate((dm, np.repeat(held[None, :], d.size - got, axis=0)))
            if deriv is not None:
                dm[:, p] *= v0
                deriv.append(dm)
            out.append(amp)
        return out

    def blocks(q: np.ndarray) -> list[np.ndarray]:
        """Per decay, its whitened residuals and derivatives (columns: residual, the law's
        parameters, its own log start), over ``scale``; a residual that is not finite is
        1e6 with no derivatives, as is a row whose derivatives are not all finite."""
        derivs: list[np.ndarray] = []
        out = []
        for d, m, dm, w in zip(decays, model(q, derivs), derivs, whiten):
            both = np.column_stack(((d - m) / scale, -dm / scale))
            if w is not None:
                both = w.apply(both)
            bad = ~np.isfinite(both[:, 0])
            both[bad | ~np.all(np.isfinite(both[:, 1:]), axis=1), 1:] = 0.0
            both[bad, 0] = 1e6
            out.append(both)
        return out

    def residuals(q: np.ndarray) -> np.ndarray:
        # The Jacobian comes with the residuals (one integration with its tangent), kept for
        # the call of ``jacobian`` at the same point that follows.
        parts = blocks(q)
        if reduce:
            out, jac = _reduced(parts, p)
        else:
            jac = np.zeros((n, p + k))
            for j, both in enumerate(parts):
                jac[rows[j]:rows[j + 1], :p] = both[:, 1:p + 1]
                jac[rows[j]:rows[j + 1], p + j] = both[:, p + 1]
            out = np.concatenate([both[:, 0] for both in parts])
        cache["x"], cache["jac"], cache["parts"] = q.copy(), jac, parts
        return out

    def jacobian(q: np.ndarray) -> np.ndarray:
        if "x" not in cache or not np.array_equal(cache["x"], q):
            residuals(q)
        return cache["jac"]

    law_start = np.asarray(start, dtype=np.float64) if start is not None \
        else _start_values(law, decays, w0, quantity)
    log_starts = np.array([math.log(d[0]) for d in decays])
    x0 = np.concatenate((law_start, log_starts))
    # Start amplitudes stay within a factor e^3 of the first measured extremum; friction
    # cannot push (gamma >= 0: a negative one would feed the motion and blow it up).
    law_lower = np.array([0.0 if name == "gamma" else -np.inf for name in LAWS[law]])
    law_start = np.maximum(law_start, np.where(np.isfinite(law_lower), 1e-12, -np.inf))
    lower = np.concatenate((law_lower, log_starts - 3.0))
    upper = np.concatenate((np.full(p, np.inf), log_starts + 3.0))
    res = sopt.least_squares(residuals, x0, jac=jacobian, x_scale="jac", method="trf",
                             bounds=(lower, upper), xtol=1e-12, ftol=1e-12, gtol=1e-12,
                             max_nfev=int(max_evaluations or 200 * (p + k)))
    jac = res.jac * scale
    rss = float(res.fun @ res.fun) * scale * scale
    dof = n - p - k
    # Extrema are not measured better than RESOLUTION of the largest: below that, a better fit
    # is rounding, not evidence for a law (the AICc below), and a record without noise leaves
    # residuals of its integration's residue, a few 1e-9, whose variance would give intervals
    # that narrow and exclude the truth (and make any other check's differences many of those
    # standard errors). The error variance is at least that resolution's.
    rss_eff = max(rss, n * (RESOLUTION * scale) ** 2)
    s2 = rss_eff / dof
    try:
        normal_inv = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        normal_inv = np.linalg.pinv(jac.T @ jac)
    cov_all = normal_inv * s2
    # A model driven where its extrema explode (a negative damping that makes the decay grow)
    # has derivatives so large that the covariance underflows to zero: nothing is pinned down,
    # and a zero-width interval would pass for certainty. Its coefficients are undetermined.
    unscaled, variances = np.diag(normal_inv)[:p], np.diag(cov_all)[:p]
    if not (np.all(np.isfinite(unscaled)) and np.all(unscaled > 0.0)
            and np.all(variances > 0.0)):
        cov_all = np.diag(np.full(p + k, math.inf))
    # Gauss-Newton: the whitened residuals move by e / scale when the whitened errors move
    # by e, the parameters by -(J^T J)^-1 J^T (e / scale) with J = res.jac = jac / scale.
    if reduce:  # the influence is on every extremum's whitened error: the full rows
        if not np.array_equal(cache["x"], res.x):
            residuals(res.x)
        influence = -np.concatenate(
            [normal_inv[:p, :p] @ both[:, 1:p + 1].T
             + normal_inv[:p, p + j][:, None] * both[None, :, p + 1]
             for j, both in enumerate(cache["parts"])], axis=1) * scale
    else:
        influence = -(normal_inv @ res.jac.T)[:p] * scale
    kk = p + k + 1
    aicc = n * math.log(rss_eff / n) + 2 * kk + 2 * kk * (kk + 1) / max(n - kk - 1, 1)
    fitted = model(res.x)
    return LawFit(law=law, params=res.x[:p].copy(), cov=cov_all[:p, :p].copy(),
                  starts=np.exp(res.x[p:]), dof=dof, rss=rss, aicc=float(aicc),
                  residuals=[d - m for d, m in zip(decays, fitted)], model=fitted,
                  w0=float(w0), alpha=float(alpha), quantity=quantity, names=LAWS[law],
                  influence=influence, converged=bool(res.status > 0))


@dataclass(frozen=True)
class PowerTest:
    """How the amplitude-dependent damping of a quadratic fit grows with the velocity: the
    power ``p`` of a term ``beta |x'|^(p - 1) x'`` that would describe the extrema better than
    the quadratic law's ``beta |x'| x'`` (``p = 2``), from :func:`fluid_power`.

    Attributes
    ----------
    power
        Estimated power (dimensionless; 2 for the quadratic law).
    se
        Its standard error.
    dof
        Degrees of freedom of its t interval (extrema minus parameters).
    change
        Largest relative difference, over the amplitudes of the fitted extrema, between the
        decay rate (damping ratio) of the quadratic law and that of the law with
        :attr:`power` fitted to the same extrema (dimensionless; 0.1 is 10 %).
    """

    power: float
    se: float
    dof: int
    change: float

    @property
    def z(self) -> float:
        """``(power - 2) / se``: how many standard errors the power lies from the quadratic
        law's."""
        return (self.power - 2.0) / self.se if self.se > 0.0 else 0.0

    def interval(self, level: float = 0.95) -> tuple[float, float]:
        """Confidence interval of :attr:`power` (t-distribution with :attr:`dof`)."""
        q = float(sstats.t.ppf(0.5 + 0.5 * level, max(self.dof, 1)))
        return self.power - q * self.se, self.power + q * self.se


#: Points of the amplitude grid :func:`fluid_power` integrates the averaged envelope on.
POWER_GRID = 2048


def fluid_power(fit: LawFit, whiteners: Sequence[Whitener | None] | None = None) -> PowerTest:
    """Test the power of the quadratic law's fluid term on the extrema it was fitted to.

    The quadratic law's ``beta |x'| x'`` is the drag of a fluid at large amplitude; other
    regimes damp with another power of the velocity (``|x'|^p``, ``p`` from about 1 to 3),
    and a law with the wrong power still fits the extrema well, with C_i and C_f that give a
    wrong damping ratio inside their own amplitude span. This is a score test of ``p = 2``:
    the fit's whitened residuals are regressed on the derivatives of the extrema with
    respect to the law's parameters, each decay's start and ``p``, which gives the
    Gauss-Newton step to the law with a free power (its ``p``, its standard error) without a
    second fit. The derivative in ``p`` comes from the first-order averaged envelope
    ``dA/dt = -A r(A)`` (:func:`decay_rate`), whose decay rate ``r`` moves by
    ``(r - a) ln(A / A_max)`` per unit of ``p``; being only the direction of the alternative,
    its averaging error does not bias the test, whose residuals are the exact model's.

    Parameters
    ----------
    fit
        A fit of the ``"quadratic"`` law (:func:`fit_law`) with ``beta > 0``.
    whiteners
        Per decay, the :class:`Whitener` the fit used (None, or a list of None: independent
        errors of equal size).

    Returns
    -------
    PowerTest

    Raises
    ------
    AnalysisError
        ``fit`` is not of the quadratic law, its ``beta`` is not positive (no fluid term to
        test), its decay rate is not positive over the extrema, its model decays stop before
        their last extremum, or there are no more extrema than parameters.

    Examples
    --------
    Extrema of a decay damped by ``|x'|^1.5`` (and a little viscous damping), fitted with
    the quadratic law: the test finds the power.

    >>> import math
    >>> import numpy as np
    >>> from scipy.integrate import solve_ivp
    >>> from fsi_lab.dsp.laws import fit_law, fluid_power
    >>> w0 = 2 * math.pi * 20.0
    >>> def motion(t, y):
    ...     return [y[1], -0.5 * y[1] - 2.0 * abs(y[1]) ** 0.5 * y[1] - w0 * w0 * y[0]]
    >>> turn = lambda t, y: y[1]
    >>> path = solve_ivp(motion, (0.0, 2.0), [0.01, 0.0], events=turn, rtol=1e-10, atol=1e-13)
    >>> amplitude = np.abs(path.y_events[0][1:, 0])
    >>> quadratic = fit_law("quadratic", [amplitude], w0, quantity="displacement")
    >>> print(f"{fluid_power(quadratic).power:.1f}")
    1.5
    """
    func = "fluid_power"
    if fit.law != "quadratic":
        raise fail(func, f"the fit is of the {fit.law} law; the test needs a quadratic one")
    a, beta = float(fit.params[0]), float(fit.params[1])
    if not (math.isfinite(beta) and beta > 0.0):
        raise fail(func, f"beta = {beta!r}: the quadratic law has no fluid term (beta > 0) "
                         "whose power could be tested")
    k = len(fit.model)
    if whiteners is None:
        whiteners = [None] * k
    top = max(float(np.max(m)) for m in fit.model)
    bottom = min(float(np.min(m)) for m in fit.model)
    if not (math.isfinite(top) and bottom > 0.0):
        raise fail(func, "the model decays stop (or leave no extremum above 0): the law "
                         "cannot be differentiated there")
    # (the extrema never leave [bottom, top]: a rate that is positive at both ends is
    # positive between them, and may well turn negative outside, where a < 0)
    grid = np.geomspace(bottom, top, POWER_GRID)
    rate = decay_rate("quadratic", fit.params, grid, fit.w0, fit.quantity)
    if not np.all(rate > 0.0):
        raise fail(func, "the fitted law's decay rate is not positive over the extrema: its "
                         "envelope is not a decay")
    fluid = rate - a                            # the fluid term's share of the rate, 1/s
    integrand = fluid * np.log(grid / top) / (grid * rate * rate)
    inner = np.concatenate(([0.0], np.cumsum(0.5 * (integrand[1:] + integrand[:-1])
                                              * np.diff(grid))))
    residuals, columns, spans, rates = [], [], [], []
    for j in range(k):
        measured = fit.residuals[j] + fit.model[j]
        amp, _, deriv = _tangent_run("quadratic", a, beta, 0.0, float(fit.starts[j]),
                                     fit.quantity, fit.w0, fit.alpha, measured.size,
                                     STEPS_PER_HALF_CYCLE)
        if amp.size < measured.size:
            raise fail(func, f"the model of decay {j} stops after {amp.size} of its "
                             f"{measured.size} extrema")
        at_extrema = decay_rate("quadratic", fit.params, amp, fit.w0, fit.quantity)
        # Averaged envelope: dA/dp = -A r(A) int_A^A0 (r - a) ln(A'/A_max) / (A' r^2) dA'.
        shift = -amp * at_extrema * (np.interp(amp[0], grid, inner) - np.interp(amp, grid, inner))
        both = np.column_stack((measured - amp, deriv[:, 0], deriv[:, 1], shift,
                                deriv[:, 2])) / top
        if whiteners[j] is not None:
            both = whiteners[j].apply(both)
        start = both[:, 4]                      # this decay's own start, projected out here
        norm = float(start @ start)
        rows = both[:, :4] - (np.outer(start, start @ both[:, :4]) / norm if norm > 0.0
                              else 0.0)
        residuals.append(rows[:, 0])
        columns.append(rows[:, 1:])
        spans.append(amp)
        rates.append(at_extrema)
    r, x = np.concatenate(residuals), np.vstack(columns)
    dof = r.size - k - 3
    if dof < 1:
        raise fail(func, f"{r.size} extrema for {k + 3} parameters; the test needs more")
    step, *_ = np.linalg.lstsq(x, r, rcond=None)
    left = r - x @ step
    # Extrema are not measured better than RESOLUTION of the largest (as in fit_law's AICc).
    s2 = max(float(left @ left) / dof, RESOLUTION * RESOLUTION)
    try:
        var = float(np.linalg.inv(x.T @ x)[2, 2]) * s2
    except np.linalg.LinAlgError:
        var = math.inf
    amp, base = np.concatenate(spans), np.concatenate(rates)
    moved = base - a
    change = step[0] + step[1] * moved / beta + step[2] * moved * np.log(amp / top)
    return PowerTest(power=2.0 + float(step[2]), se=math.sqrt(var) if var >= 0.0 else math.inf,
                     dof=int(dof), change=float(np.max(np.abs(change) / base)))


@dataclass(frozen=True)
class LawComparison:
    """Fits of several laws to the same extrema, ranked by AICc.

    Attributes
    ----------
    fits
        The fits by law name.
    preferred
        The law the record supports: the one with the lowest AICc, or the law with the fewest
        parameters among those within :data:`AICC_TIE` of it (a term the record does not
        call for is not preferred); a law with dry friction only where the friction is a
        material part of its damping (:func:`friction_share`), clearly supported
        (:data:`FRICTION_GAIN`) and no other term negative.
    delta
        AICc of each law minus the lowest (0 for the preferred, unless a law with friction
        that may not be preferred fits better; above about 4, a law is clearly less supported
        by the record).
    """

    fits: dict[str, LawFit]
    preferred: str
    delta: dict[str, float]


def friction_share(fit: LawFit) -> float:
    """The share of a fitted law's decay rate that its dry friction gives at the smallest
    extremum of its model (dimensionless; 0 for a law without friction or with none)."""
    gamma = fit.value("gamma")
    extrema = [m[m > 0.0] for m in fit.model]
    if not gamma > 0.0 or not any(m.size for m in extrema):
        return 0.0
    smallest = np.array([min(float(np.min(m)) for m in extrema if m.size)])
    rate = float(decay_rate(fit.law, fit.params, smallest, fit.w0, fit.quantity)[0])
    friction = float(decay_rate("coulomb", [0.0, gamma], smallest, fit.w0, fit.quantity)[0])
    return friction / rate if rate > 0.0 else 0.0


def compare_laws(fits: Sequence[LawFit]) -> LawComparison:
    """Rank fits of different laws to the same extrema by the corrected Akaike criterion; a
    law with dry friction may be preferred only where its friction gives at least
    :data:`FRICTION_SHARE` of its decay rate at the smallest extremum, its AICc is lower than
    every law's without friction by more than :data:`FRICTION_GAIN`, and none of its terms
    is negative by more than :data:`NEGATIVE_Z` standard errors."""
    if not fits:
        raise fail("compare_laws", "no fit given")
    lowest = min(f.aicc for f in fits)
    without = min((f.aicc for f in fits if "gamma" not in f.names), default=math.inf)
    eligible = [f for f in fits if "gamma" not in f.names or (
        friction_share(f) >= FRICTION_SHARE and f.aicc < without - FRICTION_GAIN
        and not np.any(f.params < -NEGATIVE_Z * f.se))] or list(fits)
    best = min(eligible, key=lambda f: f.aicc)
    close = [f for f in eligible if f.aicc <= best.aicc + AICC_TIE]
    simplest = min(close, key=lambda f: (len(f.params), f.aicc))
    return LawComparison(fits={f.law: f for f in fits}, preferred=simplest.law,
                         delta={f.law: f.aicc - lowest for f in fits})


# ----------------------------------------------------------------------------- signals
@numba.njit(cache=True)
def _friction_step(x, v, h, w0sq, alpha, a2, beta, gamma):
    """One Runge-Kutta step of length ``h`` (s; < 0 backwards). With dry friction (``gamma``
    > 0) a step in which the velocity changes sign is split at v = 0, where the friction force
    reverses, or - forwards - the motion sticks when the restoring force cannot overcome it
    (a state at rest that friction holds stays there, backwards too):
    integrated through, the friction's wrong sign over the rest of the step put each velocity
    zero crossing early (the half periods 0.03 % short, the fitted frequency 0.16 % low)."""
    s = 1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0
    if gamma > 0.0 and s == 0.0:
        restoring = w0sq * x + alpha * x * x * x
        if abs(restoring) <= gamma:
            return x, 0.0                  # at rest where friction holds it, either way
        s = -1.0 if restoring > 0.0 else 1.0
    xn, vn = _rk4(x, v, s, h, w0sq, alpha, a2, beta, gamma)
    if gamma <= 0.0 or vn * s >= 0.0:
        return xn, vn
    acc = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)
    an = _accel(xn, vn, s, w0sq, alpha, a2, beta, gamma)
    frac = _hermite_root(v, vn, acc * h, an * h)
    xm, _ = _rk4(x, v, s, frac * h, w0sq, alpha, a2, beta, gamma)
    restoring = w0sq * xm + alpha * xm * xm * xm
    if h > 0.0 and abs(restoring) <= gamma:
        return xm, 0.0
    return _rk4(xm, 0.0, -s, (1.0 - frac) * h, w0sq, alpha, a2, beta, gamma)


@numba.njit(cache=True)
def _march(x, v, t_from, sample_times, w0sq, alpha, a2, beta, gamma, h_max, output, out):
    """Integrate from (x, v) at ``t_from`` through the monotonic ``sample_times`` (s), writing
    x (``output`` 0), v (1) or the acceleration (2) at each; steps no longer than ``h_max``
    (negative times run backwards)."""
    t = t_from
    h_last = 0.0
    w0sq_h, a2_h = w0sq, a2
    for i in range(sample_times.shape[0]):
        target = sample_times[i]
        span = target - t
        steps = int(math.ceil(abs(span) / h_max)) if span != 0.0 else 0
        if steps > 0:
            h = span / steps
            if h != h_last:
                w0sq_h, a2_h = _rk4_matched(w0sq, a2, h)
                h_last = h
            for _ in range(steps):
                x, v = _friction_step(x, v, h, w0sq_h, alpha, a2_h, beta, gamma)
                if not (abs(v) < 1e150 and abs(x) < 1e150):   # overflow or NaN: give up
                    v = 0.0
                    x = 0.0
        t = target
        if output == 0:
            out[i] = x
        elif output == 1:
            out[i] = v
        else:
            s = 1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0
            out[i] = _accel(x, v, s, w0sq, alpha, a2, beta, gamma)


OUTPUTS = ("displacement", "velocity", "acceleration")


def simulate_decay(law: str, params: Sequence[float], w0: float, start: float,
                   start_time: float, times: np.ndarray, *, alpha: float = 0.0,
                   quantity: str = "velocity", output: str | None = None) -> np.ndarray:
    """The oscillator's free decay through an extremum ``start`` at ``start_time``, sampled.

    The motion is integrated forwards from the extremum for the later ``times`` and backwards
    for the earlier ones (:data:`STEPS_PER_HALF_CYCLE` steps per half cycle or finer). Used to
    put a fitted decay through the same filters as the record (:mod:`.identify`).

    Parameters
    ----------
    law, params, w0, alpha, quantity
        As in :func:`extremum_sequence`.
    output
        What to return: ``"displacement"``, ``"velocity"`` or ``"acceleration"`` (default:
        ``quantity``).
    start
        Signed value of the extremum, U or U/s.
    start_time
        Its time, s.
    times
        Increasing sample times, s.

    Returns
    -------
    numpy.ndarray
        The ``output`` at ``times``, U, U/s or U/s^2.
    """
    _check_law(law, params, "simulate_decay")
    output = quantity if output is None else output
    if output not in OUTPUTS:
        raise fail("simulate_decay", f"output = {output!r}; expected one of "
                                     f"{', '.join(OUTPUTS)}")
    code = OUTPUTS.index(output)
    a, beta, gamma = _law_terms(law, params)
    x, v = _start_state(float(start), quantity, w0, float(alpha), a, beta, gamma)
    times = np.asarray(times, dtype=np.float64)
    out = np.zeros(times.size)
    h = math.pi / w0 / STEPS_PER_HALF_CYCLE
    later = times >= start_time
    if later.any():
        seg = np.empty(int(later.sum()))
        _march(x, v, float(start_time), times[later], w0 * w0, float(alpha), 2.0 * a, beta,
               gamma, h, code, seg)
        out[later] = seg
    if (~later).any():
        back = times[~later][::-1].copy()
        seg = np.empty(back.size)
        _march(x, v, float(start_time), back, w0 * w0, float(alpha), 2.0 * a, beta, gamma, h,
               code, seg)
        out[~later] = seg[::-1]
    return out
