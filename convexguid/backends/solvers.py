"""Concrete backends: Clarabel and OSQP (persistent), qpsolvers (re-solved each call)."""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from convexguid.backends.base import Backend, BackendResult, ConicProgram
from convexguid.errors import BackendError

_CLARABEL_STATUS = {
    "Solved": "optimal",
    "AlmostSolved": "optimal_inaccurate",
    "PrimalInfeasible": "infeasible",
    "AlmostPrimalInfeasible": "infeasible",
    "DualInfeasible": "unbounded",
    "AlmostDualInfeasible": "unbounded",
}

UNBOUNDED_AT_SCALE = ("DualInfeasible", "AlmostDualInfeasible")
"""Clarabel's verdicts that are checked again with the objective at unit scale (:meth:`ClarabelBackend.solve`)."""

_OSQP_STATUS = {
    "solved": "optimal",
    "solved inaccurate": "optimal_inaccurate",
    "primal infeasible": "infeasible",
    "primal infeasible inaccurate": "infeasible",
    "dual infeasible": "unbounded",
    "dual infeasible inaccurate": "unbounded",
}


class ClarabelBackend(Backend):
    """Clarabel interior-point solver (QP and SOCP), data updated in place."""

    name = "clarabel"
    supports_soc = True

    def _setup(self, program: ConicProgram) -> None:
        import clarabel  # each solver package is loaded when its backend is chosen

        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.presolve_enable = False  # required for in-place data updates
        settings.input_sparse_dropzeros = False
        settings.direct_solve_method = "qdldl"
        settings.tol_gap_abs = settings.tol_gap_rel = self.tolerance
        settings.tol_feas = self.tolerance
        settings.iterative_refinement_enable = self.iterative_refinement
        if self.max_iterations:
            settings.max_iter = self.max_iterations
        cones = []
        if program.cones.zero:
            cones.append(clarabel.ZeroConeT(program.cones.zero))
        if program.cones.nonneg:
            cones.append(clarabel.NonnegativeConeT(program.cones.nonneg))
        cones.extend(clarabel.SecondOrderConeT(k) for k in program.cones.soc)
        self._solver = clarabel.DefaultSolver(program.P, program.q, program.A, program.b, cones, settings)
        self._objective = (program.P.data, program.q)

    def _update(self, program: ConicProgram) -> None:
        self._solver.update(P=program.P.data, q=program.q, A=program.A.data, b=program.b)
        self._objective = (program.P.data, program.q)

    def solve(self) -> BackendResult:
        start = time.perf_counter()
        sol, factor = self._solver.solve(), 1.0
        if str(sol.status) in UNBOUNDED_AT_SCALE:
            sol, factor = self._solved_at_unit_scale(sol)
        elapsed = time.perf_counter() - start
        status = _CLARABEL_STATUS.get(str(sol.status), "failed")
        x = np.asarray(sol.x) if status.startswith("optimal") else None
        z = factor * np.asarray(sol.z) if x is not None else None
        return BackendResult(status, x, factor * float(sol.obj_val), int(sol.iterations), elapsed,
                             float(sol.r_prim), float(sol.r_dual), z)

    def _solved_at_unit_scale(self, unbounded):
        """The program solved again with its objective divided by its largest coefficient rounded up to a power of
        two (the division is exact), then put back; returns Clarabel's answer and that factor (``unbounded`` and 1
        when no coefficient exceeds 1).

        Clarabel's test for a ray of unboundedness is not invariant to the objective's scale: an SCP subproblem,
        bounded by its trust region, whose penalty weights reach 1e6 (Betts' alp rider, a quadrature cost of size
        4e4 weighted 30 times) was called dual infeasible at its first iteration, and solved in 18 iterations with
        its objective divided by 1e6 (HiGHS confirms the optimum)."""
        P, q = self._objective
        largest = max(float(np.max(np.abs(q), initial=0.0)), float(np.max(np.abs(P), initial=0.0)))
        if not largest > 1.0:
            return unbounded, 1.0
        factor = 2.0 ** np.ceil(np.log2(largest))
        self._solver.update(P=P / factor, q=q / factor)
        try:
            return self._solver.solve(), factor
        finally:
            self._solver.update(P=P, q=q)


