r"""Closed-loop simulation of a rigid spacecraft with reaction wheels (Guo, Li, Ma 2011, Sec. 1 and 4).

Plant (eqs. 1-2 and 4 of the paper; body axes, wheel momentum :math:`h_w` relative to the body):

.. math::
    I\dot\omega + \omega^\times (I\omega + h_w) = u_c + u_d, \qquad \dot h_w = -u_c, \qquad
    \dot q = \tfrac12\, q \otimes [\omega, 0].

(The extraction prints :math:`\dot I \omega` in eqs. 1-2; :math:`I\dot\omega` is meant.) The control law
switches (repulsive potential on/off, escape law), so the loop is integrated with **fixed-step classical RK4**:
the controller is sampled once at the start of each step and its torque held constant over the step
(zero-order hold, like a flight computer running at ``1/dt`` Hz); the disturbance is evaluated continuously at
the RK4 stage times. The quaternion is renormalised after each step. Wheel momentum is not saturated (its
largest component is reported by :func:`maneuver_metrics`).

Conventions are those of :mod:`convexguid.rotations` (scalar-last quaternions, body relative to inertial);
angles are radians except in fields whose names end in ``_deg``.

References
----------
Guo Yanning, Li Chuanjiang, Ma Guangfu, "Spacecraft autonomous attitude maneuver control by potential function
method", Acta Aeronautica et Astronautica Sinica 32(3), 457-464, 2011 (eqs. 1-4, Table 1, Sec. 4).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from convexguid.checks import finite_vector, inertia_matrix, unit_vector
from convexguid.dynamics.disturbance import guo2011_disturbance
from convexguid.errors import SpecError
from convexguid.families.potential_function.controller import ControlInfo
from convexguid.progress import report
from convexguid.rotations import axis_angle_to_quat, cross3, quat_angle_between, quat_normalize

__all__ = [
    "GUO2011_INERTIA", "GUO2011_Q0", "GUO2011_Q_COMMAND", "GUO2011_Q_FORBIDDEN", "quaternion_rate", "settling_time",
    "SimulationResult", "ManeuverMetrics", "simulate", "maneuver_metrics",
]


def _frozen(a: ArrayLike) -> NDArray:
    arr = np.array(a, dtype=float)
    arr.setflags(write=False)
    return arr


GUO2011_INERTIA = _frozen(np.diag([800.0, 750.0, 600.0]))
"""Inertia (kg m^2) of Table 1."""
GUO2011_Q0 = _frozen([0.0, 0.0, 0.0, 1.0])
"""Initial attitude of Table 1."""
GUO2011_Q_COMMAND = _frozen(axis_angle_to_quat([0.0, 0.0, 1.0], math.pi / 2))
"""Command attitude: 90 deg about z (Sec. 4; Table 1 prints the rounded [0, 0, 0.707, 0.707])."""
GUO2011_Q_FORBIDDEN = _frozen(axis_angle_to_quat([0.0, 0.0, 1.0], math.pi / 4))
"""Forbidden attitude: 45 deg about z (Sec. 4; Table 1 prints the rounded [0, 0, 0.383, 0.924])."""


def quaternion_rate(q: NDArray, omega: NDArray) -> NDArray:
    r"""Kinematics of eq. 4, :math:`\dot q_v = \tfrac12(q_4\omega - \omega^\times q_v)`,
    :math:`\dot q_4 = -\tfrac12 \omega^T q_v`.

    The same as :func:`convexguid.rotations.quat_derivative` (:math:`\tfrac12 q \otimes [\omega, 0]`), written
    out for one quaternion because the integrator calls it four times per step.
    """
    return 0.5 * np.concatenate([q[3] * omega + cross3(q[:3], omega), [-(omega @ q[:3])]])


class AttitudeController(Protocol):
    """What :func:`simulate` needs of a controller."""

    q_command: NDArray

    def torque(self, t: float, q: NDArray, omega: NDArray, h_w: NDArray | None = None
               ) -> tuple[NDArray, ControlInfo]: ...


@dataclass(frozen=True)
class SimulationResult:
    r"""Sampled closed-loop trajectory; ``N + 1`` samples at ``t = 0, dt, ..., N dt``.

    ``u[k]`` is the torque held over :math:`[t_k, t_{k+1})`; the last entry is the controller output at the
    final state (not applied). Per-sample controller diagnostics come from :class:`ControlInfo`.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        Sample times (s).
    q : ndarray, shape (N+1, 4)
        Attitude, scalar-last.
    omega, h_w, u : ndarray, shape (N+1, 3)
        Body rate (rad/s), wheel momentum (N m s), applied control torque (N m).
    u_unclipped : ndarray, shape (N+1, 3)
        Control law output before clipping to the torque limit (N m).
    theta_e : ndarray, shape (N+1,)
        Principal Euler-axis angle to ``q_command`` (rad).
    theta_b : ndarray, shape (N+1,)
        Euler-axis angle to the forbidden attitude (rad; NaN without one).
    potential_active, escape_active, saturated : ndarray of bool, shape (N+1,)
        Repulsive potential on, escape law (eq. 32) on, torque clipped to the limit.
    mu, s, g : ndarray, shape (N+1,)
        Gains in use.
    dt : float
        Integration step and control period (s).
    q_command : ndarray, shape (4,)
        Command attitude the errors refer to.
    """

    t: NDArray
    q: NDArray
    omega: NDArray
    h_w: NDArray
    u: NDArray
    u_unclipped: NDArray
    theta_e: NDArray
    theta_b: NDArray
    potential_active: NDArray
    escape_active: NDArray
    saturated: NDArray
    mu: NDArray
    s: NDArray
    g: NDArray
    dt: float
    q_command: NDArray


@dataclass(frozen=True)
class ManeuverMetrics:
    """Summary of a run (see :func:`maneuver_metrics`).

    Attributes
    ----------
    t_1deg, t_01deg : float or None
        First time (s) after which the attitude error stays below 1 deg / 0.1 deg; None if it never does.
    min_theta_b_deg : float
        Smallest Euler-axis angle to the forbidden attitude (deg; NaN without one).
    t_min_theta_b : float
        Time (s) at which it occurs (NaN without a forbidden attitude).
    max_abs_u : float
        Largest applied torque component (N m).
    energy : float
        :math:`\\int \\|u\\|^2 dt` (N^2 m^2 s), exact for the zero-order-held torque.
    final_error_deg : float
        Attitude error at ``t_final`` (deg).
    final_rate : float
        Rate error :math:`\\|\\omega\\|` at ``t_final`` (rad/s; the command is inertially fixed).
    max_abs_h_w : float
        Largest wheel-momentum component (N m s).
    """

    t_1deg: float | None
    t_01deg: float | None
    min_theta_b_deg: float
    t_min_theta_b: float
    max_abs_u: float
    energy: float
    final_error_deg: float
    final_rate: float
    max_abs_h_w: float


def simulate(controller: AttitudeController, inertia: ArrayLike, q0: ArrayLike, omega0: ArrayLike,
             q_command: ArrayLike, t_final: float, dt: float,
             disturbance: Callable[[float], NDArray] = guo2011_disturbance,
             h_w0: ArrayLike | None = None) -> SimulationResult:
    """Integrate the closed loop with fixed-step RK4 and a zero-order-held control torque.

    Parameters
    ----------
    controller : AttitudeController
        E.g. :class:`~convexguid.families.potential_function.controller.PotentialFunctionController`; its ``torque(t, q,
        omega, h_w)`` is sampled once per step.
    inertia : array_like, shape (3, 3)
        Plant inertia (kg m^2); may differ from the controller's model.
    q0, omega0 : array_like
        Initial attitude (scalar-last) and body rate (rad/s).
    q_command : array_like, shape (4,)
        Command attitude against which errors are recorded; must equal ``controller.q_command`` up to sign.
    t_final, dt : float
        Final time and step (s); ``t_final / dt`` is rounded to a whole number of steps.
    disturbance : callable, optional
        ``u_d(t)`` in body axes (N m); default: the paper's (:func:`guo2011_disturbance`).
    h_w0 : array_like, shape (3,), optional
        Initial wheel momentum (N m s); zero by default.

    Returns
    -------
    SimulationResult

    Raises
    ------
    SpecError
        For invalid inputs or a ``q_command`` that differs from the controller's.
    """
    inertia = inertia_matrix(inertia)
    if not (math.isfinite(dt) and math.isfinite(t_final) and 0 < dt <= t_final):
        raise SpecError(f"need 0 < dt <= t_final, got dt = {dt!r}, t_final = {t_final!r}")
    q_command = unit_vector("q_command", q_command, 4)
    if quat_angle_between(q_command, controller.q_command) > 1e-9:
        raise SpecError(f"q_command {q_command.tolist()} differs from the controller's "
                        f"{np.asarray(controller.q_command).tolist()}")
    inertia_inv = np.linalg.inv(inertia)
    n_steps = int(round(t_final / dt))

    def rhs(t: float, y: NDArray, u: NDArray) -> NDArray:
        q, w, h = y[:4], y[4:7], y[7:]
        w_dot = inertia_inv @ (u + disturbance(t) - cross3(w, inertia @ w + h))
        return np.concatenate([quaternion_rate(q, w), w_dot, -u])

    y = np.concatenate([unit_vector("q0", q0, 4), finite_vector("omega0", omega0, 3),
                        np.zeros(3) if h_w0 is None else finite_vector("h_w0", h_w0, 3)])
    ys = np.empty((n_steps + 1, 10))
    us = np.empty((n_steps + 1, 3))
    infos: list[ControlInfo] = []
    for k in range(n_steps + 1):
        report("simulation step", k, n_steps)
        t = k * dt
        ys[k] = y
        u, info = controller.torque(t, y[:4], y[4:7], y[7:])
        us[k] = u
        infos.append(info)
        if k == n_steps:
            break
        k1 = rhs(t, y, u)
        k2 = rhs(t + dt / 2, y + dt / 2 * k1, u)
        k3 = rhs(t + dt / 2, y + dt / 2 * k2, u)
        k4 = rhs(t + dt, y + dt * k3, u)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        y[:4] = quat_normalize(y[:4])

    def field(name: str, dtype: type = float) -> NDArray:
        return np.array([getattr(i, name) for i in infos], dtype=dtype)

    return SimulationResult(
        t=np.arange(n_steps + 1) * dt, q=ys[:, :4], omega=ys[:, 4:7], h_w=ys[:, 7:], u=us,
        u_unclipped=np.array([i.u_unclipped for i in infos]),
        theta_e=quat_angle_between(q_command, ys[:, :4]), theta_b=field("theta_b"),
        potential_active=field("potential_active", bool), escape_active=field("escape_active", bool),
        saturated=field("saturated", bool), mu=field("mu"), s=field("s"), g=field("g"), dt=float(dt),
        q_command=q_command)


def settling_time(t: NDArray, error: NDArray, threshold: float) -> float | None:
    """First time after which ``error`` stays below ``threshold`` (None if it ends at or above it)."""
    above = np.flatnonzero(error >= threshold)
    if above.size == 0:
        return float(t[0])
    if above[-1] == len(t) - 1:
        return None
    return float(t[above[-1] + 1])


def maneuver_metrics(result: SimulationResult) -> ManeuverMetrics:
    """Maneuver times, closest approach to the forbidden attitude, torque, energy and final errors of a run.

    Parameters
    ----------
    result : SimulationResult

    Returns
    -------
    ManeuverMetrics
    """
    err = result.theta_e
    has_b = not np.all(np.isnan(result.theta_b))
    k_min = int(np.nanargmin(result.theta_b)) if has_b else -1
    applied = result.u[:-1]
    return ManeuverMetrics(
        t_1deg=settling_time(result.t, err, math.radians(1.0)),
        t_01deg=settling_time(result.t, err, math.radians(0.1)),
        min_theta_b_deg=math.degrees(result.theta_b[k_min]) if has_b else math.nan,
        t_min_theta_b=float(result.t[k_min]) if has_b else math.nan,
        max_abs_u=float(np.abs(applied).max()),
        energy=float(np.sum(applied * applied) * result.dt),
        final_error_deg=math.degrees(err[-1]),
        final_rate=float(np.linalg.norm(result.omega[-1])),
        max_abs_h_w=float(np.abs(result.h_w).max()),
    )
