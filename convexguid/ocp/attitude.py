"""Rigid-body attitude as CasADi expressions, for problems stated with :class:`convexguid.ocp.Problem`.

Quaternions are scalar last, body relative to inertial (the convention of :mod:`convexguid.rotations`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def quaternion_rate(q, omega) -> ca.SX:
    """:math:`\\dot q = \\tfrac12\\, q \\otimes [\\omega, 0]`: four expressions for the quaternion ``q`` (four
    symbols) and the body rate ``omega`` (three)."""
    qv, q4, w = ca.vertcat(*q[:3]), q[3], ca.vertcat(*omega)
    return 0.5 * ca.vertcat(q4 * w + ca.cross(qv, w), -ca.dot(qv, w))


def body_rate_rate(omega, torque, inertia) -> ca.SX:
    """Euler's equations :math:`\\dot\\omega = I^{-1}(u - \\omega \\times I\\omega)` for a full inertia matrix."""
    inertia = np.asarray(inertia, dtype=float)
    w, u = ca.vertcat(*omega), ca.vertcat(*torque)
    return ca.mtimes(ca.DM(np.linalg.inv(inertia)), u - ca.cross(w, ca.mtimes(ca.DM(inertia), w)))


def rigid_body_dynamics(q, omega, torque, inertia) -> dict:
    """The ``{symbol: rate}`` mapping :meth:`~convexguid.ocp.problem.Problem.dynamics` takes, for quaternion and
    body-rate states driven by body torques."""
    rates = ca.vertcat(quaternion_rate(q, omega), body_rate_rate(omega, torque, inertia))
    return dict(zip([*q, *omega], ca.vertsplit(rates), strict=True))


def inertial_direction(q, body_vector) -> ca.SX:
    """The body-fixed ``body_vector`` in inertial axes at attitude ``q``."""
    qv, q4, b = ca.vertcat(*q[:3]), q[3], ca.DM(np.asarray(body_vector, dtype=float))
    return b + 2 * q4 * ca.cross(qv, b) + 2 * ca.cross(qv, ca.cross(qv, b))
