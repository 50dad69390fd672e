"""Mapped Chebyshev pseudospectral transcription (Cai, Zhu, Zeng 2018, Sec. 2.3).

The flat outputs are represented by their values at the mapped Chebyshev-Gauss-Lobatto
(CGL) nodes and interpolated by the barycentric rational interpolant of eq. (21).
The Kosloff-Tal-Ezer map spreads the CGL points towards a uniform distribution,
which keeps the differentiation matrices far better conditioned than the plain
Chebyshev ones (the paper's motivation).

.. math::

    \\tau_k = \\cos(\\pi k / N), \\qquad
    \\lambda_k = g(\\tau_k) = \\frac{\\arcsin(\\alpha \\tau_k)}{\\arcsin \\alpha}, \\qquad
    \\alpha = \\operatorname{sech}(|\\ln \\varepsilon| / N)

Nodes run from :math:`\\lambda_0 = 1` down to :math:`\\lambda_N = -1` as in the paper;
:class:`MappedChebyshev` reverses them so that time increases with the node index.
All arrays returned here are read-only and cached.

References
----------
Cai W., Zhu Y., Zeng P., "Differentially flat method of attitude maneuver trajectory
planning for space vehicles under multiple constraints", J. Dynamics and Control, 2018,
eqs. (17)-(28).
Berrut J.-P., Trefethen L. N., "Barycentric Lagrange interpolation", SIAM Review 46(3), 2004
(second-derivative formula, eq. 9.4 there).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@lru_cache(maxsize=64)
def cgl_nodes(n: int) -> np.ndarray:
    """Chebyshev-Gauss-Lobatto points of the second kind, eq. (19): :math:`\\tau_k = \\cos(\\pi k/N)`."""
    return _readonly(np.cos(np.pi * np.arange(n + 1) / n))


def kosloff_tal_ezer_alpha(n: int, epsilon: float) -> float:
    """Map parameter of eq. (20): :math:`\\alpha = \\operatorname{sech}(|\\ln\\varepsilon|/N)`."""
    return 1.0 / np.cosh(abs(np.log(epsilon)) / n)


def kte_map(tau: np.ndarray, alpha: float) -> np.ndarray:
    """Kosloff-Tal-Ezer map of eq. (18): :math:`g(\\tau) = \\arcsin(\\alpha\\tau)/\\arcsin\\alpha`."""
    return np.arcsin(alpha * np.asarray(tau)) / np.arcsin(alpha)


def kte_map_derivative(tau: np.ndarray, alpha: float) -> np.ndarray:
    """:math:`g'(\\tau) = \\alpha / (\\arcsin\\alpha \\, \\sqrt{1 - \\alpha^2\\tau^2})`, used in eq. (26)."""
    return alpha / (np.arcsin(alpha) * np.sqrt(1.0 - (alpha * np.asarray(tau)) ** 2))


@lru_cache(maxsize=64)
def cgl_barycentric_weights(n: int) -> np.ndarray:
    """Barycentric weights of eq. (22): :math:`(-1)^k`, halved at both ends."""
    w = (-1.0) ** np.arange(n + 1)
    w[0] *= 0.5
    w[n] *= 0.5
    return _readonly(w)


@lru_cache(maxsize=64)
def clenshaw_curtis_weights(n: int) -> np.ndarray:
    """Clenshaw-Curtis weights on the CGL points, eqs. (27)-(28).

    .. math::

        w_0 = w_N = \\frac{1}{N^2 - 1}\\ (N \\text{ even}),\\ \\frac{1}{N^2}\\ (N \\text{ odd}), \\qquad
        w_s = \\frac{4}{N} \\sideset{}{''}\\sum_{i=0}^{\\lfloor N/2 \\rfloor}
              \\frac{\\cos(2\\pi i s / N)}{1 - 4 i^2}

    where the double prime halves the first term, and the last one when :math:`N` is even.
    They integrate polynomials of degree :math:`N` exactly and sum to 2.
    """
    s = np.arange(1, n)
    i = np.arange(n // 2 + 1)
    halves = np.ones(i.size)
    halves[0] = 0.5
    if n % 2 == 0:
        halves[-1] = 0.5
    terms = halves / (1.0 - 4.0 * i**2)
    w = np.empty(n + 1)
    w[1:-1] = 4.0 / n * np.cos(2.0 * np.pi * np.outer(s, i) / n) @ terms
    w[0] = w[-1] = 1.0 / (n**2 - 1) if n % 2 == 0 else 1.0 / n**2
    return _readonly(w)


def barycentric_differentiation(x: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and second differentiation matrices of the barycentric rational interpolant, eqs. (24)-(25).

    .. math::

        D_{ij} = \\frac{w_j / w_i}{x_i - x_j}, \\qquad
        D^{(2)}_{ij} = 2 D_{ij} \\left(D_{ii} - \\frac{1}{x_i - x_j}\\right) \\quad (i \\ne j), \\qquad
        D_{ii} = -\\sum_{k\\ne i} D_{ik}.

    The paper prints the second-derivative bracket with the opposite sign on
    :math:`\\sum_{k\\ne i}`; written with :math:`D_{ii} = -\\sum_{k \\ne i} D_{ik}` the
    formula above is Berrut and Trefethen's (2004) eq. (9.4), and only it differentiates
    :math:`x^2` exactly (tested).
    """
    diff = x[:, None] - x[None, :]
    np.fill_diagonal(diff, 1.0)
    d1 = (w[None, :] / w[:, None]) / diff
    np.fill_diagonal(d1, 0.0)
    np.fill_diagonal(d1, -d1.sum(axis=1))
    d2 = 2.0 * d1 * (np.diag(d1)[:, None] - 1.0 / diff)
    np.fill_diagonal(d2, 0.0)
    np.fill_diagonal(d2, -d2.sum(axis=1))
    return d1, d2


