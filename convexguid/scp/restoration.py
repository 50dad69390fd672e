"""Start points the SCP can step from, and certificates when there are none. :func:`restore_start` moves a start that
breaks the hard linear constraints ``A x = b, G x <= h`` (every subproblem keeps them) to the nearest point that meets
them, or certifies that there is none. :func:`run_phase1` is the nonlinear counterpart: the same engine with the
objective dropped minimises the :math:`\\ell_1` violation alone, and a stall with the violation positive is a local
certificate of infeasibility (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sec. 17.2 and 18.5 on elastic modes;
docs/engine.md, 'Restoration and phase 1').
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram, make_backend
from convexguid.scp.merit import describe_violations, penalty_sum
from convexguid.scp.problem import LinearConstraints, NonconvexProgram

if TYPE_CHECKING:
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.state import IterationState

MAX_PHASE1_RUNS = 3
"""Phase-1 restorations one run may make before a stall with constraints violated ends it."""

CERTIFYING_BACKEND = "clarabel"
"""Interior-point solver used for the projection and the elastic program (accurate, reports infeasibility)."""


@dataclass(frozen=True)
class Restoration:
    """A start point on the hard linear constraints, or the certificate that there is none."""

    x: np.ndarray | None
    certificate: str = ""

    @property
    def feasible(self) -> bool:
        return self.x is not None


def linear_violation(lin: LinearConstraints, x: np.ndarray) -> float:
    """Worst violation of ``A x = b`` and ``G x <= h``, relative to ``1 + |rhs|``."""
    eq = np.abs(lin.A @ x - lin.b) / (1 + np.abs(lin.b)) if lin.A.shape[0] else np.zeros(0)
    ineq = lin.gap(x) / (1 + np.abs(lin.h))
    return float(max(np.max(eq, initial=0.0), np.max(ineq, initial=0.0)))


INCONSISTENT = 1e-8
"""Least total violation (each hard row divided by its norm: a distance in scaled variables) above which the hard
linear constraints are certified inconsistent; below it the elastic program's point is the start (round-off)."""


def restore_start(program: NonconvexProgram, x0: np.ndarray, tolerance: float = 1e-9) -> Restoration:
    """The point nearest ``x0`` on ``A x = b, G x <= h`` (scaled norm), or a certificate of inconsistency: solves
    :math:`\\min \\tfrac12 \\|v\\|^2` s.t. :math:`A(x_0 + S v) = b,\\ G(x_0 + S v) \\le h` with :math:`S` the variable
    scale (by least squares when there are only equalities); if that has no solution, the elastic LP
    :math:`\\min 1^T(p + n + s)` s.t. :math:`A S v + p - n = b - A x_0,\\ G S v - s \\le h - G x_0`,
    :math:`p, n, s \\ge 0` gives the least total violation, which is the certificate when above :data:`INCONSISTENT`.
    Each row is divided by its norm first (the Delta III launch: docs/engine.md, 'Restoration and phase 1')."""
    lin = program.linear_constraints()
    if linear_violation(lin, x0) <= tolerance:
        return Restoration(x0)
    scale = program.variable_scale()
    n, n_a, n_g = x0.size, lin.A.shape[0], lin.G.shape[0]
    if n_g == 0 and n_a <= n:
        # equalities only: the nearest point is the least-norm solution of A S v = b - A x0, in closed form
        x = x0 + scale * lin.onto_equalities(x0, scale)
        if linear_violation(lin, x) <= tolerance:
            return Restoration(x)
    rows, _, _ = lin.in_unit_rows(scale)
    A = sp.csc_matrix(sp.vstack([rows.A.tocsr(), rows.G.tocsr()]) @ sp.diags(scale))
    rhs = np.concatenate([rows.b - rows.A @ x0, rows.h - rows.G @ x0])
    projection = ConicProgram(sp.identity(n, format="csc"), np.zeros(n), A, rhs, Cones(zero=n_a, nonneg=n_g))
    result = make_backend(CERTIFYING_BACKEND, projection, 1e-10).solve()
    if result.usable:
        return Restoration(x0 + scale * result.x)
    least, v = _least_violation(A, rhs, n_a, n_g)
    if least <= INCONSISTENT:
        return Restoration(x0 + scale * v)
    return Restoration(None, f"the hard linear constraints (boundary conditions, bounds) are inconsistent: the elastic "
                       f"linear program's least total violation is {least:.3g} > {INCONSISTENT:g} (each row in units "
                       "of its norm in the scaled variables)")


