"""The analytical beam-in-fluid model of Section 5 of the paper (Eqs. 8-23, 26).

A clamped-free Euler-Bernoulli beam of length L moves with its base (base acceleration
``w_b''(t)``). Its displacement relative to the base is expanded on the undamped mode shapes,
``w_rel(x, t) = sum_n W_n(x) q_n(t)`` (Eq. 13), and each modal coordinate obeys (Eq. 20)::

    (mu + M) q_n'' + (C_i + C_f |q_n'|) q_n' + EI beta_n^4 / L^4 q_n = Q_n / b
    Q_n = -(mu + M) w_b'' int_0^L W_n dx                                       (Eq. 21)
    b   = int_0^L W_n^2 dx = L                                                 (Eq. 22)

with the beam's mass per length ``mu = rho * width * thickness``, the added mass of the fluid
``M = rho_f pi (H/2)^2`` (Eq. 10, H = width) and the theoretical quadratic fluid damping
``C_f = rho_f C_d H / 2`` (Eq. 26). The natural frequencies are
``omega_n^2 = EI beta_n^4 / ((mu + M) L^4)`` (Eq. 23); "dry" means fluid = air, whose (small) added
mass the paper's Table 1 includes.

Two corrections to the paper's printed text, both checked by the tests:

- Eq. (16) prints ``sigma_n = (sinh b - sin b) / (cosh b - cos b)``; the free-end conditions
  (Eq. 14) need ``sigma_n = (sinh b - sin b) / (cosh b + cos b)`` (= (cosh b + cos b) /
  (sinh b + sin b) on the roots). The printed form violates W''(L) = W'''(L) = 0.
- The text below Eq. (23) calls 1.875, 4.694, ... "beta_n / L"; they are beta_n (dimensionless).

Mode shapes are evaluated in an overflow-free form (exponentials scaled by e^-beta), so any mode
number can be used. The integrator lives in :mod:`fsi_lab.modal_integrator`.

Units are SI throughout: m, kg, s, Pa, Hz (rad/s where named ``omega``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from fsi_lab.errors import ParameterError
from fsi_lab.specimen import FLUID_DENSITY

#: Damping ratios of the paper's dry numerical model (Section 3): 0.2 % and 0.1 % for modes 1, 2.
PAPER_DRY_RATIOS = (0.002, 0.001)
#: C_i (kg/(m s)) and C_f (kg/m^2) the paper identified from its wet experiment (Section 5.3).
PAPER_WET_C_I = 0.65
PAPER_WET_C_F = 33.0

PROJECTIONS = ("per-mode", "galerkin")


# --------------------------------------------------------------------------- characteristic roots
def _sech(x: float) -> float:
    """1 / cosh(x) without overflow for large x."""
    e = math.exp(-abs(x))
    return 2.0 * e / (1.0 + e * e)


def _brent(f, lo: float, hi: float, xtol: float, rtol: float, maxiter: int) -> float:
    """A root of ``f`` in ``[lo, hi]``, where ``f`` changes sign, by Brent's method.

    The steps of ``scipy.optimize.brentq`` (inverse quadratic extrapolation or secant when
    they shrink the bracket fast enough, bisection otherwise), so that the roots are the
    same to the last bit, without importing scipy for a handful of roots: the beam model is
    built by every ``fsi-lab profile check``. Converged when the bracket is within
    ``(xtol + rtol |x|)``.
    """
    xpre, xcur = lo, hi
    fpre, fcur = f(xpre), f(xcur)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError(f"f({lo}) and f({hi}) have the same sign: no root is bracketed")
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):  # a good short step
                spre, scur = scur, stry
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = f(xcur)
    raise ArithmeticError(f"no root found in [{lo}, {hi}] after {maxiter} iterations")


def clamped_free_betas(modes: int) -> np.ndarray:
    """Roots beta_n of cos(beta) cosh(beta) = -1, n = 1..modes.

    Solved as ``cos(beta) + 1/cosh(beta) = 0`` (no overflow) by Brent's method on the bracket
    ``[(n-1) pi, n pi]``, which holds exactly one root, close to ``(2n - 1) pi / 2``.

    Parameters
    ----------
    modes
        Number of roots wanted, >= 1.

    Returns
    -------
    numpy.ndarray
        ``beta_n`` (dimensionless), shape ``(modes,)``, absolute accuracy about 1e-15 * beta_n.
    """
    _check_modes(modes, "modes")
    betas = np.empty(modes)
    for i in range(modes):
        n = i + 1

        def f(b: float) -> float:
            return math.cos(b) + _sech(b)

        lo = (n - 1) * math.pi
        hi = n * math.pi
        betas[i] = _brent(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    return betas


def _check_modes(modes: Any, where: str) -> int:
    if isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or modes < 1:
        raise ParameterError(f"{where}: got {modes!r}; expected an integer >= 1 (number of modes)")
    return int(modes)


def _sigma_and_tail(beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sigma_n and (1 - sigma_n) e^beta / 2 in forms that do not overflow or cancel."""
    e = np.exp(-beta)
    den = 1.0 + e * e + 2.0 * np.cos(beta) * e
    sigma = (1.0 - e * e - 2.0 * np.sin(beta) * e) / den
    # (1 - sigma) / 2 * e^beta, computed without forming 1 - sigma (which is ~ e^-beta).
    tail = (e + np.cos(beta) + np.sin(beta)) / den
    return sigma, tail


