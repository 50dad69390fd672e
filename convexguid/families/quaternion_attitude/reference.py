"""IPOPT reference for the quaternion attitude transcription (independent of the SCP code's maps).

The nonlinear program of :mod:`convexguid.families.quaternion_attitude.program` is solved once
more with CasADi + IPOPT (exact Hessians). Only the variable *layout* (node-major rows
``[q (4, scalar-last), omega (3), u (3)]`` for ``K + 1`` nodes, then :math:`t_f` when the final
time is free), the case data (:class:`~convexguid.families.quaternion_attitude.program.AttitudeCase`)
and the numeric initial guess are shared with the SCP code. The rigid-body dynamics, the
Hermite-Simpson defects, the pointing-cone cosines and the forbidden-attitude rows are written
again here in CasADi symbols, so a slip in either implementation shows up as a different optimum
(or as a residual of the other implementation's constraints).

With :math:`q = [v, w]` (scalar last), body rate :math:`\\omega`, torque :math:`u`, inertia
:math:`I` (full matrix) and the Hamilton product
:math:`p \\otimes q = [p_w q_v + q_w p_v + p_v \\times q_v,\\; p_w q_w - p_v\\cdot q_v]`:

.. math::

    \\dot q = \\tfrac12\\, q \\otimes [\\omega, 0]
            = \\tfrac12 [\\,w\\,\\omega + v \\times \\omega,\\; -v\\cdot\\omega\\,], \\qquad
    \\dot\\omega = I^{-1}(u - \\omega \\times I\\omega).

On ``K`` equal intervals, :math:`h = t_f / K`, with :math:`f_k = f(x_k, u_k)`:

.. math::

    x_c = \\tfrac12 (x_k + x_{k+1}) + \\tfrac{h}{8}(f_k - f_{k+1}), \\quad
    u_c = \\tfrac12 (u_k + u_{k+1}), \\quad
    x_{k+1} - x_k - \\tfrac{h}{6}\\left(f_k + 4 f(x_c, u_c) + f_{k+1}\\right) = 0,

    \\min t_f \\quad\\text{or}\\quad
    \\min \\sum_k \\tfrac{h}{6}\\left(|u_k|^2 + 4 |u_c|^2 + |u_{k+1}|^2\\right) \\;(t_f \\text{ fixed}),

    \\text{s.t.}\\quad x_0 = x_0^{given},\\; x_K = x_f^{given}, \\quad
    |\\omega_{k,i}| \\le \\omega_{max}, \\quad |u_{k,i}| \\le u_{max,i}, \\quad
    t_f \\ge 10^{-3}\\, t_f^{guess},

    c_k = b^T C_{BI}(q_k)\\, r
        = (w^2 - v^Tv)\\, b^Tr + 2 (b^Tv)(v^Tr) - 2 w\\, v^T(r \\times b), \\quad
    c_k \\le \\cos(\\theta + m) \\;\\text{(keep-out)}, \\quad
    c_k \\ge \\cos(\\alpha - m) \\;\\text{(keep-in)},

    |q_b \\cdot q_k| \\le \\cos\\left((\\theta_m + m)/2\\right) \\;\\text{(forbidden attitude)},

for every node :math:`k`, the rate box, the cones and the forbidden attitudes also at every interval midpoint
:math:`x_c = \\tfrac12(x_k + x_{k+1}) + \\tfrac{h}{8}(f_k - f_{k+1})`, with the node margin :math:`m`
(angles clipped to :math:`[0, \\pi]`).
:math:`C_{BI}(q)` is the unnormalised quadratic form, exactly as in the SCP transcription (no
unit-norm constraint: the kinematics conserve :math:`|q|`). IPOPT works on scaled variables
(quaternions as they are, rates divided by the slew's natural rate (:func:`natural_rate`, as the SCP),
torques by their axis bounds
:math:`u_{max,i}`, :math:`t_f` by its guess) and on defect rows divided by the same state scales; the
objective is :math:`t_f / t_f^{guess}` or the energy divided by :math:`\\max_i u_{max,i}^2\\, t_f`.
Boundary states, rate and torque boxes and the lower bound on :math:`t_f` are variable bounds.

References
----------
Wang, Xu, Li, path-transfer fast planning for large-angle attitude maneuvers under multiple
constraints (seed 003): quaternion model and pointing constraint :math:`b^T C(q) r \\le \\cos\\theta`.
Guo, Li, Ma 2011 (seed 001), eq. (7): the forbidden-attitude distance.
Hargraves C. R., Paris S. W., "Direct trajectory optimization using nonlinear programming
and collocation", J. Guidance 10(4), 1987 (Hermite-Simpson collocation).
Waechter A., Biegler L. T., "On the implementation of an interior-point filter line-search
algorithm for large-scale nonlinear programming", Math. Programming 106, 2006 (IPOPT).
Andersson J. et al., "CasADi: a software framework for nonlinear optimization and optimal
control", Math. Programming Computation 11, 2019.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from convexguid.families.quaternion_attitude.program import NODE, NX, AttitudeCase, natural_rate
from convexguid.reference import ReferenceResult

__all__ = ["solve_quaternion_attitude_ipopt"]


def _dynamics_function(ca: Any, inertia: np.ndarray) -> Any:
    """CasADi function :math:`f(x, u) = [\\tfrac12 q\\otimes[\\omega, 0],\\; I^{-1}(u - \\omega\\times I\\omega)]`."""
    x, u = ca.SX.sym("x", NX), ca.SX.sym("u", 3)
    v, w, omega = x[0:3], x[3], x[4:7]
    qdot = 0.5 * ca.vertcat(w * omega + ca.cross(v, omega), -ca.dot(v, omega))
    inertia_dm = ca.DM(np.asarray(inertia, dtype=float))
    omega_dot = ca.solve(inertia_dm, u - ca.cross(omega, ca.mtimes(inertia_dm, omega)))
    return ca.Function("rigid_body", [x, u], [ca.vertcat(qdot, omega_dot)])


def _simpson_defect_function(ca: Any, f: Any) -> Any:
    """CasADi function of one interval: :math:`x_1 - x_0 - \\tfrac{h}{6}(f_0 + 4f_c + f_1)`."""
    x0, x1 = ca.SX.sym("x0", NX), ca.SX.sym("x1", NX)
    u0, u1 = ca.SX.sym("u0", 3), ca.SX.sym("u1", 3)
    h = ca.SX.sym("h")
    f0, f1 = f(x0, u0), f(x1, u1)
    xc = (x0 + x1) / 2 + h / 8 * (f0 - f1)
    defect = x1 - x0 - h / 6 * (f0 + 4 * f(xc, (u0 + u1) / 2) + f1)
    return ca.Function("simpson_defect", [x0, u0, x1, u1, h], [defect, xc])


def _cone_cosine(ca: Any, q: Any, body_axis: np.ndarray, inertial_dir: np.ndarray) -> Any:
    """:math:`b^T C_{BI}(q) r` with the unnormalised :math:`C_{BI} = (w^2 - v^Tv)I + 2vv^T - 2w[v\\times]`."""
    v, w = q[0:3], q[3]
    b = ca.DM(np.asarray(body_axis, dtype=float))
    r = ca.DM(np.asarray(inertial_dir, dtype=float))
    dcm = (w**2 - ca.dot(v, v)) * ca.DM.eye(3) + 2 * ca.mtimes(v, v.T) - 2 * w * ca.skew(v)
    return ca.mtimes(b.T, ca.mtimes(dcm, r))


def solve_quaternion_attitude_ipopt(case: AttitudeCase, intervals: int, guess: np.ndarray, tf_guess: float,
                                    margin: float = 0.0, max_iter: int = 3000,
                                    tol: float = 1e-8) -> ReferenceResult:
    """Solve the Hermite-Simpson attitude NLP of ``case`` with CasADi + IPOPT (exact Hessian) from ``guess``.

    Parameters
    ----------
    case : AttitudeCase
        The slew; minimum time when ``case.tf`` is ``None``, minimum energy at ``case.tf`` otherwise.
    intervals : int
        Number ``K`` of equal Hermite-Simpson intervals.
    guess : numpy.ndarray
        ``(K + 1, 10)`` node rows ``[q, omega, u]`` (SI units).
    tf_guess : float
        Initial final time, s (also the time scale; ignored as a variable when ``case.tf`` is set).
    margin : float, optional
        Node margin on the cones and forbidden attitudes, rad (as
        :func:`~convexguid.families.quaternion_attitude.program.transcribe_slew`'s).
    max_iter : int, optional
        IPOPT's iteration limit, default 3000.
    tol : float, optional
        IPOPT's ``tol`` on the scaled NLP error, default ``1e-8``.

    Returns
    -------
    ReferenceResult
        ``x`` as node rows (nodes raveled, then :math:`t_f` for minimum time; what
        :meth:`~convexguid.families.quaternion_attitude.program.Slew.from_node_rows` takes to the program's
        vector), ``objective`` the final time (s) or the energy :math:`\\int|u|^2 dt` (N^2 m^2 s), IPOPT status
        and iteration count, solve and setup times.

    Raises
    ------
    ModuleNotFoundError
        If ``casadi`` is not installed (``pip install convexguid[bench]``).
    ValueError
        If ``guess`` is not ``(K + 1, 10)``.
    """
    import casadi as ca  # optional (the bench and test extras): loaded when IPOPT is asked for

    start = time.perf_counter()
    K, n1 = intervals, intervals + 1
    guess = np.asarray(guess, dtype=float)
    if guess.shape != (n1, NODE):
        raise ValueError(f"guess must be ({n1}, {NODE}) node rows, got {guess.shape}")
    free_time = case.tf is None
    n = n1 * NODE + (1 if free_time else 0)
    rate_scale = natural_rate(case, tf_guess)
    node_scale = np.concatenate([np.ones(4), np.full(3, rate_scale), case.torque_max])
    energy_unit = float(np.max(case.torque_max))**2 * float(case.tf) if not free_time else 1.0
    scale = np.concatenate([np.tile(node_scale, n1), [tf_guess] if free_time else []])

    z = ca.SX.sym("z", n)  # scaled decision vector
    d = z * ca.DM(scale)
    nodes = ca.reshape(d[: n1 * NODE], NODE, n1)  # column k = (q_k, omega_k, u_k): d is node-major
    X, U = nodes[:NX, :], nodes[NX:, :]
    tf = d[n - 1] if free_time else float(case.tf)
    h = tf / K

    defect = _simpson_defect_function(ca, _dynamics_function(ca, case.inertia))
    state_scale = ca.DM(node_scale[:NX])
    intervals = [defect(X[:, k], U[:, k], X[:, k + 1], U[:, k + 1], h) for k in range(K)]
    midpoints = ca.horzcat(*[xc for _, xc in intervals])
    groups = [(ca.vertcat(*[zeta / state_scale for zeta, _ in intervals]), 0.0, 0.0)]
    if case.rate_max is not None:
        groups.append((ca.vec(midpoints[4:, :]) / case.rate_max, -1.0, 1.0))
    path_q = ca.horzcat(X[:4, :], midpoints[:4, :])  # cones at the nodes and at the interval midpoints
    for cone in case.cones:
        cosine = ca.vertcat(*[_cone_cosine(ca, path_q[:, k], cone.body_axis, cone.inertial_dir)
                              for k in range(n1 + K)])
        if cone.keep_out:
            groups.append((cosine, -np.inf, np.cos(min(np.pi, cone.half_angle_rad + margin))))
        else:
            groups.append((cosine, np.cos(max(0.0, cone.half_angle_rad - margin)), np.inf))
    for fb in case.forbidden:
        bound = np.cos(min(np.pi, fb.min_angle + margin) / 2)
        groups.append((ca.mtimes(ca.DM(np.asarray(fb.q, dtype=float)).T, path_q).T, -bound, bound))
    g = ca.vertcat(*[expr for expr, _, _ in groups])
    lbg = np.concatenate([np.full(expr.numel(), lo) for expr, lo, _ in groups])
    ubg = np.concatenate([np.full(expr.numel(), hi) for expr, _, hi in groups])

    if free_time:
        objective = d[n - 1] / tf_guess
    else:
        uc = (U[:, :-1] + U[:, 1:]) / 2
        energy = h / 6 * (ca.sumsqr(U[:, :-1]) + 4 * ca.sumsqr(uc) + ca.sumsqr(U[:, 1:]))
        objective = energy / energy_unit

    # Variable bounds (scaled): rate and torque boxes, fixed boundary states, t_f > 0.
    lbz, ubz = np.full(n, -np.inf), np.full(n, np.inf)
    rate_box = np.inf if case.rate_max is None else case.rate_max / rate_scale
    box = np.concatenate([np.full(4, np.inf), np.full(3, rate_box), np.ones(3)])
    lbz[: n1 * NODE], ubz[: n1 * NODE] = np.tile(-box, n1), np.tile(box, n1)
    for k, state in ((0, np.concatenate([case.q0, case.w0])), (K, np.concatenate([case.qf, case.wf]))):
        lbz[k * NODE: k * NODE + NX] = ubz[k * NODE: k * NODE + NX] = state / node_scale[:NX]
    if free_time:
        lbz[-1] = 1e-3

    options = {"ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol, "ipopt.max_iter": max_iter,
               "print_time": False}
    solver = ca.nlpsol("quaternion_attitude_ipopt", "ipopt", {"x": z, "f": objective, "g": g}, options)
    setup = time.perf_counter() - start

    x0 = np.concatenate([guess.ravel(), [tf_guess] if free_time else []]) / scale
    start = time.perf_counter()
    sol = solver(x0=np.clip(x0, lbz, ubz), lbx=lbz, ubx=ubz, lbg=lbg, ubg=ubg)
    wall = time.perf_counter() - start
    stats = solver.stats()
    x = np.asarray(sol["x"]).ravel() * scale
    value = float(sol["f"]) * (tf_guess if free_time else energy_unit)
    return ReferenceResult(x=x, objective=value, iterations=int(stats.get("iter_count", -1)),
                           status=str(stats["return_status"]), success=bool(stats["success"]),
                           wall_time_s=wall, setup_time_s=setup)
