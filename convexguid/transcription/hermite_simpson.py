"""Hermite-Simpson collocation defects (compressed form) with their Jacobians.

On an interval of length :math:`h` with end states :math:`x_0, x_1` and controls
:math:`u_0, u_1`, the cubic Hermite interpolant of the states gives the midpoint state
and the control is interpolated linearly (Wang & Tang 2003, eqs. 5-6):

.. math::

    x_c = \\tfrac12 (x_0 + x_1) + \\tfrac{h}{8} (f_0 - f_1), \\qquad
    u_c = \\tfrac12 (u_0 + u_1), \\qquad f_k = f(x_k, u_k).

The paper's defect (eqs. 7-8), the collocation residual at the midpoint,
:math:`\\Delta = f(x_c, u_c) + \\tfrac{3}{2h}(x_0 - x_1) + \\tfrac14 (f_0 + f_1)`, equals
:math:`-\\tfrac{3}{2h}` times Simpson's rule residual

.. math::

    \\zeta = x_1 - x_0 - \\tfrac{h}{6} \\left(f_0 + 4 f_c + f_1\\right),

which is what :func:`hermite_simpson_defects` returns: it is measured in the states' own
units and stays well scaled when an interval shrinks to zero length (a burn arc
whose duration is a decision variable may do that). The two forms have the same roots.

References
----------
Wang H., Tang G., J. National Univ. of Defense Technology 25(5), 2003, eqs. (5)-(8).
Hargraves C. R., Paris S. W., "Direct trajectory optimization using nonlinear
programming and collocation", J. Guidance 10(4), 1987.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

Dynamics = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``f(x, u)`` on stacked rows ``x (K, nx)``, ``u (K, nu)`` -> ``(K, nx)``."""

DynamicsJacobian = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
"""``(df/dx (K, nx, nx), df/du (K, nx, nu))`` at stacked rows."""


@dataclass(frozen=True)
class IntervalMap:
    """Values of a map over ``K`` intervals (rows) and its partials in the interval's ends and length."""

    values: np.ndarray
    d_x0: np.ndarray
    d_u0: np.ndarray
    d_x1: np.ndarray
    d_u1: np.ndarray
    d_h: np.ndarray


@dataclass(frozen=True)
class HermiteSimpsonMidpoint(IntervalMap):
    """Midpoint states :math:`x_c` of ``K`` intervals and their partial derivatives (same layout as the defects).

    .. math::

        \\partial x_c/\\partial x_0 = \\tfrac12 I + \\tfrac{h}{8}F_0, \\quad
        \\partial x_c/\\partial x_1 = \\tfrac12 I - \\tfrac{h}{8}F_1, \\quad
        \\partial x_c/\\partial u_0 = \\tfrac{h}{8}G_0, \\quad
        \\partial x_c/\\partial u_1 = -\\tfrac{h}{8}G_1, \\quad
        \\partial x_c/\\partial h = \\tfrac18 (f_0 - f_1).

    Constraining a path function at :math:`x_c` as well as at the nodes halves the gap in
    which the interpolated trajectory is unchecked.
    """


@dataclass(frozen=True)
class HermiteSimpsonDefects(IntervalMap):
    """Defects :math:`\\zeta_k` of ``K`` intervals and their partial derivatives.

    ``d_x0[k]`` is :math:`\\partial\\zeta_k/\\partial x_0` (nx, nx), likewise ``d_u0``, ``d_x1``,
    ``d_u1`` (nx, nu for controls); ``d_h[k]`` is :math:`\\partial\\zeta_k/\\partial h_k` (nx,).
    """

    midpoint: HermiteSimpsonMidpoint


def hermite_simpson_midpoint(f: Dynamics, x0: np.ndarray, u0: np.ndarray, x1: np.ndarray, u1: np.ndarray,
                             h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint state and control of eqs. (5)-(6) on each interval (rows)."""
    h = np.asarray(h, float).reshape(-1, 1)
    xc = 0.5 * (x0 + x1) + h / 8 * (f(x0, u0) - f(x1, u1))
    return xc, 0.5 * (u0 + u1)


def hermite_simpson_defects(f: Dynamics, jac: DynamicsJacobian, x0: np.ndarray, u0: np.ndarray,
                            x1: np.ndarray, u1: np.ndarray, h: np.ndarray) -> HermiteSimpsonDefects:
    """Simpson defects of ``K`` intervals (rows of the arguments, ``h`` of shape ``(K,)``) and Jacobians.

    With :math:`F = \\partial f/\\partial x`, :math:`G = \\partial f/\\partial u` at the ends (0, 1) and at
    the midpoint (c), the chain rule through :math:`x_c, u_c` gives

    .. math::

        \\partial\\zeta/\\partial x_0 = -I - \\tfrac{h}{6}\\left(F_0 + 4F_c(\\tfrac12 I + \\tfrac{h}{8}F_0)\\right),
        \\qquad
        \\partial\\zeta/\\partial h = -\\tfrac16 (f_0 + 4 f_c + f_1) - \\tfrac{h}{12} F_c (f_0 - f_1),

    and likewise for :math:`x_1, u_0, u_1`.
    """
    h = np.asarray(h, float)
    hh = h[:, None, None]
    f0, f1 = f(x0, u0), f(x1, u1)
    xc, uc = hermite_simpson_midpoint(f, x0, u0, x1, u1, h)
    fc = f(xc, uc)
    F0, G0 = jac(x0, u0)
    F1, G1 = jac(x1, u1)
    Fc, Gc = jac(xc, uc)
    eye = np.eye(x0.shape[1])
    values = x1 - x0 - h[:, None] / 6 * (f0 + 4 * fc + f1)
    d_x0 = -eye - hh / 6 * (F0 + 4 * Fc @ (0.5 * eye + hh / 8 * F0))
    d_x1 = eye - hh / 6 * (F1 + 4 * Fc @ (0.5 * eye - hh / 8 * F1))
    d_u0 = -hh / 6 * (G0 + 4 * (hh / 8 * Fc @ G0 + 0.5 * Gc))
    d_u1 = -hh / 6 * (G1 + 4 * (-hh / 8 * Fc @ G1 + 0.5 * Gc))
    d_h = -(f0 + 4 * fc + f1) / 6 - h[:, None] / 12 * np.einsum("kij,kj->ki", Fc, f0 - f1)
    midpoint = HermiteSimpsonMidpoint(xc, 0.5 * eye + hh / 8 * F0, hh / 8 * G0, 0.5 * eye - hh / 8 * F1, -hh / 8 * G1,
                                      (f0 - f1) / 8)
    return HermiteSimpsonDefects(values, d_x0, d_u0, d_x1, d_u1, d_h, midpoint)