def _shape(xi: np.ndarray, beta: np.ndarray, derivative: int = 0) -> np.ndarray:
    """d^k W / d xi^k / beta^k at xi = x / L for every beta (shape ``xi.shape + beta.shape``).

    W = cosh z - cos z - sigma (sinh z - sin z), z = beta xi, written as
    ``tail e^(z - beta) + (1 + sigma)/2 e^-z - cos z + sigma sin z``.
    """
    sigma, tail = _sigma_and_tail(beta)
    z = np.multiply.outer(xi, beta)
    k = derivative
    grow = tail * np.exp(z - beta)
    decay = 0.5 * (1.0 + sigma) * np.exp(-z) * (-1.0) ** k
    trig = -np.cos(z + k * math.pi / 2) + sigma * np.sin(z + k * math.pi / 2)
    return grow + decay + trig


# --------------------------------------------------------------------------- damping
@dataclass(frozen=True)
class Damping:
    """How the modal equations are damped.

    The linear part is either a viscous coefficient per unit length ``c_i`` (the wet model,
    Eq. 20) or damping ratios per mode ``ratios`` (the dry numerical model); the quadratic fluid
    part ``c_f`` may be added to either.

    Parameters
    ----------
    c_i
        Linear (material) damping per unit length C_i, kg/(m s) (= N s/m^2).
    c_f
        Quadratic (fluid) damping per unit length C_f, kg/m^2 (= N s^2/m^3).
    ratios
        Linear damping ratios zeta_n (dimensionless), one per mode; or exactly two with
        ``rayleigh=True``. Mutually exclusive with a non-zero ``c_i``.
    rayleigh
        Extend two ratios to every mode with Rayleigh damping fitted on modes 1 and 2,
        ``zeta_n = alpha / (2 omega_n) + beta omega_n / 2`` (as the paper's FE model does).
    projection
        ``"per-mode"``: the paper's approximation C_f |q_n'| q_n' in each mode's equation.
        ``"galerkin"``: the consistent projection
        ``(1/b) int_0^L C_f |w_rel'| w_rel' W_n dx`` which couples the modes.
    """

    c_i: float = 0.0
    c_f: float = 0.0
    ratios: tuple[float, ...] | None = None
    rayleigh: bool = False
    projection: str = "per-mode"

    def __post_init__(self) -> None:
        for name, unit in (("c_i", "kg/(m s)"), ("c_f", "kg/m^2")):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or value < 0:
                raise ParameterError(
                    f"damping.{name}: got {value!r}; expected a finite number >= 0 {unit}")
        if self.projection not in PROJECTIONS:
            raise ParameterError(
                f"damping.projection: got {self.projection!r}; expected one of "
                + ", ".join(repr(p) for p in PROJECTIONS))
        if self.ratios is not None:
            ratios = tuple(self.ratios)
            for i, r in enumerate(ratios):
                if isinstance(r, bool) or not isinstance(r, (int, float)) \
                        or not math.isfinite(r) or r < 0:
                    raise ParameterError(
                        f"damping.ratios[{i}]: got {r!r}; expected a finite number >= 0")
            if not ratios:
                raise ParameterError("damping.ratios: empty; expected one ratio per mode")
            if self.c_i:
                raise ParameterError(
                    "damping: both c_i and ratios are given; give the linear damping either as "
                    "c_i (per unit length) or as ratios (per mode), not both")
            if self.rayleigh and len(ratios) != 2:
                raise ParameterError(
                    f"damping.ratios: Rayleigh damping needs exactly 2 ratios (modes 1 and 2); "
                    f"got {len(ratios)}")
            object.__setattr__(self, "ratios", tuple(float(r) for r in ratios))
        elif self.rayleigh:
            raise ParameterError("damping.rayleigh: needs two ratios (modes 1 and 2)")

    @classmethod
    def paper_dry(cls) -> "Damping":
        """The dry numerical model: 0.2 % and 0.1 % for modes 1 and 2, Rayleigh beyond."""
        return cls(ratios=PAPER_DRY_RATIOS, rayleigh=True)

    @classmethod
    def paper_wet(cls, projection: str = "per-mode") -> "Damping":
        """The wet analytical model with the paper's fitted C_i = 0.65 and C_f = 33.0."""
        return cls(c_i=PAPER_WET_C_I, c_f=PAPER_WET_C_F, projection=projection)


