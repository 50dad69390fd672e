"""IPOPT reference for the flat-output attitude problem (independent of the SCP code's maps).

The transcription of :mod:`convexguid.families.flat_attitude.program` is solved once more as a
single nonlinear program with CasADi + IPOPT (exact Hessians). Only the *transcription*
is shared with the SCP code: the mapped-Chebyshev differentiation matrices, the
quadrature weights, the path-interpolation matrix (nodes, check points, extra points)
and the boundary-condition rows. The flat maps, the torque and the keep-out cones are
written again here in CasADi symbols, so a sign slip in either implementation shows up
as a different optimum.

With :math:`Z \\in \\mathbb{R}^{(N+1)\\times 3}` the node values of
:math:`\\zeta = (\\varphi, \\theta, \\psi)` (the decision vector ``x`` is ``Z`` node-major),
:math:`s = 2/(t_f - t_0)`, :math:`\\dot Z = s D_1 Z`, :math:`\\ddot Z = s^2 D_2 Z`:

.. math::

    \\omega_1 = \\dot\\varphi - \\dot\\psi\\sin\\theta, \\quad
    \\omega_2 = \\dot\\theta\\cos\\varphi + \\dot\\psi\\sin\\varphi\\cos\\theta, \\quad
    \\omega_3 = -\\dot\\theta\\sin\\varphi + \\dot\\psi\\cos\\varphi\\cos\\theta,

    u = I\\dot\\omega + \\omega \\times I\\omega, \\qquad
    \\min_x \\sum_k w_k \\|u_k\\|^2, \\quad w = \\tfrac{t_f - t_0}{2} w^{cc} g'(\\tau),

    \\text{s.t.}\\quad A x = b, \\quad |(P U)_{ij}| \\le u_{max}, \\quad
    r_B^T C_{BI}(P Z)_{p}\\, r_I \\le \\cos\\beta.

References
----------
Cai W., Zhu Y., Zeng P., "Differentially flat method of attitude maneuver trajectory
planning for space vehicles under multiple constraints", J. Dynamics and Control 16(1),
2018, DOI 10.6052/1672-6553-2018-005, eqs. (10)-(12), (26), (29)-(31).
Waechter A., Biegler L. T., "On the implementation of an interior-point filter line-search
algorithm for large-scale nonlinear programming", Math. Programming 106, 2006 (IPOPT).
Andersson J. et al., "CasADi: a software framework for nonlinear optimization and optimal
control", Math. Programming Computation 11, 2019.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from convexguid.families.flat_attitude.program import FlatAttitudeProblem, FlatAttitudeProgram
from convexguid.reference import ReferenceResult


def _body_rates(ca: Any, z: Any, zd: Any) -> Any:
    """:math:`\\omega = E(\\zeta)\\dot\\zeta` (eq. 10) at one point; ``z``, ``zd`` are 3-vectors."""
    p, t = z[0], z[1]
    pd, td, yd = zd[0], zd[1], zd[2]
    return ca.vertcat(pd - yd * ca.sin(t),
                      td * ca.cos(p) + yd * ca.sin(p) * ca.cos(t),
                      -td * ca.sin(p) + yd * ca.cos(p) * ca.cos(t))


def _body_acceleration(ca: Any, z: Any, zd: Any, zdd: Any) -> Any:
    """:math:`\\dot\\omega = E\\ddot\\zeta + \\dot E\\dot\\zeta` (eq. 11) at one point."""
    p, t = z[0], z[1]
    pd, td, yd = zd[0], zd[1], zd[2]
    pdd, tdd, ydd = zdd[0], zdd[1], zdd[2]
    sp, cp, st, ct = ca.sin(p), ca.cos(p), ca.sin(t), ca.cos(t)
    return ca.vertcat(pdd - ydd * st - yd * td * ct,
                      tdd * cp - td * pd * sp + ydd * sp * ct + yd * (pd * cp * ct - td * sp * st),
                      -tdd * sp - td * pd * cp + ydd * cp * ct - yd * (pd * sp * ct + td * cp * st))


def _torque_function(ca: Any, inertia: np.ndarray) -> Any:
    """CasADi function :math:`u = I\\dot\\omega + \\omega\\times(I\\omega)` (eq. 12) of one node."""
    z, zd, zdd = ca.SX.sym("z", 3), ca.SX.sym("zd", 3), ca.SX.sym("zdd", 3)
    inertia_dm = ca.DM(np.asarray(inertia, dtype=float))
    omega, omega_dot = _body_rates(ca, z, zd), _body_acceleration(ca, z, zd, zdd)
    u = ca.mtimes(inertia_dm, omega_dot) + ca.cross(omega, ca.mtimes(inertia_dm, omega))
    return ca.Function("flat_torque", [z, zd, zdd], [u])


def _cone_function(ca: Any, body_axis: np.ndarray, inertial_dir: np.ndarray) -> Any:
    """CasADi function :math:`r_B^T C_{BI}(\\zeta) r_I` of one point's Euler angles (3-2-1 DCM, eq. 4)."""
    z = ca.SX.sym("z", 3)
    sp, cp, st = ca.sin(z[0]), ca.cos(z[0]), ca.sin(z[1])
    ct, sy, cy = ca.cos(z[1]), ca.sin(z[2]), ca.cos(z[2])
    dcm = ca.vertcat(ca.horzcat(ct * cy, ct * sy, -st),
                     ca.horzcat(sp * st * cy - cp * sy, sp * st * sy + cp * cy, sp * ct),
                     ca.horzcat(cp * st * cy + sp * sy, cp * st * sy - sp * cy, cp * ct))
    value = ca.mtimes(ca.DM(np.asarray(body_axis, dtype=float)).T,
                      ca.mtimes(dcm, ca.DM(np.asarray(inertial_dir, dtype=float))))
    return ca.Function("cone_cosine", [z], [value])


