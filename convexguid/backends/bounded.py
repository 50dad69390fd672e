"""PIQP, a sparse interior-point QP solver that takes variable bounds apart from its constraint rows.

An SCP subproblem (:mod:`convexguid.scp.assembly`) bounds most of its variables one at a time: every penalty slack by
``s >= 0`` and every step by its trust region ``|d_i| <= radius``. In Clarabel's form each such bound is a row of ``A``
and a row and column of the KKT system the interior-point method factors at every iteration; PIQP (R. Schwan,
Y. Jiang, D. Kuhn, C. N. Jones, "PIQP: A Proximal Interior-Point Quadratic Programming Solver", IEEE CDC 2023) keeps
bounds ``x_l <= x <= x_u`` on the diagonal instead. :class:`BoundsLayout` reads once, from the first program's pattern,
which rows of ``A`` bound a single variable; each later program's bounds are then gathered through fixed index maps
(the tightest row on each side of a variable sets its bound) and every row's multiplier is handed back in the program's
own layout, so the SCP sees the same :class:`~convexguid.backends.base.BackendResult` as from Clarabel.

Measured on the 25 subproblems of ``problems/wang_multicone_time.yaml`` (1915 variables, 4106 rows of which 3402 bound
one variable): PIQP 0.48 s in all against Clarabel's 1.02 s, the same objectives to 1e-7 (docs/engine.md,
'Subproblem backends').
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from convexguid.backends.base import Backend, BackendResult, ConicProgram
from convexguid.errors import BackendError

_PIQP_STATUS = {
    "PIQP_SOLVED": "optimal",
    "PIQP_PRIMAL_INFEASIBLE": "infeasible",
    "PIQP_DUAL_INFEASIBLE": "unbounded",
}


class BoundsLayout:
    """Which rows of a program's ``A`` bound one variable, and the maps that turn a program of that pattern into
    PIQP's ``(A_eq, b_eq, G, h, x_l, x_u)`` and its multipliers back into the program's rows.

    A nonnegative row with a single structural entry ``a x_j <= b`` is an upper bound ``b / a`` when ``a > 0`` and a
    lower bound when ``a < 0``; the sign of each such entry is part of the layout (:meth:`fits`), as is the set of other
    rows with ``b = +inf``, which bound nothing and are left out (their multipliers are zero)."""

    def __init__(self, program: ConicProgram) -> None:
        A, nz = program.A, program.cones.zero
        m, n = A.shape
        singleton = (np.bincount(A.indices, minlength=m) == 1) & (np.arange(m) >= nz)
        singleton[A.indices[singleton[A.indices] & (A.data == 0)]] = False  # a zero coefficient bounds nothing
        # each bound row's one entry, by its position in A's CSC data (so by variable, then row)
        self.bound_pos = np.flatnonzero(singleton[A.indices])
        self.bound_rows = A.indices[self.bound_pos]
        self.bound_var = np.repeat(np.arange(n), np.diff(A.indptr))[self.bound_pos]
        self.upper = A.data[self.bound_pos] > 0
        self.n, self.nz = n, nz
        self.eq_rows = np.arange(nz)
        self.vacuous = np.isposinf(program.b) & ~singleton  # a row with no upper limit is left out
        self.vacuous[:nz] = False
        self.ineq_rows = np.flatnonzero(~singleton & ~self.vacuous & (np.arange(m) >= nz))
        self._eq, self._ineq = _RowBlock(A, self.eq_rows), _RowBlock(A, self.ineq_rows)

    def fits(self, program: ConicProgram) -> bool:
        """Whether every bound row of ``program`` still has a nonzero coefficient of its layout's sign, and the rows
        without an upper limit are the same."""
        a = program.A.data[self.bound_pos]
        vacuous = np.isposinf(program.b)
        vacuous[: self.nz] = False
        vacuous[self.bound_rows] = False
        return bool(np.all(np.where(self.upper, a > 0, a < 0))) and np.array_equal(vacuous, self.vacuous)

    def split(self, program: ConicProgram) -> tuple[sp.csc_matrix, np.ndarray, sp.csc_matrix, np.ndarray,
                                                     np.ndarray, np.ndarray, np.ndarray]:
        """``(A_eq, b_eq, G, h, x_l, x_u, limit)``: the zero rows, the other rows, the variable bounds (the tightest
        bound row on each side), and each bound row's own limit on its variable."""
        b = program.b
        A_eq, G = self._eq.matrix(program.A), self._ineq.matrix(program.A)
        limit = b[self.bound_rows] / program.A.data[self.bound_pos]
        x_l, x_u = np.full(self.n, -np.inf), np.full(self.n, np.inf)
        np.minimum.at(x_u, self.bound_var[self.upper], limit[self.upper])
        np.maximum.at(x_l, self.bound_var[~self.upper], limit[~self.upper])
        return A_eq, b[self.eq_rows], G, b[self.ineq_rows], x_l, x_u, limit

    def row_duals(self, program: ConicProgram, y: np.ndarray, z_ineq: np.ndarray, z_lower: np.ndarray,
                  z_upper: np.ndarray, x_l: np.ndarray, x_u: np.ndarray, limit: np.ndarray) -> np.ndarray:
        """The multipliers of the program's rows (Clarabel's convention: ``P x + q + A^T z = 0``, ``z >= 0`` on the
        nonnegative rows): a bound's multiplier goes to the first of its rows that sets it, divided by the row's
        coefficient."""
        z = np.zeros(program.A.shape[0])
        z[self.eq_rows], z[self.ineq_rows] = y, z_ineq
        bound = np.where(self.upper, x_u[self.bound_var], x_l[self.bound_var])
        sets = limit == bound
        dual = np.where(self.upper, z_upper[self.bound_var], z_lower[self.bound_var])
        coef = np.abs(program.A.data[self.bound_pos])
        candidates = np.flatnonzero(sets)  # the first row per variable and side takes the bound's multiplier
        _, first = np.unique(self.bound_var[candidates] * 2 + self.upper[candidates], return_index=True)
        owner = candidates[first]
        z[self.bound_rows[owner]] = dual[owner] / coef[owner]
        return z