# --------------------------------------------------------------------------- the model
def _positive(value: Any, where: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) \
            or not math.isfinite(value) or value <= 0:
        raise ParameterError(f"{where}: got {value!r}; expected a finite number > 0 {unit}")
    return float(value)


@dataclass(frozen=True)
class BeamModel:
    """Clamped-free Euler-Bernoulli beam in a fluid, truncated to ``modes`` modes.

    Parameters
    ----------
    length
        Free length L, m.
    width
        Width H (facing the flow), m.
    thickness
        Thickness in the direction of vibration, m.
    youngs_modulus
        E, Pa.
    density
        Beam material density rho, kg/m^3.
    fluid
        Name of the surrounding fluid, one of :data:`fsi_lab.specimen.FLUID_DENSITY`.
    drag_coefficient
        C_d for the theoretical quadratic damping (Eq. 26), dimensionless.
    modes
        Number of modes kept, >= 1.
    damping
        See :class:`Damping`. Default: no damping.

    Raises
    ------
    ParameterError
        Non-positive or non-finite geometry/material, unknown fluid, modes < 1, damping ratios
        that do not match the number of modes.
    """

    length: float
    width: float
    thickness: float
    youngs_modulus: float
    density: float
    fluid: str
    drag_coefficient: float = 1.8
    modes: int = 4
    damping: Damping = field(default_factory=Damping)

    def __post_init__(self) -> None:
        for name, unit in (("length", "m"), ("width", "m"), ("thickness", "m"),
                           ("youngs_modulus", "Pa"), ("density", "kg/m^3")):
            object.__setattr__(self, name, _positive(getattr(self, name), f"beam.{name}", unit))
        if self.fluid not in FLUID_DENSITY:
            raise ParameterError(
                f"beam.fluid: got {self.fluid!r}; expected one of "
                + ", ".join(repr(f) for f in FLUID_DENSITY))
        cd = self.drag_coefficient
        if isinstance(cd, bool) or not isinstance(cd, (int, float)) or not math.isfinite(cd) \
                or cd < 0:
            raise ParameterError(
                f"beam.drag_coefficient: got {cd!r}; expected a finite number >= 0")
        object.__setattr__(self, "modes", _check_modes(self.modes, "beam.modes"))
        if not isinstance(self.damping, Damping):
            raise ParameterError(
                f"beam.damping: got {type(self.damping).__name__}; expected fsi_lab.beam.Damping")
        ratios = self.damping.ratios
        if ratios is not None and not self.damping.rayleigh and len(ratios) != self.modes:
            raise ParameterError(
                f"damping.ratios: {len(ratios)} ratios for {self.modes} modes; give one ratio "
                f"per mode, or two with rayleigh=True to extend them by Rayleigh damping")

    @classmethod
    def from_specimen(cls, specimen: Any, modes: int = 4, damping: Damping | None = None,
                      fluid: str | None = None) -> "BeamModel":
        """Build the model of a profile's specimen.

        Parameters
        ----------
        specimen
            A :class:`fsi_lab.specimen.Specimen`.
        modes
            Number of modes kept.
        damping
            Damping; ``None`` means the theoretical fluid damping C_f = rho_f C_d H / 2
            (Eq. 26) and no material damping.
        fluid
            Override the specimen's fluid (``"air"`` for the dry model).
        """
        fluid = specimen.fluid if fluid is None else fluid
        model = cls(length=specimen.length, width=specimen.width, thickness=specimen.thickness,
                    youngs_modulus=specimen.youngs_modulus, density=specimen.density,
                    fluid=fluid, drag_coefficient=specimen.drag_coefficient, modes=modes)
        if damping is None:
            damping = Damping(c_f=model.c_f_theory)
        return model.with_damping(damping)

    def with_damping(self, damping: Damping) -> "BeamModel":
        """The same beam with other damping."""
        return BeamModel(self.length, self.width, self.thickness, self.youngs_modulus,
                         self.density, self.fluid, self.drag_coefficient, self.modes, damping)

    # ---------------------------------------------------------------- section and fluid
    @property
    def fluid_density(self) -> float:
        """Density of the surrounding fluid rho_f, kg/m^3."""
        return FLUID_DENSITY[self.fluid]

    @property
    def second_moment(self) -> float:
        """Second moment of area I = H t^3 / 12, m^4."""
        return self.width * self.thickness ** 3 / 12.0

    @property
    def bending_stiffness(self) -> float:
        """EI, N m^2."""
        return self.youngs_modulus * self.second_moment

    @property
    def mass_per_length(self) -> float:
        """The beam's own mass per length mu = rho H t, kg/m."""
        return self.density * self.width * self.thickness

    @property
    def added_mass(self) -> float:
        """Added mass per length of the fluid M = rho_f pi (H/2)^2 (Eq. 10), kg/m."""
        return self.fluid_density * math.pi * (self.width / 2.0) ** 2

    @property
    def total_mass_per_length(self) -> float:
        """mu + M, kg/m."""
        return self.mass_per_length + self.added_mass

    @property
    def added_mass_ratio(self) -> float:
        """M / mu (17.33 for the paper's beam in water)."""
        return self.added_mass / self.mass_per_length

    @property
    def c_f_theory(self) -> float:
        """Theoretical quadratic damping C_f = rho_f C_d H / 2 (Eq. 26), kg/m^2."""
        return 0.5 * self.fluid_density * self.drag_coefficient * self.width

    # ---------------------------------------------------------------- modal quantities
    @cached_property
    def betas(self) -> np.ndarray:
        """beta_n, roots of cos(beta) cosh(beta) = -1, shape ``(modes,)``."""
        return clamped_free_betas(self.modes)

    @property
    def sigmas(self) -> np.ndarray:
        """sigma_n = (sinh b - sin b) / (cosh b + cos b) (Eq. 16, corrected), shape ``(modes,)``."""
        return _sigma_and_tail(self.betas)[0]

    @property
    def natural_frequencies_rad(self) -> np.ndarray:
        """Undamped omega_n = sqrt(EI beta_n^4 / ((mu + M) L^4)) (Eq. 23), rad/s."""
        return self.betas ** 2 / self.length ** 2 * math.sqrt(
            self.bending_stiffness / self.total_mass_per_length)

    @property
    def natural_frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies f_n = omega_n / (2 pi), Hz."""
        return self.natural_frequencies_rad / (2.0 * math.pi)

    @property
    def norm(self) -> float:
        """b = int_0^L W_n^2 dx (Eq. 22), m; equal to L for every mode with this normalisation."""
        return self.length

    @property
    def mode_integrals(self) -> np.ndarray:
        """int_0^L W_n dx = 2 sigma_n L / beta_n, m, shape ``(modes,)``."""
        return 2.0 * self.sigmas * self.length / self.betas

    @property
    def participation(self) -> np.ndarray:
        """p_n = int W_n / b: q_n'' = ... - p_n w_b'' (Eqs. 20-21 divided by mu + M)."""
        return self.mode_integrals / self.norm

    @cached_property
    def linear_damping_rates(self) -> np.ndarray:
        """Linear damping term divided by (mu + M), 1/s: q_n'' + rate_n q_n' + ...

        ``C_i / (mu + M)`` or ``2 zeta_n omega_n``.
        """
        d = self.damping
        omega = self.natural_frequencies_rad
        if d.ratios is None:
            return np.full(self.modes, d.c_i / self.total_mass_per_length)
        if not d.rayleigh:
            return 2.0 * np.asarray(d.ratios) * omega
        w1, w2 = _rayleigh_omegas(self)
        z1, z2 = d.ratios
        # zeta = a / (2 w) + b w / 2 fitted at w1, w2; rate = 2 zeta w = a + b w^2.
        b = 2.0 * (z2 * w2 - z1 * w1) / (w2 ** 2 - w1 ** 2)
        a = 2.0 * z1 * w1 - b * w1 ** 2
        return a + b * omega ** 2

    @property
    def damping_ratios(self) -> np.ndarray:
        """Linear damping ratio of each mode, rate_n / (2 omega_n) (dimensionless)."""
        return self.linear_damping_rates / (2.0 * self.natural_frequencies_rad)

    @property
    def quadratic_damping_rate(self) -> float:
        """C_f / (mu + M), 1/m."""
        return self.damping.c_f / self.total_mass_per_length

    # ---------------------------------------------------------------- shapes
    def _xi(self, x: Any) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if not np.all(np.isfinite(x)) or np.any(x < 0) or np.any(x > self.length):
            bad = x[~(np.isfinite(x) & (x >= 0) & (x <= self.length))].ravel()[0]
            raise ParameterError(
                f"position x = {float(bad)!r} m is not on the beam; "
                f"expected 0 <= x <= {self.length:g} m")
        return x / self.length

    def mode_shape(self, x: Any, n: int, derivative: int = 0) -> np.ndarray:
        """Mode shape W_n (Eq. 15) or its derivative at positions ``x``.

        Parameters
        ----------
        x
            Positions from the clamp, m (scalar or array), 0 <= x <= L.
        n
            Mode number, 1-based (any n >= 1; not limited to ``modes``).
        derivative
            0..4: d^k W_n / dx^k, in m^-k. W_n is dimensionless, |W_n(L)| = 2.
        """
        n = _check_modes(n, "mode number n")
        if derivative not in (0, 1, 2, 3, 4):
            raise ParameterError(f"derivative: got {derivative!r}; expected 0, 1, 2, 3 or 4")
        beta = clamped_free_betas(n)[-1:] if n > self.modes else self.betas[n - 1:n]
        scale = (beta[0] / self.length) ** derivative
        return scale * _shape(self._xi(x), beta, derivative)[..., 0]

    def mode_shapes(self, x: Any, derivative: int = 0) -> np.ndarray:
        """All kept mode shapes at ``x``: shape ``np.shape(x) + (modes,)``, m^-derivative."""
        if derivative not in (0, 1, 2, 3, 4):
            raise ParameterError(f"derivative: got {derivative!r}; expected 0, 1, 2, 3 or 4")
        scale = (self.betas / self.length) ** derivative
        return scale * _shape(self._xi(x), self.betas, derivative)

    def reconstruct(self, modal: Any, x: Any) -> np.ndarray:
        """Field relative to the base from modal coordinates: sum_n W_n(x) q_n (Eq. 13).

        Parameters
        ----------
        modal
            Modal displacements (m), velocities (m/s) or accelerations (m/s^2),
            shape ``(..., modes)``.
        x
            Positions, m, shape ``(points,)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(..., points)``, in the unit of ``modal``.
        """
        modal = np.asarray(modal, dtype=float)
        if modal.shape[-1:] != (self.modes,):
            raise ParameterError(
                f"modal coordinates have shape {modal.shape}; expected (..., {self.modes})")
        return modal @ self.mode_shapes(np.atleast_1d(x)).T

    def static_tip_deflection(self, base_acceleration: float) -> float:
        """Exact static tip deflection relative to the base under a constant base acceleration.

        The uniform load -(mu + M) a gives w(L) = -(mu + M) a L^4 / (8 EI), m. Used to check the
        modal truncation.
        """
        return -self.total_mass_per_length * base_acceleration * self.length ** 4 / (
            8.0 * self.bending_stiffness)

    def galerkin_factors(self, points: int = 400) -> np.ndarray:
        """kappa_n = int_0^L |W_n|^3 dx / b: the Galerkin quadratic damping of a lone mode.

        With only mode n moving, the consistent projection gives kappa_n C_f |q_n'| q_n' where
        the paper's per-mode approximation has C_f |q_n'| q_n'.
        """
        xg, wg = np.polynomial.legendre.leggauss(points)
        xi = 0.5 * (xg + 1.0)
        w = _shape(xi, self.betas)
        return 0.5 * (wg[:, None] * np.abs(w) ** 3).sum(axis=0) * self.length / self.norm

    def summary(self) -> dict[str, Any]:
        """JSON-ready figures: fluid, added-mass ratio, natural frequencies (Hz), C_f theory."""
        return {
            "fluid": self.fluid,
            "added_mass_ratio": float(self.added_mass_ratio),
            "natural_frequencies_hz": [float(f) for f in self.natural_frequencies_hz],
            "c_f_theory": float(self.c_f_theory),
        }


def _rayleigh_omegas(model: BeamModel) -> tuple[float, float]:
    """omega_1, omega_2 of the model (computed even if it keeps fewer than 2 modes)."""
    betas = clamped_free_betas(2)
    factor = math.sqrt(model.bending_stiffness / model.total_mass_per_length) / model.length ** 2
    return float(betas[0] ** 2 * factor), float(betas[1] ** 2 * factor)
