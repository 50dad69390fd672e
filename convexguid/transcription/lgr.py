"""Legendre-Gauss-Radau (LGR) points, quadrature weights and the Radau differentiation matrix.

The :math:`N` LGR points on :math:`[-1, 1)` are :math:`\\tau_0 = -1` and the roots of
:math:`(P_{N-1} + P_N)/(1 + \\tau)`; they include the initial point, not the final one. A state is
approximated by the Lagrange polynomial (degree :math:`N`) on the :math:`N + 1` support points
:math:`\\tau_0, \\dots, \\tau_{N-1}, \\tau_N = 1`; its derivative at the :math:`N` LGR points is the
:math:`N \\times (N + 1)` matrix :math:`D_{kl} = \\dot L_l(\\tau_k)` (Feng, Chen, Yang 2018, eqs. 23-28). The
quadrature :math:`\\int_{-1}^{1} f \\approx \\sum_k w_k f(\\tau_k)` over the LGR points is exact for polynomials
of degree :math:`\\le 2N - 2`, and with it :math:`x(1) = x(-1) + \\sum_k w_k \\dot x(\\tau_k)` (eq. 38).

This is the layout of Garg et al., whose collocation equations have the costate-mapping property: the
terminal sensitivity to a control at node :math:`k` is :math:`w_k \\Phi(t_f, t_k) B_k` to spectral accuracy,
which the energy-optimal correction of :mod:`convexguid.families.lpmpc.controller` relies on.

References
----------
Garg D. et al., "A unified framework for the numerical solution of optimal control problems using
pseudospectral methods", Automatica 46(11), 2010 (Radau points, weights and differentiation matrix).
Feng Y., Chen W., Yang L., "Fuel-optimal attitude maneuver using linear pseudo-spectral model predictive
control method", J. Beijing Univ. Aeronautics and Astronautics 44(10), 2018, eqs. (23)-(28), (38).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.polynomial import legendre

from convexguid.transcription.mapped_chebyshev import barycentric_differentiation, barycentric_interpolation_matrix


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@lru_cache(maxsize=32)
def lgr_points(n: int) -> np.ndarray:
    """The :math:`n` LGR points, ascending, :math:`\\tau_0 = -1` (roots of :math:`P_{n-1} + P_n`)."""
    if n < 2:
        raise ValueError(f"LGR points need n >= 2, got {n}")
    coefficients = np.zeros(n + 1)
    coefficients[n - 1] = coefficients[n] = 1.0
    roots = np.sort(np.real(legendre.legroots(coefficients)))
    roots[0] = -1.0  # exactly
    return _readonly(roots)


@lru_cache(maxsize=32)
def lgr_weights(n: int) -> np.ndarray:
    """Quadrature weights of the :math:`n` LGR points: :math:`2/n^2` at -1, else
    :math:`(1 - \\tau_k) / (n^2 P_{n-1}(\\tau_k)^2)`."""
    tau = lgr_points(n)
    p = legendre.legval(tau, np.eye(n)[n - 1])
    w = (1.0 - tau) / (n**2 * p**2)
    w[0] = 2.0 / n**2
    return _readonly(w)


def _barycentric_weights(points: np.ndarray) -> np.ndarray:
    diff = points[:, None] - points[None, :]
    np.fill_diagonal(diff, 1.0)
    return 1.0 / diff.prod(axis=1)


@lru_cache(maxsize=32)
def radau_support(n: int) -> np.ndarray:
    """The :math:`n + 1` support points of the state polynomial: the LGR points and :math:`\\tau_n = 1`."""
    return _readonly(np.append(lgr_points(n), 1.0))


@lru_cache(maxsize=32)
def lgr_differentiation(n: int) -> np.ndarray:
    """:math:`D \\in R^{n \\times (n+1)}`: derivative at the LGR points of the degree-:math:`n` interpolant
    through its values at the support points (eq. 28)."""
    s = radau_support(n)
    first, _ = barycentric_differentiation(s, _barycentric_weights(s))
    return _readonly(first[:n].copy())


def lagrange_rows(points: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Rows: the Lagrange basis on ``points`` evaluated at ``tau`` (barycentric form, exact at the points)."""
    return barycentric_interpolation_matrix(points, _barycentric_weights(points), tau, atol=1e-14)


@dataclass(frozen=True)
class RadauGrid:
    """``n`` LGR points on :math:`[t_0, t_f]` (eq. 20: :math:`t = p(\\tau + 1) + t_0`)."""

    n: int
    t0: float
    tf: float

    @property
    def p(self) -> float:
        """:math:`p = (t_f - t_0)/2`, the factor of the normalised dynamics (eq. 22)."""
        return 0.5 * (self.tf - self.t0)

    @property
    def times(self) -> np.ndarray:
        """The times of the LGR points (the collocation and control nodes)."""
        return self.t0 + self.p * (lgr_points(self.n) + 1.0)

    @property
    def weights(self) -> np.ndarray:
        return lgr_weights(self.n)

    @property
    def differentiation(self) -> np.ndarray:
        return lgr_differentiation(self.n)

    def control_interpolation(self, t: np.ndarray) -> np.ndarray:
        """Lagrange rows over the LGR points at times ``t`` (eq. 24; beyond the last point it extrapolates)."""
        return lagrange_rows(lgr_points(self.n), (np.asarray(t, dtype=float) - self.t0) / self.p - 1.0)
