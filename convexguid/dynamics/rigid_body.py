"""Rigid-body attitude dynamics, :math:`I\\dot\\omega + \\omega \\times I\\omega = u`, with quaternion kinematics.

Quaternions are scalar-last ``[x, y, z, w]``, Hamilton product, body relative to
inertial (see :mod:`convexguid.rotations`); rates are body-frame, in rad/s.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from convexguid.rotations import quat_derivative


def euler_torque(inertia: np.ndarray, omega: np.ndarray, omega_dot: np.ndarray) -> np.ndarray:
    """Torque that produces ``omega_dot`` at rate ``omega`` (Euler's equations, Cai et al. eq. 1 and 12).

    .. math:: u = I\\dot\\omega + \\omega \\times (I \\omega)

    Vectorised over a leading axis; accepts complex input (for complex-step derivatives).
    """
    i_omega = omega @ inertia.T
    return omega_dot @ inertia.T + np.cross(omega, i_omega)


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