class _RowBlock:
    """Some rows of a CSC matrix as a CSC matrix of their own, gathered through fixed positions (explicit zeros kept,
    so every program of the pattern gives PIQP the same pattern)."""

    def __init__(self, A: sp.csc_matrix, rows: np.ndarray) -> None:
        renumber = np.full(A.shape[0], -1)
        renumber[rows] = np.arange(rows.size)
        taken = renumber[A.indices] >= 0
        self.positions = np.flatnonzero(taken)
        self.indices = renumber[A.indices[taken]].astype(np.int32)
        col_of = np.repeat(np.arange(A.shape[1]), np.diff(A.indptr))
        counts = np.bincount(col_of[taken], minlength=A.shape[1])
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        self.shape = (rows.size, A.shape[1])

    def matrix(self, A: sp.csc_matrix) -> sp.csc_matrix:
        return sp.csc_matrix((A.data[self.positions], self.indices, self.indptr), shape=self.shape)


class PiqpBackend(Backend):
    """PIQP on the program's rows with its single-variable rows as bounds (:class:`BoundsLayout`); no
    second-order cones."""

    name = "piqp"

    def _setup(self, program: ConicProgram) -> None:
        import piqp  # loaded when this backend is chosen

        if program.cones.soc:
            raise BackendError("backend 'piqp' cannot take second-order cones; use 'clarabel'")
        self._piqp = piqp
        self._layout = BoundsLayout(program)
        self._solver = None
        self._program = program

    def _update(self, program: ConicProgram) -> None:
        if not self._layout.fits(program):
            self._layout, self._solver = BoundsLayout(program), None
        self._program = program

    def _solver_for(self, program: ConicProgram, parts) -> None:
        A_eq, b_eq, G, h, x_l, x_u, _ = parts
        P = program.P  # PIQP reads the upper triangle, as stored
        h_l = np.full(h.size, -np.inf)
        if self._solver is None:
            solver = self._piqp.SparseSolver()
            s = solver.settings
            s.verbose = False
            s.eps_abs = s.eps_rel = self.tolerance
            s.num_threads = 1
            if self.max_iterations:
                s.max_iter = self.max_iterations
            solver.setup(P, program.q, A_eq, b_eq, G, h_l, h, x_l, x_u)
            self._solver = solver
        else:
            self._solver.update(P=P, c=program.q, A=A_eq, b=b_eq, G=G, h_l=h_l, h_u=h, x_l=x_l, x_u=x_u)

    def solve(self) -> BackendResult:
        program = self._program
        if not _numbers(program):
            # PIQP reads a NaN limit as no limit and drops its row: refuse, as Clarabel does
            return BackendResult("failed", None, float("nan"), 0, 0.0, float("nan"), float("nan"))
        start = time.perf_counter()
        parts = self._layout.split(program)
        self._solver_for(program, parts)
        status = self._solver.solve()
        elapsed = time.perf_counter() - start
        result, info = self._solver.result, self._solver.result.info
        verdict = _PIQP_STATUS.get(str(status).rsplit(".", 1)[-1], "failed")
        x = z = None
        if verdict == "optimal":
            x = np.asarray(result.x)
            z = self._layout.row_duals(program, np.asarray(result.y), np.asarray(result.z_u),
                                       np.asarray(result.z_bl), np.asarray(result.z_bu), parts[4], parts[5], parts[6])
        return BackendResult(verdict, x, float(info.primal_obj), int(info.iter), elapsed,
                             float(info.primal_res), float(info.dual_res), z)


def _numbers(program: ConicProgram) -> bool:
    """Whether every entry of the program is a number (a row's limit may be ``+inf``: no limit)."""
    finite = all(np.all(np.isfinite(v)) for v in (program.P.data, program.q, program.A.data))
    return finite and not np.any(np.isnan(program.b) | np.isneginf(program.b))
