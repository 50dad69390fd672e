"""LQR baselines of Feng, Chen, Yang (2018): tracking a nominal, and regulating straight to the target.

Both re-linearize the MRP attitude dynamics (:func:`~convexguid.dynamics.mrp_attitude.mrp_error_matrices`)
at every command and solve the continuous algebraic Riccati equation for the gain
:math:`K = R^{-1} B^T S` (frozen-time LQR, weights :math:`Q = q I_6`, :math:`R = r I_3` as in the paper's
Sec. 3.1):

* tracking: :math:`u = \\tilde u(t) - K(\\tilde x(t))\\,(x - \\tilde x(t))`, linearized on the nominal;
* direct: :math:`u = -K(x)\\,(x - x_f)`, linearized at the measured state, no nominal.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_continuous_are

from convexguid.dynamics.mrp_attitude import mrp_error_matrices
from convexguid.families.lpmpc.tracking import Nominal


def lqr_gain(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray) -> np.ndarray:
    """:math:`K = R^{-1} B^T S` with :math:`S` the stabilizing solution of the CARE."""
    S = solve_continuous_are(A, B, Q, R)
    return np.linalg.solve(R, B.T @ S)


class LqrTracker:
    """Frozen-time LQR about the nominal (the paper's "LQR tracking the nominal")."""

    def __init__(self, name: str, nominal: Nominal, inertia: np.ndarray, q: float, r: float) -> None:
        self.name, self.nominal = name, nominal
        self.inertia, self.inertia_inv = inertia, np.linalg.inv(inertia)
        self.Q, self.R = q * np.eye(6), r * np.eye(3)

    def command(self, t: float, measured: np.ndarray) -> np.ndarray:
        x_nom = self.nominal.state(t)
        A, B = mrp_error_matrices(x_nom, self.inertia, self.inertia_inv)
        return self.nominal.control(t) - lqr_gain(A, B, self.Q, self.R) @ (measured - x_nom)


class LqrRegulator:
    """Frozen-time LQR from the measured state straight to the target (the paper's "LQR direct")."""

    def __init__(self, name: str, target: np.ndarray, inertia: np.ndarray, q: float, r: float) -> None:
        self.name, self.target = name, np.asarray(target, dtype=float)
        self.inertia, self.inertia_inv = inertia, np.linalg.inv(inertia)
        self.Q, self.R = q * np.eye(6), r * np.eye(3)

    def command(self, t: float, measured: np.ndarray) -> np.ndarray:
        A, B = mrp_error_matrices(measured, self.inertia, self.inertia_inv)
        return -lqr_gain(A, B, self.Q, self.R) @ (measured - self.target)
