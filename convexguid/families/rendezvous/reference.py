"""IPOPT reference for the rendezvous burn/coast transcription (independent of the SCP code's maps).

The nonlinear program of :mod:`convexguid.families.rendezvous.arcs` (Wang & Tang 2003,
eqs. 4-11) is solved once more with CasADi + IPOPT (exact Hessians). Only the variable
*layout* (:class:`~convexguid.families.rendezvous.arc_layout.ArcLayout`), the constant matrices
:math:`A, B` of eq. (2) (:func:`~convexguid.dynamics.clohessy_wiltshire.cw_matrices`) and the
numeric initial guess are shared with the SCP code. The Hermite-Simpson defects, the
Clohessy-Wiltshire free motion of the coast arcs and the unit-direction constraints are
written again here in CasADi symbols, so a slip in either implementation shows up as a
different optimum (or as a residual of the other implementation's constraints).

With :math:`b` burns of :math:`S` sub-intervals, nodes :math:`(X_k, U_k)` and arc durations
:math:`T_1, \\dots, T_{2b-1}` (burns at odd positions 1, 3, ..., coasts between them):

.. math::

    \\min \\sum_{j} T_{2j-1} \\quad\\text{s.t.}\\quad
    X_{k+1} - X_k - \\tfrac{h}{6}\\,(f_k + 4 f_c + f_{k+1}) = 0 \\;\\text{(burns, } h = T_{burn}/S),

    X_{start} - \\Phi(T_{coast})\\,X_{end} = 0, \\quad |U_k|^2 = 1, \\quad
    X_1 = X_0^{given},\\; X_n = X_f^{given}, \\quad \\sum_i T_i = t_f - t_0, \\quad T_i \\ge 0,

with :math:`f = AX + BU`, :math:`X_c = \\tfrac12(X_k + X_{k+1}) + \\tfrac{h}{8}(f_k - f_{k+1})`,
:math:`U_c = \\tfrac12(U_k + U_{k+1})`. IPOPT works on scaled variables (positions, velocities
and durations divided by typical magnitudes, the directions as they are) and on defect rows
divided by the same state scales; the objective is the burn time divided by
:math:`t_f - t_0`. The bounds :math:`T_i \\ge 0` are variable bounds.

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003, eqs. (1)-(11).
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

from convexguid.dynamics.clohessy_wiltshire import cw_matrices
from convexguid.families.rendezvous.arc_layout import ArcLayout, ArcsPlan
from convexguid.families.rendezvous.case import Rendezvous
from convexguid.reference import ReferenceResult

__all__ = ["ArcsReferenceResult", "cw_free_motion", "solve_rendezvous_arcs_ipopt"]


ArcsReferenceResult = ReferenceResult
"""Outcome of the arcs NLP solve: the same fields as the flat-attitude reference (``x`` in SI units, burn time)."""


def cw_free_motion(ca: Any, mean_motion: float, state: Any, dt: Any) -> Any:
    """Closed-form unforced Clohessy-Wiltshire motion, :math:`\\Phi(\\Delta t)\\,X` of eq. (3), in CasADi.

    Written out as the solution of eq. (1) with :math:`a = 0` rather than as a matrix:
    with :math:`\\tau = n\\Delta t`, :math:`s = \\sin\\tau`, :math:`c = \\cos\\tau`,

    .. math::

        x &= x_0 + 6(\\tau - s)\\,y_0 + \\tfrac{4s - 3\\tau}{n}\\dot x_0 + \\tfrac{2(1 - c)}{n}\\dot y_0, &
        \\dot x &= 6n(1 - c)\\,y_0 + (4c - 3)\\,\\dot x_0 + 2s\\,\\dot y_0,

        y &= (4 - 3c)\\,y_0 - \\tfrac{2(1 - c)}{n}\\dot x_0 + \\tfrac{s}{n}\\dot y_0, &
        \\dot y &= 3ns\\,y_0 - 2s\\,\\dot x_0 + c\\,\\dot y_0,

        z &= c\\,z_0 + \\tfrac{s}{n}\\dot z_0, &
        \\dot z &= -ns\\,z_0 + c\\,\\dot z_0.

    (The :math:`\\dot x_0` term of :math:`y` has the sign that satisfies eq. (2): for small
    :math:`\\Delta t`, :math:`\\ddot y \\approx -2n\\dot x_0` gives :math:`y \\approx -n\\dot x_0\\Delta t^2`.
    The printed eq. (3) shows :math:`2(1 - \\cos\\tau)/\\omega`.)

    Parameters
    ----------
    ca : module
        The ``casadi`` module.
    mean_motion : float
        Target orbit rate :math:`n`, rad/s.
    state : casadi.SX or casadi.MX
        ``[x, y, vx, vy]`` (coplanar) or ``[x, y, z, vx, vy, vz]``, m and m/s.
    dt : casadi.SX, casadi.MX or float
        Coast duration, s.

    Returns
    -------
    casadi.SX or casadi.MX
        The propagated state, same layout as ``state``.
    """
    n = mean_motion
    dim = state.numel() // 2
    x, y, vx, vy = state[0], state[1], state[dim], state[dim + 1]
    tau = n * dt
    s, c = ca.sin(tau), ca.cos(tau)
    pos = [x + 6 * (tau - s) * y + (4 * s - 3 * tau) / n * vx + 2 * (1 - c) / n * vy,
           (4 - 3 * c) * y - 2 * (1 - c) / n * vx + s / n * vy]
    vel = [6 * n * (1 - c) * y + (4 * c - 3) * vx + 2 * s * vy,
           3 * n * s * y - 2 * s * vx + c * vy]
    if dim == 3:
        z, vz = state[2], state[5]
        pos.append(c * z + s / n * vz)
        vel.append(-n * s * z + c * vz)
    return ca.vertcat(*pos, *vel)


def _state_scale(case: Rendezvous) -> np.ndarray:
    """Typical position (m) and velocity (m/s) magnitudes, one per state component.

    Position: the largest boundary coordinate. Velocity: the largest boundary velocity or
    the mean speed needed to cover that distance in the maneuver time, whichever is larger.
    """
    d = case.dim
    pos = max(float(np.max(np.abs(np.concatenate([case.x0[:d], case.xf[:d]])))), 1.0)
    vel = max(float(np.max(np.abs(np.concatenate([case.x0[d:], case.xf[d:]])))), pos / case.duration, 1e-3)
    return np.concatenate([np.full(d, pos), np.full(d, vel)])


def _simpson_defect_function(ca: Any, A: np.ndarray, B: np.ndarray) -> Any:
    """CasADi function of one burn sub-interval: :math:`X_1 - X_0 - \\tfrac{h}{6}(f_0 + 4f_c + f_1)` (eqs. 5-8)."""
    nx, nu = B.shape
    x0, x1 = ca.SX.sym("x0", nx), ca.SX.sym("x1", nx)
    u0, u1 = ca.SX.sym("u0", nu), ca.SX.sym("u1", nu)
    h = ca.SX.sym("h")
    A_dm, B_dm = ca.DM(A), ca.DM(B)

    def f(x: Any, u: Any) -> Any:
        return ca.mtimes(A_dm, x) + ca.mtimes(B_dm, u)

    f0, f1 = f(x0, u0), f(x1, u1)
    xc = (x0 + x1) / 2 + h / 8 * (f0 - f1)
    uc = (u0 + u1) / 2
    defect = x1 - x0 - h / 6 * (f0 + 4 * f(xc, uc) + f1)
    return ca.Function("simpson_defect", [x0, u0, x1, u1, h], [defect])


def _design_scale(case: Rendezvous, layout: ArcLayout) -> np.ndarray:
    """Scale of every design variable: state scales, 1 for directions, :math:`t_f - t_0` for durations."""
    node = np.concatenate([_state_scale(case), np.ones(layout.nu)])
    return np.concatenate([np.tile(node, layout.num_nodes), np.full(layout.num_arcs, case.duration)])


def solve_rendezvous_arcs_ipopt(program: ArcsPlan, x0: np.ndarray | None = None, tol: float = 1e-10,
                                max_iter: int = 3000) -> ArcsReferenceResult:
    """Solve the burn/coast NLP of ``program`` with CasADi + IPOPT (exact Hessian) from ``x0``.

    Parameters
    ----------
    program : ArcsPlan
        The arcs' program (:class:`~convexguid.families.rendezvous.arc_phases.PhasedArcsProgram`): supplies the
        case, the variable layout (burns, sub-intervals per burn) and the default initial guess; its constraint
        and Jacobian code is not used.
    x0 : numpy.ndarray, optional
        Initial design vector in SI units; default the program's initial guess (the paper's: equal arc
        durations, states linear in time, directions along :math:`v_f - v_0`).
    tol : float, optional
        IPOPT's ``tol`` on the scaled NLP error, default ``1e-10``.
    max_iter : int, optional
        IPOPT's iteration limit, default 3000.

    Returns
    -------
    ArcsReferenceResult
        Design vector (SI), burn time, IPOPT status and iteration count, solve and setup times.

    Raises
    ------
    ModuleNotFoundError
        If ``casadi`` is not installed (``pip install convexguid[bench]``).
    NotImplementedError
        If the layout has a lead or trail coast (the reference writes the paper's arcs only).
    """
    if program.layout.lead_coast or program.layout.trail_coast:
        raise NotImplementedError("the IPOPT reference writes the paper's burn - coast - burn arcs only")
    import casadi as ca  # optional (the bench and test extras): loaded when IPOPT is asked for

    start = time.perf_counter()
    case, lay = program.case, program.layout
    A, B = cw_matrices(case.mean_motion, case.accel, case.dim)
    scale = _design_scale(case, lay)
    state_scale = ca.DM(_state_scale(case))

    z = ca.SX.sym("z", lay.num_variables)  # scaled design vector
    d = z * ca.DM(scale)
    nodes = ca.reshape(d[: lay.duration_offset], lay.node_size, lay.num_nodes)  # column k = (X_k, U_k)
    X, U = nodes[: lay.nx, :], nodes[lay.nx:, :]
    T = d[lay.duration_offset:]

    simpson = _simpson_defect_function(ca, A, B)
    burn_rows, coast_rows = [], []
    for b in range(lay.burns):
        k = lay.burn_nodes(b)
        h = T[lay.burn_arc(b)] / lay.subintervals
        for i in range(lay.subintervals):
            burn_rows.append(simpson(X[:, k[i]], U[:, k[i]], X[:, k[i + 1]], U[:, k[i + 1]], h) / state_scale)
    for c in range(lay.burns - 1):
        end, nxt = lay.burn_nodes(c)[-1], lay.burn_nodes(c + 1)[0]
        drifted = cw_free_motion(ca, case.mean_motion, X[:, end], T[lay.coast_arc(c)])
        coast_rows.append((drifted - X[:, nxt]) / state_scale)
    unit = ca.sum1(U * U).T - 1
    boundary = ca.vertcat((X[:, 0] - ca.DM(case.x0)) / state_scale,
                          (X[:, lay.num_nodes - 1] - ca.DM(case.xf)) / state_scale)
    total_time = (ca.sum1(T) - case.duration) / case.duration
    g = ca.vertcat(*burn_rows, *coast_rows, unit, boundary, total_time)

    burn_time = sum(T[lay.burn_arc(b)] for b in range(lay.burns))
    lbz = np.full(lay.num_variables, -np.inf)
    lbz[lay.duration_offset:] = 0.0
    options = {"ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol, "ipopt.max_iter": max_iter,
               "print_time": False}
    solver = ca.nlpsol("rendezvous_arcs_ipopt", "ipopt", {"x": z, "f": burn_time / case.duration, "g": g},
                       options)
    setup = time.perf_counter() - start

    guess = program.design_vector(program.initial_guess()) if x0 is None else np.asarray(x0, dtype=float)
    start = time.perf_counter()
    sol = solver(x0=guess / scale, lbx=lbz, ubx=np.inf, lbg=0.0, ubg=0.0)
    wall = time.perf_counter() - start
    stats = solver.stats()
    x = np.asarray(sol["x"]).ravel() * scale
    durations = x[lay.duration_offset:]
    objective = float(sum(durations[lay.burn_arc(b)] for b in range(lay.burns)))
    return ArcsReferenceResult(x=x, objective=objective, status=str(stats["return_status"]),
                               success=bool(stats["success"]), iterations=int(stats.get("iter_count", -1)),
                               wall_time_s=wall, setup_time_s=setup)
