"""Rigid-body attitude dynamics, :math:`I\\dot\\omega + \\omega \\times I\\omega = u`, with quaternion kinematics.

Quaternions are scalar-last ``[x, y, z, w]``, Hamilton product, body relative to
inertial (see :mod:`convexguid.rotations`); rates are body-frame, in rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from convexguid.rotations import cross_rows, quat_derivative


def euler_torque(inertia: np.ndarray, omega: np.ndarray, omega_dot: np.ndarray) -> np.ndarray:
    """Torque that produces ``omega_dot`` at rate ``omega`` (Euler's equations, Cai et al. eq. 1 and 12).

    .. math:: u = I\\dot\\omega + \\omega \\times (I \\omega)

    Vectorised over a leading axis; accepts complex input (for complex-step derivatives).
    """
    i_omega = omega @ inertia.T
    return omega_dot @ inertia.T + cross_rows(omega, i_omega)


def rigid_body_rhs(inertia: np.ndarray, torque: Callable[[float], np.ndarray]
                   ) -> Callable[[float, np.ndarray], np.ndarray]:
    """Right-hand side of the state ``[q (4), omega (3)]`` under the commanded body torque ``torque(t)``.

    .. math:: \\dot q = \\tfrac12 q \\otimes [\\omega, 0], \\qquad
              \\dot\\omega = I^{-1}\\,(u - \\omega \\times I\\omega)
    """
    inertia_inv = np.linalg.inv(inertia)

    def rhs(t: float, state: np.ndarray) -> np.ndarray:
        q, omega = state[:4], state[4:]
        omega_dot = inertia_inv @ (torque(t) - np.cross(omega, inertia @ omega))
        return np.concatenate([quat_derivative(q, omega), omega_dot])

    return rhs


def rigid_body_rhs_fast(inertia: np.ndarray, torque: Callable[[float], np.ndarray]
                        ) -> Callable[[float, np.ndarray], np.ndarray]:
    """:func:`rigid_body_rhs` written out for one state: the same equations, a fraction of the cost.

    The seven state components, the torque and the 3x3 products with the inertia and its inverse
    are plain floats; the only allocation per call is the result. Made for an integrator's inner
    loop (a dense check calls it thousands of times), where NumPy's per-call overhead on length-3
    arrays dominated. ``torque(t)`` returns three numbers (an array or a sequence). Agrees with
    :func:`rigid_body_rhs` to rounding.
    """
    (i11, i12, i13), (i21, i22, i23), (i31, i32, i33) = np.asarray(inertia, dtype=float).tolist()
    (j11, j12, j13), (j21, j22, j23), (j31, j32, j33) = np.linalg.inv(inertia).tolist()

    def rhs(t: float, state: np.ndarray) -> np.ndarray:
        x, y, z, w, p, q, r = state.tolist()
        u = torque(t)
        u1, u2, u3 = u.tolist() if isinstance(u, np.ndarray) else u
        h1 = i11 * p + i12 * q + i13 * r  # I omega
        h2 = i21 * p + i22 * q + i23 * r
        h3 = i31 * p + i32 * q + i33 * r
        e1 = u1 - (q * h3 - r * h2)  # u - omega x I omega
        e2 = u2 - (r * h1 - p * h3)
        e3 = u3 - (p * h2 - q * h1)
        return np.array([0.5 * (w * p + (y * r - z * q)), 0.5 * (w * q + (z * p - x * r)),
                         0.5 * (w * r + (x * q - y * p)), -0.5 * (x * p + y * q + z * r),
                         j11 * e1 + j12 * e2 + j13 * e3, j21 * e1 + j22 * e2 + j23 * e3,
                         j31 * e1 + j32 * e2 + j33 * e3])

    return rhs


def min_slew_time(inertia: np.ndarray, torque_norm_max: float, angle_rad: float, momentum0: float = 0.0,
                  momentum_f: float = 0.0) -> float:
    """A lower bound on the duration of any maneuver through the rotation angle ``angle_rad``, s.

    The angular momentum changes at most at the rate ``torque_norm_max`` (the largest Euclidean norm of an
    admissible torque, N m), so from ``momentum0`` at the start and back to ``momentum_f`` at the end (N m s)
    :math:`|H(t)| \\le \\min(H_0 + \\tau t,\\; H_f + \\tau (T - t))`; the body rate is at most
    :math:`|H| / \\lambda_{min}(I)` and the rotation angle at most its integral. The bound is the shortest
    ``T`` whose integral reaches the angle; rest to rest it is the bang-bang time
    :math:`T = 2\\sqrt{\\theta \\lambda_{min} / \\tau}`. It holds for every path (not only the eigenaxis one).
    """
    needed = angle_rad * float(np.linalg.eigvalsh(inertia)[0])  # integral of |H| dt the rotation needs
    tau, a, b = torque_norm_max, momentum0, momentum_f

    def reachable(T: float) -> float:  # integral over [0, T] of min(a + tau t, b + tau (T - t))
        cross = min(max((b - a + tau * T) / (2 * tau), 0.0), T)
        return a * cross + 0.5 * tau * cross**2 + b * (T - cross) + 0.5 * tau * (T - cross) ** 2

    if needed <= 0.0:
        return 0.0
    if a == b == 0.0:
        return 2.0 * math.sqrt(needed / tau)
    high = 1.0
    while reachable(high) < needed:
        high *= 2.0
    low = 0.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if reachable(mid) < needed else (low, mid)
    return low