def barycentric_interpolation_matrix(x: np.ndarray, w: np.ndarray, points: np.ndarray,
                                     atol: float = 0.0) -> np.ndarray:
    """Matrix ``L`` with ``L @ f(x) = f_interp(points)`` for the barycentric formula of eq. (21).

    .. math::

        \\bar f(\\lambda) = \\sum_k \\frac{w_k f_k}{\\lambda - \\lambda_k}
                         \\Big/ \\sum_k \\frac{w_k}{\\lambda - \\lambda_k}

    A point that coincides with a node (within ``atol``) gets that node's value exactly.
    """
    points = np.atleast_1d(np.asarray(points, dtype=float))
    diff = points[:, None] - x[None, :]
    exact = np.abs(diff) <= atol
    diff[exact] = 1.0
    terms = w[None, :] / diff
    mat = terms / terms.sum(axis=1, keepdims=True)
    hit = exact.any(axis=1)
    mat[hit] = exact[hit].astype(float)
    return mat


@dataclass(frozen=True)
class MappedChebyshev:
    """The mapped CGL grid of the paper, ordered so that time increases with the index.

    Parameters
    ----------
    n
        Polynomial order :math:`N` (:math:`N + 1` nodes).
    epsilon
        Rounding error admitted by the map, eq. (20); :math:`\\alpha = 0.9135` for
        :math:`N = 32`, :math:`\\varepsilon = 10^{-6}`.
    """

    n: int
    epsilon: float

    def __post_init__(self) -> None:
        if self.n < 2:
            raise ValueError(f"mapped Chebyshev grid needs N >= 2 (got {self.n})")
        if not 0.0 < self.epsilon < 1.0:
            raise ValueError(f"map epsilon must lie in (0, 1) (got {self.epsilon})")

    @property
    def alpha(self) -> float:
        return kosloff_tal_ezer_alpha(self.n, self.epsilon)

    @cached_property
    def tau(self) -> np.ndarray:
        """Standard CGL points, increasing."""
        return _readonly(cgl_nodes(self.n)[::-1].copy())

    @cached_property
    def nodes(self) -> np.ndarray:
        """Mapped nodes :math:`\\lambda_k \\in [-1, 1]`, increasing."""
        return _readonly(kte_map(self.tau, self.alpha))

    @cached_property
    def barycentric_weights(self) -> np.ndarray:
        return _readonly(cgl_barycentric_weights(self.n)[::-1].copy())

    @cached_property
    def _derivative_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        d1, d2 = barycentric_differentiation(self.nodes, self.barycentric_weights)
        return _readonly(d1), _readonly(d2)

    @property
    def d1(self) -> np.ndarray:
        """First differentiation matrix with respect to :math:`\\lambda`."""
        return self._derivative_matrices[0]

    @property
    def d2(self) -> np.ndarray:
        """Second differentiation matrix with respect to :math:`\\lambda`."""
        return self._derivative_matrices[1]

    @cached_property
    def quadrature_weights(self) -> np.ndarray:
        """Weights of eq. (26): :math:`\\int_{-1}^1 f\\,d\\lambda \\approx \\sum_k w^c_k g'(\\tau_k) f(\\lambda_k)`."""
        cc = clenshaw_curtis_weights(self.n)[::-1]
        return _readonly(cc * kte_map_derivative(self.tau, self.alpha))

    def times(self, t0: float, tf: float) -> np.ndarray:
        """Node times, inverting eq. (17): :math:`t = t_0 + (\\lambda + 1)(t_f - t_0)/2`."""
        return t0 + (self.nodes + 1.0) * 0.5 * (tf - t0)

    def interpolation_matrix(self, lam: np.ndarray) -> np.ndarray:
        """Barycentric interpolation from the nodes to the points ``lam`` (in :math:`[-1, 1]`)."""
        return barycentric_interpolation_matrix(self.nodes, self.barycentric_weights, lam)

    def check_points(self, per_interval: int) -> np.ndarray:
        """``per_interval`` equally spaced points strictly inside each node interval."""
        if per_interval <= 0:
            return np.empty(0)
        frac = np.arange(1, per_interval + 1) / (per_interval + 1)
        left, right = self.nodes[:-1], self.nodes[1:]
        return (left[:, None] + (right - left)[:, None] * frac[None, :]).ravel()