class OsqpBackend(Backend):
    """OSQP operator-splitting QP solver, data updated in place (no second-order cones)."""

    name = "osqp"

    def _setup(self, program: ConicProgram) -> None:
        import osqp  # loaded when this backend is chosen

        if program.cones.soc:
            raise BackendError("backend 'osqp' cannot take second-order cones; use 'clarabel'")
        self._solver = osqp.OSQP()
        lower, upper = self._bounds(program)
        self._solver.setup(program.P, program.q, program.A, lower, upper, verbose=False,
                           eps_abs=self.tolerance, eps_rel=self.tolerance, polishing=True,
                           max_iter=self.max_iterations or 20000)

    @staticmethod
    def _bounds(program: ConicProgram) -> tuple[np.ndarray, np.ndarray]:
        lower = np.full(program.b.size, -np.inf)
        lower[: program.cones.zero] = program.b[: program.cones.zero]
        return lower, program.b

    def _update(self, program: ConicProgram) -> None:
        lower, upper = self._bounds(program)
        self._solver.update(Px=program.P.data, Ax=program.A.data, q=program.q, l=lower, u=upper)

    def solve(self) -> BackendResult:
        start = time.perf_counter()
        res = self._solver.solve(raise_error=False)
        elapsed = time.perf_counter() - start
        status = _OSQP_STATUS.get(str(res.info.status), "failed")
        x = np.asarray(res.x) if status.startswith("optimal") else None
        z = np.asarray(res.y) if x is not None else None  # l <= Ax <= u: y > 0 on active upper bounds
        return BackendResult(status, x, float(res.info.obj_val), int(res.info.iter), elapsed,
                             float(res.info.prim_res), float(res.info.dual_res), z)


class QpsolversBackend(Backend):
    """Any QP solver known to :mod:`qpsolvers`; solved from scratch each call (for cross-checks)."""

    def __init__(self, solver: str, program: ConicProgram, tolerance: float = 1e-8,
                 max_iterations: int = 0, iterative_refinement: bool = True) -> None:
        self.solver = solver
        self.name = f"qpsolvers:{solver}"
        super().__init__(program, tolerance, max_iterations, iterative_refinement)

    def _setup(self, program: ConicProgram) -> None:
        if program.cones.soc:
            raise BackendError(f"backend '{self.name}' cannot take second-order cones; use 'clarabel'")
        self._program = program

    def _update(self, program: ConicProgram) -> None:
        self._program = program

    def solve(self) -> BackendResult:
        import qpsolvers  # loaded when this backend is chosen

        prog = self._program
        P_full = (prog.P + sp.triu(prog.P, k=1).T).tocsc()
        nz = prog.cones.zero
        # qpsolvers wants None, not an empty block, for a missing equality or inequality set
        eq = (prog.A[:nz], prog.b[:nz]) if nz else (None, None)
        ineq = (prog.A[nz:], prog.b[nz:]) if prog.A.shape[0] > nz else (None, None)
        problem = qpsolvers.Problem(P_full, prog.q, *ineq, *eq)
        start = time.perf_counter()
        sol = qpsolvers.solve_problem(problem, solver=self.solver)
        elapsed = time.perf_counter() - start
        if not sol.found or sol.x is None:
            return BackendResult("failed", None, float("nan"), 0, elapsed, float("nan"), float("nan"))
        z = np.concatenate([sol.y, sol.z]) if sol.y is not None and sol.z is not None else None
        return BackendResult("optimal", np.asarray(sol.x), float(sol.obj if sol.obj is not None else np.nan),
                             0, elapsed, float(sol.primal_residual()), float(sol.dual_residual()), z)