def _least_violation(A: sp.csc_matrix, rhs: np.ndarray, n_a: int, n_g: int) -> tuple[float, np.ndarray | None]:
    """Optimal value and step ``v`` of the elastic LP of :func:`restore_start` (``A``, ``rhs`` already scaled and
    shifted); infinity and None when it has no answer."""
    n = A.shape[1]
    eye_a, eye_g = sp.identity(n_a), sp.identity(n_g)
    # variables [v, p, n, s]; rows: equalities, inequalities, then p, n, s >= 0
    rows_eq = sp.hstack([A[:n_a], eye_a, -eye_a, sp.csr_matrix((n_a, n_g))])
    rows_in = sp.hstack([A[n_a:], sp.csr_matrix((n_g, 2 * n_a)), -eye_g])
    slack_rows = sp.hstack([sp.csr_matrix((2 * n_a + n_g, n)), -sp.identity(2 * n_a + n_g)])
    M = sp.csc_matrix(sp.vstack([rows_eq, rows_in, slack_rows]))
    b = np.concatenate([rhs, np.zeros(2 * n_a + n_g)])
    num = n + 2 * n_a + n_g
    q = np.concatenate([np.zeros(n), np.ones(2 * n_a + n_g)])
    lp = ConicProgram(sp.csc_matrix((num, num)), q, M, b, Cones(zero=n_a, nonneg=n_g + 2 * n_a + n_g))
    result = make_backend(CERTIFYING_BACKEND, lp, 1e-10).solve()
    return (float(result.objective), result.x[:n]) if result.usable else (float("inf"), None)


def run_phase1(algo: SCPAlgorithm, state: IterationState) -> None:
    """At the largest penalty and still infeasible: phase 1 from ``state`` (see the module docstring). A feasible point
    found so restarts the main loop from it; the certificate is global when every map is affine."""
    if state.phase1_runs >= MAX_PHASE1_RUNS:
        # no certificate (each phase 1 found a feasible point) and no iteration limit reached: not a plan
        state.finish("unverified", f"iterates stalled with constraints violated after {MAX_PHASE1_RUNS} phase-1 "
                     "restarts (each found a feasible point the main loop left again): "
                     + describe_violations(state.ev))
        return
    state.phase1_runs += 1
    settings = replace(algo.settings, penalty=1.0, penalty_max=1.0, penalty_unit="absolute")
    phase1 = type(algo)(algo.program, settings, algo.log, phase1=True)
    p1 = phase1.initialize(state.x)
    while not p1.finished:
        phase1.step(p1)
    state.iteration += p1.iteration
    state.history.extend(replace(r, iteration=state.iteration - p1.iteration + r.iteration) for r in p1.history)
    state.solver_time_s += p1.solver_time_s
    state.escape_log += [f"phase 1 {note}" for note in p1.escape_log]
    state.convexify_time_s += p1.convexify_time_s
    if p1.status not in ("converged", "infeasible"):
        state.finish(p1.status, "phase-1 (least violation) ended " + p1.status + ": " + p1.message)
        return
    # the elastic program evaluates the program itself: its point's evaluation is the main loop's
    state.x, state.raw, state.ev = p1.x, p1.raw, p1.ev
    state.objective = algo.objective(state.ev, state.x)
    if p1.status == "converged":
        state.kkt, state.merit = None, algo.merit(state.ev, state.x, state.penalty)
        state.radius = algo.trust_region.initial
        if state.funnel is not None:
            # a funnel as wide as the start's would let the next step throw the restored feasibility away: it starts
            # afresh, as a warm start's, at the restored point (measured: docs/engine.md, 'Restoration and phase 1')
            state.funnel = algo.funnel.initial(max(penalty_sum(state.ev), algo.settings.feasibility_tolerance),
                                               warm=True)
    else:
        where = ("the program is convex: no point is feasible" if getattr(algo.program, "affine", False)
                 else "locally: no nearby point is feasible")
        state.finish("infeasible", f"certificate: {p1.message} ({where})")