def solve_flat_attitude_ipopt(problem: FlatAttitudeProblem, x0: np.ndarray, tol: float = 1e-8,
                              nodes_only: bool = False, expand: bool = False) -> ReferenceResult:
    """Solve the flat-attitude transcription of ``problem`` with CasADi + IPOPT from ``x0``.

    The pointwise maps (torque, cone cosine) are CasADi ``SX`` functions of one node,
    mapped over the nodes; the dense linear maps (differentiation, path interpolation,
    boundary rows) stay single matrix products in an ``MX`` graph. Expanding everything
    to ``SX`` gives the same iterates but takes minutes to set up for :math:`N = 128`.

    Parameters
    ----------
    problem : FlatAttitudeProblem
        The transcribed problem; its grid, quadrature weights, path-interpolation matrix
        and boundary-condition rows (:meth:`FlatAttitudeProgram.linear_constraints`) are used as is.
    x0 : numpy.ndarray
        Initial guess, ``3 (N + 1)`` node-major Euler angles, rad.
    tol : float, optional
        IPOPT's ``tol`` (scaled NLP error), default ``1e-8``.
    nodes_only : bool, optional
        Impose the torque box and the cones at the nodes only (the paper's NLP), not also at the
        check points and refinement points the SCP imposes them at.
    expand : bool, optional
        Let CasADi expand the graph to ``SX`` before IPOPT (``expand`` option of ``nlpsol``): slower to
        set up, faster to evaluate; with exact Hessians either way.

    Returns
    -------
    ReferenceResult
        Solution, objective, IPOPT status and iteration count, solve and setup times.

    Raises
    ------
    ModuleNotFoundError
        If ``casadi`` is not installed (``pip install convexguid[bench]``).
    """
    import casadi as ca  # optional (the bench and test extras): loaded when IPOPT is asked for

    start = time.perf_counter()
    n1 = problem.grid.n + 1
    s = problem.time_scale
    x = ca.MX.sym("x", 3 * n1)
    z = ca.reshape(x, 3, n1)  # column k is (roll, pitch, yaw) at node k: x is node-major
    zd = s * ca.mtimes(z, ca.DM(np.asarray(problem.grid.d1).T))
    zdd = s * s * ca.mtimes(z, ca.DM(np.asarray(problem.grid.d2).T))
    u = _torque_function(ca, problem.inertia).map(n1)(z, zd, zdd)
    weights = 0.5 * (problem.tf - problem.t0) * np.asarray(problem.grid.quadrature_weights)
    objective = ca.mtimes(ca.sum1(u * u), ca.DM(weights))

    path = ca.DM(np.eye(n1) if nodes_only else np.asarray(problem.path_interpolation).T)
    n_path = path.shape[1]
    z_path = ca.mtimes(z, path)
    linear = FlatAttitudeProgram(problem).linear_constraints()
    groups = [(ca.mtimes(ca.DM(linear.A), x), linear.b, linear.b),
              (ca.vec(ca.mtimes(u, path)), -problem.torque_max, problem.torque_max)]
    for cone in problem.cones:
        cosine = _cone_function(ca, cone.body_axis, cone.inertial_dir).map(n_path)(z_path)
        groups.append((cosine.T, -np.inf, np.cos(cone.half_angle_rad)))
    g = ca.vertcat(*[expr for expr, _, _ in groups])
    lbg = np.concatenate([np.broadcast_to(lo, (expr.numel(),)) for expr, lo, _ in groups])
    ubg = np.concatenate([np.broadcast_to(hi, (expr.numel(),)) for expr, _, hi in groups])

    options = {"ipopt.print_level": 0, "ipopt.tol": tol, "ipopt.sb": "yes", "print_time": False, "expand": expand}
    solver = ca.nlpsol("flat_attitude_ipopt", "ipopt", {"x": x, "f": objective, "g": g}, options)
    setup = time.perf_counter() - start

    start = time.perf_counter()
    sol = solver(x0=np.asarray(x0, dtype=float), lbg=lbg, ubg=ubg)
    wall = time.perf_counter() - start
    stats = solver.stats()
    return ReferenceResult(x=np.asarray(sol["x"]).ravel(), objective=float(sol["f"]),
                           iterations=int(stats.get("iter_count", -1)), status=str(stats["return_status"]),
                           success=bool(stats["success"]), wall_time_s=wall, setup_time_s=setup)
