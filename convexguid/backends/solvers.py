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

    def _update(self, program: ConicProgram) -> None:
        self._solver.update(P=program.P.data, q=program.q, A=program.A.data, b=program.b)

    def solve(self) -> BackendResult:
        start = time.perf_counter()
        sol = self._solver.solve()
        elapsed = time.perf_counter() - start
        status = _CLARABEL_STATUS.get(str(sol.status), "failed")
        x = np.asarray(sol.x) if status.startswith("optimal") else None
        z = np.asarray(sol.z) if x is not None else None
        return BackendResult(status, x, float(sol.obj_val), int(sol.iterations), elapsed,
                             float(sol.r_prim), float(sol.r_dual), z)


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
