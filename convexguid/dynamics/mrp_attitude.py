"""Rigid-body attitude in modified Rodrigues parameters (MRPs), and its error dynamics about a nominal.

State :math:`x = [\\sigma, \\omega]` (MRPs of the body relative to inertial, body rates in rad/s):

.. math::

    \\dot\\sigma = G(\\sigma)\\,\\omega, \\qquad
    G(\\sigma) = \\tfrac14\\big[(1 - \\sigma^T\\sigma) I + 2 S(\\sigma) + 2 \\sigma\\sigma^T\\big],
    \\qquad J\\dot\\omega = -S(\\omega) J\\omega + u + d

(Feng, Chen, Yang 2018, eqs. 1-3 and 5). Linearized about a nominal :math:`(\\tilde x, \\tilde u)`, the
deviation obeys :math:`\\delta\\dot x = A(t)\\,\\delta x + B(t)\\,\\delta u` (eq. 11) with

.. math::

    A = \\begin{bmatrix} A_{11} & G(\\sigma) \\\\ 0 & A_{22} \\end{bmatrix}, \\quad
    B = \\begin{bmatrix} 0 \\\\ J^{-1} \\end{bmatrix}, \\quad
    A_{11} = \\tfrac12\\big[(\\sigma^T\\omega) I + \\sigma\\omega^T - \\omega\\sigma^T - S(\\omega)\\big], \\quad
    A_{22} = J^{-1}\\big[S(J\\omega) - S(\\omega) J\\big]

(eqs. 12-19, derived here from eq. 1; the paper's printed forms were lost in extraction). Every
function takes a leading batch axis and complex input (for complex-step checks).
"""

from __future__ import annotations

import numpy as np

from convexguid.rotations import skew


def mrp_kinematics_matrix(sigma: np.ndarray) -> np.ndarray:
    """:math:`G(\\sigma)`, shape ``(..., 3, 3)`` (eq. 3)."""
    s = np.asarray(sigma)
    sts = np.sum(s * s, -1)[..., None, None]
    eye = np.eye(3)
    return 0.25 * ((1 - sts) * eye + 2 * skew(s) + 2 * s[..., :, None] * s[..., None, :])


def mrp_state_derivative(x: np.ndarray, u: np.ndarray, inertia: np.ndarray, inertia_inv: np.ndarray) -> np.ndarray:
    """:math:`\\dot x` for states ``x`` (..., 6) under torques ``u`` (..., 3) (disturbance included in ``u``)."""
    sigma, omega = x[..., :3], x[..., 3:]
    sigma_dot = np.einsum("...ij,...j->...i", mrp_kinematics_matrix(sigma), omega)
    omega_dot = (u - np.cross(omega, omega @ inertia.T)) @ inertia_inv.T
    return np.concatenate([sigma_dot, omega_dot], -1)


def mrp_error_matrices(x: np.ndarray, inertia: np.ndarray, inertia_inv: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """:math:`A(t)` (..., 6, 6) and :math:`B(t)` (..., 6, 3) of the error dynamics at nominal states ``x``."""
    x = np.asarray(x)
    sigma, omega = x[..., :3], x[..., 3:]
    batch = x.shape[:-1]
    eye = np.eye(3)
    s_dot_w = np.sum(sigma * omega, -1)[..., None, None]
    a11 = 0.5 * (s_dot_w * eye + sigma[..., :, None] * omega[..., None, :]
                 - omega[..., :, None] * sigma[..., None, :] - skew(omega))
    j_omega = omega @ inertia.T
    a22 = inertia_inv @ (skew(j_omega) - skew(omega) @ inertia)
    A = np.zeros((*batch, 6, 6), dtype=np.result_type(x, float))
    A[..., :3, :3] = a11
    A[..., :3, 3:] = mrp_kinematics_matrix(sigma)
    A[..., 3:, 3:] = a22
    B = np.zeros((*batch, 6, 3))
    B[..., 3:, :] = inertia_inv
    return A, B


def _derivative_1(x: np.ndarray, u: np.ndarray, inertia: np.ndarray, inertia_inv: np.ndarray) -> np.ndarray:
    """:func:`mrp_state_derivative` of one real state, written out (the batched form costs ~25x more per call)."""
    s1, s2, s3, w1, w2, w3 = x
    sts, sw = s1 * s1 + s2 * s2 + s3 * s3, s1 * w1 + s2 * w2 + s3 * w3
    a = 1.0 - sts
    sigma_dot = (0.25 * (a * w1 + 2.0 * (s2 * w3 - s3 * w2) + 2.0 * s1 * sw),
                 0.25 * (a * w2 + 2.0 * (s3 * w1 - s1 * w3) + 2.0 * s2 * sw),
                 0.25 * (a * w3 + 2.0 * (s1 * w2 - s2 * w1) + 2.0 * s3 * sw))
    h = inertia @ x[3:]
    gyro = np.array([w2 * h[2] - w3 * h[1], w3 * h[0] - w1 * h[2], w1 * h[1] - w2 * h[0]])
    return np.concatenate([sigma_dot, inertia_inv @ (u - gyro)])


def rk4_step(x: np.ndarray, u: np.ndarray, dt: float, inertia: np.ndarray, inertia_inv: np.ndarray) -> np.ndarray:
    """One classical Runge-Kutta step of length ``dt`` for one state, with the torque ``u`` held constant."""
    k1 = _derivative_1(x, u, inertia, inertia_inv)
    k2 = _derivative_1(x + 0.5 * dt * k1, u, inertia, inertia_inv)
    k3 = _derivative_1(x + 0.5 * dt * k2, u, inertia, inertia_inv)
    k4 = _derivative_1(x + dt * k3, u, inertia, inertia_inv)
    return x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def shortest_mrp(sigma: np.ndarray) -> np.ndarray:
    """The MRP set with :math:`|\\sigma| \\le 1` (the shadow set where the norm exceeds 1); quaternion :math:`w \\ge 0`.

    Feng et al. Sec. 2.2 keep the quaternion's scalar part non-negative so that a small attitude error
    is a small MRP error; this is the same rule in MRPs.
    """
    s = np.asarray(sigma, dtype=float)
    if s.ndim == 1:
        n2 = float(s @ s)
        return -s / n2 if n2 > 1.0 else s
    n2 = np.sum(s * s, -1, keepdims=True)
    return np.where(n2 > 1.0, -s / np.where(n2 > 0, n2, 1.0), s)
