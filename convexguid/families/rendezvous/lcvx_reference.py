"""The ``lcvx`` SOCP stated plainly in cvxpy: an independent reference for the project's own statement.

:mod:`convexguid.families.rendezvous.lcvx` states the lossless-convexification SOCP on :mod:`convexguid.ocp` (the
flow in closed form, the thrust slack as its 2-norm fuel) and the SCP engine solves it. Here cvxpy states the
problem the way it reads in the paper, states kept as variables:

.. math::

    \\min \\sum_{k=0}^{K-1} \\Gamma_k\\,\\Delta t
    \\quad\\text{s.t.}\\quad X_{k+1} = \\Phi X_k + \\Gamma_d u_k,\\quad
    |u_k| \\le \\Gamma_k \\le 1,\\quad X_0 = X_{init},\\; X_K = X_f,

with the same exact zero-order-hold pair (:func:`~convexguid.dynamics.clohessy_wiltshire.cw_zoh`) and
solved by cvxpy's ``CLARABEL`` interface. The two must give the same burn time (the ``lcvx (cvxpy statement)``
benchmark row and ``tests/test_lcvx_reference.py``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from convexguid.dynamics.clohessy_wiltshire import cw_zoh
from convexguid.families.rendezvous.case import Rendezvous


@dataclass(frozen=True)
class LcvxReferenceResult:
    """cvxpy's answer: ``status`` (``optimal``, ``infeasible``, ...), burn time (s, NaN unless optimal),
    controls ``u`` (K x nu) and throttles ``Gamma`` (K), Clarabel's iterations and solve time, cvxpy's
    compile time and the wall time of the whole call (s)."""

    status: str
    burn_time_s: float
    controls: np.ndarray
    throttle: np.ndarray
    iterations: int
    solve_time_s: float
    compile_time_s: float
    wall_time_s: float

    @property
    def optimal(self) -> bool:
        return self.status == cp.OPTIMAL


def solve_lcvx_cvxpy(case: Rendezvous, steps: int, tolerance: float = 1e-9) -> LcvxReferenceResult:
    """Build and solve the uncondensed SOCP on ``steps`` zero-order-hold steps with cvxpy + Clarabel."""
    start = time.perf_counter()
    dt = case.duration / steps
    phi, gam = cw_zoh(case.mean_motion, case.accel, dt, case.dim)
    x = cp.Variable((steps + 1, case.nx))
    u = cp.Variable((steps, case.nu))
    throttle = cp.Variable(steps)
    constraints = [
        x[1:].T == phi @ x[:-1].T + gam @ u.T,
        cp.norm(u, 2, axis=1) <= throttle,
        throttle <= 1,
        x[0] == case.x0,
        x[steps] == case.xf,
    ]
    problem = cp.Problem(cp.Minimize(dt * cp.sum(throttle)), constraints)
    problem.solve(solver=cp.CLARABEL, tol_gap_abs=tolerance, tol_gap_rel=tolerance, tol_feas=tolerance)
    wall = time.perf_counter() - start
    ok, stats = problem.status == cp.OPTIMAL, problem.solver_stats
    nan = np.full((steps, case.nu), np.nan)
    return LcvxReferenceResult(
        problem.status, float(problem.value) if ok else float("nan"), u.value if ok else nan,
        throttle.value if ok else np.full(steps, np.nan), int(stats.num_iters or 0), float(stats.solve_time or 0.0),
        float(problem.compilation_time or 0.0), wall)
