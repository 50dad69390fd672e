"""Dense active-set QP backend (DAQP) with the exact-penalty slacks handled as pieces, not variables.

An SCP subproblem (:mod:`convexguid.scp.assembly`, :mod:`convexguid.scp.condensed`) softens
every linearized constraint with a penalized slack: a column :math:`s \\ge 0` with cost
:math:`q_s > 0` and no curvature that appears in one row (``a'x - c s <= b``: the penalty is
:math:`(q_s/c) \\max(0, a'x - b)`) or in two opposite rows (``|a'x - b| <= c s``: the penalty is
:math:`(q_s/c) |a'x - b|`). Handed to a dense solver as variables, hundreds of such slacks make
the QP several times larger than the step and its Hessian singular, which defeats a dense method.

:class:`DaqpBackend` reads that structure from the program's sparsity pattern once and solves
for the other ("core") variables only. Each penalty :math:`\\varphi(v)`, :math:`v = a'x - b`, is
convex piecewise linear with slopes :math:`\\alpha_- < \\alpha_+` (``0, q/c`` for one row,
``-q/c, q/c`` for two). Guessing the piece of every penalty (:math:`v \\le 0` with slope
:math:`\\alpha_-`, or :math:`v \\ge 0` with slope :math:`\\alpha_+`) leaves a QP in the core
variables with the guessed slopes in its linear term and :math:`v \\le 0` or :math:`v \\ge 0` as
rows. Its solution solves the whole program exactly when every penalty's effective slope
:math:`g = \\alpha + \\lambda` (:math:`\\lambda` the multiplier of its row) lies in
:math:`[\\alpha_-, \\alpha_+]`, the subdifferential of :math:`\\varphi` at :math:`v = 0`; otherwise
the pieces whose slope falls outside switch and the QP is solved again, warm, from its last
active set. Every switched row is active, so the last solution stays feasible and the objective
cannot increase. The first guess is the side of :math:`v` at :math:`x = 0`, which keeps
:math:`x = 0` feasible (the SCP's zero step always is).

DAQP (D. Arnström, A. Bemporad, D. Axehill, "A dual active-set solver for embedded quadratic
programming using recursive LDL' updates", IEEE TAC 67(8), 2022) needs a positive definite
Hessian; the equality rows are added to it as :math:`\\gamma E^T E`, which changes neither the
solution nor the multipliers on :math:`E x = f`, so a Hessian singular only along directions the
equalities fix (boundary conditions) needs no regularization. What is left singular, DAQP's own
proximal iterations handle, less accurately.

The answer is checked, not assumed: the slacks and every row's multiplier are recovered in the
program's own layout, and the status follows the full program's primal and dual residuals and
duality gap (``optimal`` within the tolerance, ``optimal_inaccurate`` within
:data:`INACCURATE_FACTOR` times it, ``failed`` beyond).
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from convexguid.backends.base import Backend, BackendResult, ConicProgram
from convexguid.errors import BackendError

MAX_ROUNDS = 50
"""DAQP solves (piece switches) allowed in one program before the backend reports failure."""

INACCURATE_FACTOR = 1e4
"""Residuals up to this many times the tolerance give ``optimal_inaccurate`` instead of ``failed``."""

PROXIMAL_WEIGHT = 0.1
"""DAQP's proximal weight when the Hessian is singular (in the scaled variables, whose trust box is about 1)."""

PRIMAL_TOLERANCES = (1e-9, 1e-8)
"""DAQP's primal tolerance, tightest first: a subproblem DAQP calls infeasible at the first (it never is: the step
d = 0 meets its hard rows) is solved again at the next before the fallback takes it; the answer is graded against
the backend's tolerance either way. Measured on the flat slew at N = 64 with check points: two of its subproblems
so, and Clarabel's re-solves of them took 0.9 of the SCP's 1.13 s; at 1e-8 DAQP solves them, 0.21 s in all."""

_INF = 1e30
_DAQP_FAILURE = {-1: "infeasible", -3: "unbounded"}


@dataclass(frozen=True)
class _Penalties:
    """Penalty slacks of one kind (one row, or two opposite rows): columns, rows, positions in ``A.data``."""

    col: np.ndarray
    bound_row: np.ndarray
    row: np.ndarray
    coef: np.ndarray
    """Positions in ``A.data`` of the slack's entry in ``row``."""
    bound_coef: np.ndarray
    """Positions of the slack's entry in ``bound_row``."""
    mirror_row: np.ndarray
    mirror_coef: np.ndarray

    @property
    def size(self) -> int:
        return self.col.size


def _penalties(items: np.ndarray | list[tuple[int, ...]]) -> _Penalties:
    """Penalties from rows ``(col, bound_row, row, coef, bound_coef, mirror_row, mirror_coef)``."""
    arr = np.asarray(items, dtype=np.int64).reshape(-1, 7)
    return _Penalties(*(arr[:, k] for k in range(7)))


class _Layout:
    """How one sparsity pattern splits into core variables, penalty slacks and kinds of rows.

    Read once from the first program (with its values: a slack has no curvature and a cost of
    at least zero). :meth:`check` tells whether a later program with the same pattern still has
    that structure; the backend then gathers its numbers through fixed index maps.
    """

    def __init__(self, program: ConicProgram) -> None:
        A, P = program.A, program.P
        n_rows, n = A.shape
        nz = program.cones.zero
        entry_col = np.repeat(np.arange(n), np.diff(A.indptr))
        entry_row = A.indices
        row_len = np.bincount(entry_row, minlength=n_rows)
        singleton = (row_len == 1) & (np.arange(n_rows) >= nz)
        # entries of each row (CSR order over positions in A.data): A is canonical CSC, so a stable sort by row
        # alone keeps each row's entries by column (the order np.lexsort((entry_col, entry_row)) gives)
        by_row = np.argsort(entry_row, kind="stable")
        row_ptr = np.concatenate([[0], np.cumsum(row_len)])

        def row_entries(i: int) -> np.ndarray:
            return by_row[row_ptr[i]: row_ptr[i + 1]]

        p_col = np.repeat(np.arange(n), np.diff(P.indptr))
        curved = np.zeros(n, dtype=bool)
        curved[P.indices[P.data != 0]] = True
        curved[p_col[P.data != 0]] = True
        # candidate slacks: no curvature, cost >= 0, only negative entries, none in an equality row
        slack = ~curved & (program.q >= 0)
        bad = (A.data >= 0) | (entry_row < nz)
        slack[entry_col[bad]] = False
        # each slack's bound s >= 0: its one singleton row, with b = 0
        single_rows = np.flatnonzero(singleton)
        single_pos = by_row[row_ptr[single_rows]]
        single_col = entry_col[single_pos]
        ok = slack[single_col] & (program.b[single_rows] == 0)
        slack[single_col[ok][np.bincount(single_col[ok], minlength=n)[single_col[ok]] > 1]] = False
        bound_row = np.full(n, -1)
        bound_pos = np.full(n, -1)
        bound_row[single_col[ok]], bound_pos[single_col[ok]] = single_rows[ok], single_pos[ok]
        slack &= bound_row >= 0
        # the slack's other entries: one row (hinge) or two opposite rows (absolute value), no other slack there
        slacks_in_row = np.bincount(entry_row[slack[entry_col]], minlength=n_rows)
        other = slack[entry_col] & (entry_row != bound_row[entry_col])
        count = np.bincount(entry_col[other], minlength=n)
        crowded = other & ((slacks_in_row[entry_row] > 1) | singleton[entry_row])
        slack[entry_col[crowded]] = False
        slack &= (count == 1) | (count == 2)
        other &= slack[entry_col]
        pos = np.flatnonzero(other)  # column-major: a column's entries are adjacent
        one = pos[count[entry_col[pos]] == 1]
        hinge_col = entry_col[one]
        hinges = np.column_stack([hinge_col, bound_row[hinge_col], entry_row[one], one, bound_pos[hinge_col],
                                  np.full(one.size, -1), np.full(one.size, -1)])
        two = pos[count[entry_col[pos]] == 2].reshape(-1, 2)
        absolutes = []
        for p1, p2 in two:
            c, r1, r2 = entry_col[p1], entry_row[p1], entry_row[p2]
            if (self._opposite(A, row_entries(r1), row_entries(r2), c, entry_col)
                    and np.isclose(program.b[r1], -program.b[r2], rtol=1e-12, atol=0)):
                absolutes.append((c, bound_row[c], r1, p1, bound_pos[c], r2, p2))
            else:
                slack[c] = False
        self.n, self.nz = n, nz
        self.core = np.flatnonzero(~slack)
        self.hinge, self.absolute = _penalties(hinges), _penalties(absolutes)
        self.num_pen = self.hinge.size + self.absolute.size
        used = np.zeros(n_rows, dtype=bool)
        for pen in (self.hinge, self.absolute):
            used[pen.bound_row] = used[pen.row] = True
            used[pen.mirror_row[pen.mirror_row >= 0]] = True
        self.eq_rows = np.arange(nz)
        self.bound_rows = np.flatnonzero(singleton & ~used)
        self.ineq_rows = np.flatnonzero(~used & ~singleton & (np.arange(n_rows) >= nz))
        position = np.full(n, -1)
        position[self.core] = np.arange(self.core.size)
        self.bound_data = by_row[row_ptr[self.bound_rows]].astype(np.int64)
        self.bound_var = position[entry_col[self.bound_data]]
        # the rows DAQP sees: equalities, inequalities, hinge rows, absolute-value rows (their + side)
        self.rows = np.concatenate([self.eq_rows, self.ineq_rows, self.hinge.row, self.absolute.row]).astype(np.int64)
        row_slot = np.full(n_rows, -1)
        row_slot[self.rows] = np.arange(self.rows.size)
        core_entry = position[entry_col] >= 0
        take = core_entry & (row_slot[entry_row] >= 0)
        n_c = self.core.size
        self.r_src = np.flatnonzero(take)
        self.r_dst = row_slot[entry_row[take]] * n_c + position[entry_col[take]]
        # mirror rows of absolute-value penalties: their core entries, in the + row's order
        mirror_slot = np.full(n_rows, -1)
        mirror_slot[self.absolute.mirror_row] = row_slot[self.absolute.row]
        take_m = core_entry & (mirror_slot[entry_row] >= 0)
        self.m_src = np.flatnonzero(take_m)
        self.m_dst = mirror_slot[entry_row[take_m]] * n_c + position[entry_col[take_m]]
        # P's upper triangle on the core, mirrored
        p_take = (position[P.indices] >= 0) & (position[p_col] >= 0)
        pi, pj = position[P.indices[p_take]], position[p_col[p_take]]
        self.p_src = np.flatnonzero(p_take)
        self.p_dst, self.p_dst_t = pi * n_c + pj, pj * n_c + pi
        self.slack_p = np.flatnonzero(~p_take)  # entries of P touching a slack: must stay zero
        self.slack_cols = np.flatnonzero(slack)
        # every penalty, hinges first: its slack's column, row, entry in that row; its bound's row and entry
        pens = (self.hinge, self.absolute)
        self.pen_col, self.pen_row, self.pen_coef, self.pen_bound_row, self.pen_bound_coef = (
            np.concatenate([getattr(pen, name) for pen in pens])
            for name in ("col", "row", "coef", "bound_row", "bound_coef"))

    @staticmethod
    def _opposite(A: sp.csc_matrix, first: np.ndarray, second: np.ndarray, c: int, entry_col: np.ndarray) -> bool:
        """Whether two rows have the same pattern, opposite values on every column but the slack ``c``
        and the same value there."""
        cols1, cols2 = entry_col[first], entry_col[second]
        if not np.array_equal(cols1, cols2):
            return False
        keep = cols1 != c
        return bool(np.allclose(A.data[first][keep], -A.data[second][keep], rtol=1e-12, atol=0)
                    and np.allclose(A.data[first][~keep], A.data[second][~keep], rtol=1e-12, atol=0))

    def check(self, program: ConicProgram) -> str:
        """Why ``program`` no longer has the structure read from the first one ('' when it has)."""
        A, P = program.A, program.P
        if np.any(P.data[self.slack_p] != 0):
            return "curvature on a penalty slack"
        if np.any(program.q[self.slack_cols] < 0):
            return "negative cost on a penalty slack"
        if np.any(A.data[self.pen_coef] >= 0):
            return "penalty slack with a nonnegative coefficient"
        if np.any(program.b[self.pen_bound_row] != 0) or np.any(A.data[self.pen_bound_coef] >= 0):
            return "penalty slack without its bound s >= 0"
        ab = self.absolute
        if ab.size:
            plus = np.zeros(self.rows.size * self.core.size)
            plus[self.r_dst] = A.data[self.r_src]
            minus = np.zeros_like(plus)
            minus[self.m_dst] = A.data[self.m_src]
            first = (self.rows.size - ab.size) * self.core.size  # the absolute-value rows come last
            plus, minus = plus[first:], minus[first:]
            scale = 1.0 + float(np.max(np.abs(plus), initial=0.0))
            if (not np.allclose(minus, -plus, rtol=0, atol=1e-12 * scale)
                    or not np.allclose(program.b[ab.mirror_row], -program.b[ab.row], rtol=1e-12, atol=0)
                    or not np.allclose(A.data[ab.mirror_coef], A.data[ab.coef], rtol=1e-12, atol=0)):
                return "the two rows of an absolute-value penalty are no longer opposite"
        return ""


class DaqpBackend(Backend):
    """DAQP, dense dual active-set QP solver, with the penalty slacks solved as pieces (module docstring).

    Meant for the condensed subproblem (:mod:`convexguid.scp.condensed`): a few hundred core
    variables at most. Each solve starts from the last one's pieces and active set. No
    second-order cones.
    """

    name = "daqp"
    dense = True

    def _setup(self, program: ConicProgram) -> None:
        import daqp  # noqa: F401 - fail at setup, not at the first solve, when it is missing

        if program.cones.soc:
            raise BackendError("backend 'daqp' cannot take second-order cones; use 'clarabel'")
        canonical = _canonical(program)
        self._layout = _Layout(canonical)
        self._program, self._as_given = canonical, canonical is program  # as given: its objective is ours
        self._high: np.ndarray | None = None  # the piece of every penalty at the last solution
        self._lam: np.ndarray | None = None  # DAQP's multipliers at the last solution

    def _update(self, program: ConicProgram) -> None:
        self._program = _canonical(program)
        self._as_given = self._program is program

    def sibling(self, program: ConicProgram) -> DaqpBackend | None:
        """This backend's layout for ``program`` of the same pattern, when the program has its structure (the
        check every solve makes), with no warm start: reading the layout again costs as much as a few solves."""
        if not self.same_pattern(program) or self._layout.check(_canonical(program)):
            return None
        twin = copy.copy(self)
        twin._update(program)
        twin._high = twin._lam = None
        return twin

    def solve(self) -> BackendResult:
        start = time.perf_counter()
        prog = self._program
        why = self._layout.check(prog)
        if why:
            return BackendResult("failed", None, float("nan"), 0, time.perf_counter() - start, float("nan"),
                                 float("nan"))
        try:
            status, x, z, iterations, hessian = self._solve(prog)
        except (ValueError, np.linalg.LinAlgError):  # DAQP refused the data (e.g. not finite)
            self._high = self._lam = None
            status, x, z, iterations, hessian = "failed", None, None, 0, None
        if x is None:
            return BackendResult(status, None, float("nan"), iterations, time.perf_counter() - start,
                                 float("nan"), float("nan"))
        # P x from the dense core Hessian (P is zero on the slacks, which check() confirmed): the same product to
        # rounding, 6 us against the sparse upper triangle's 70 us (P x + P' x - diag(P) x, at N = 32)
        px = np.zeros(x.size)
        px[self._layout.core] = hessian @ x[self._layout.core]
        objective = float(0.5 * x @ px + prog.q @ x)  # ConicProgram.objective's sum (to rounding), less the constant
        s = prog.b - prog.A @ x
        nz = prog.cones.zero
        primal = max(float(np.max(np.abs(s[:nz]), initial=0.0)), float(np.max(-s[nz:], initial=0.0)))
        dual = float(np.max(np.abs(px + prog.q + prog.A.T @ z), initial=0.0))
        gap = abs(float(x @ px + prog.q @ x + prog.b @ z))
        status = self._grade(prog, objective, primal, dual, gap)
        elapsed = time.perf_counter() - start
        return BackendResult(status, x if status != "failed" else None, objective, iterations, elapsed, primal,
                             dual, z if status != "failed" else None, exact_objective=self._as_given)

    def _grade(self, prog: ConicProgram, objective: float, primal: float, dual: float, gap: float) -> str:
        """``optimal`` when the residuals meet the tolerance, relative to the data (as Clarabel measures them)."""
        tol = self.tolerance
        excess = max(primal / (1.0 + float(np.max(np.abs(prog.b), initial=0.0))),
                     dual / (1.0 + float(np.max(np.abs(prog.q), initial=0.0))),
                     gap / (1.0 + abs(objective)))
        if excess <= tol:
            return "optimal"
        return "optimal_inaccurate" if excess <= INACCURATE_FACTOR * tol else "failed"

    def _solve(self, prog: ConicProgram) -> tuple[str, np.ndarray | None, np.ndarray | None, int, np.ndarray]:
        """DAQP's answer in the program's layout: status, ``x``, ``z``, DAQP iterations, and the dense symmetric
        Hessian of the core variables (``P`` there)."""
        import daqp  # the optional solver package, loaded when this backend runs

        lay = self._layout
        data, b = prog.A.data, prog.b
        n_c, m = lay.core.size, lay.rows.size
        rows = np.zeros(m * n_c)
        rows[lay.r_dst] = data[lay.r_src]
        rows = rows.reshape(m, n_c)
        H = np.zeros(n_c * n_c)
        H[lay.p_dst_t] = prog.P.data[lay.p_src]
        H[lay.p_dst] = prog.P.data[lay.p_src]
        H = hessian = H.reshape(n_c, n_c)
        f = prog.q[lay.core].copy()
        n_eq, n_in = lay.eq_rows.size, lay.ineq_rows.size
        if n_eq:
            # exact regularization along the equalities: gamma E'(E x - f) vanishes where E x = f
            E = rows[:n_eq]
            norms = np.einsum("ij,ij->i", E, E)
            if np.any(norms > 0):
                gamma = max(float(np.max(np.abs(np.diag(H)), initial=0.0)), 1.0) / float(np.max(norms))
                H = H + gamma * (E.T @ E)
                f -= gamma * (E.T @ b[lay.eq_rows])
        eps_prox = 0.0 if _positive_definite(H) else PROXIMAL_WEIGHT
        # simple bounds: the tightest row of each kind on each core variable
        coef = data[lay.bound_data]
        limit = b[lay.bound_rows] / coef
        upper, upper_row = _tightest(limit, lay.bound_var, coef > 0, n_c, np.inf)
        lower, lower_row = _tightest(-limit, lay.bound_var, coef < 0, n_c, np.inf)
        lower = -lower
        # penalties on v = a'x - b (core part of their rows), slopes lo < hi
        hinge, ab = lay.hinge, lay.absolute
        c_pen = -data[lay.pen_coef]
        q_pen = prog.q[lay.pen_col]
        hi = q_pen / c_pen
        lo = np.concatenate([np.zeros(hinge.size), -hi[hinge.size:]])
        pen0 = n_eq + n_in
        pen_rows = rows[pen0:]
        b_pen = b[lay.pen_row]
        high = -b_pen > 0  # v > 0 at x = 0
        if self._high is not None:
            high |= (b_pen == 0) & self._high
        bu = np.concatenate([np.minimum(upper, _INF), b[lay.eq_rows], b[lay.ineq_rows], np.zeros(lay.num_pen)])
        bl = np.concatenate([np.maximum(lower, -_INF), b[lay.eq_rows], np.full(n_in, -_INF), np.zeros(lay.num_pen)])
        sense = np.zeros(n_c + m, dtype=np.int32)
        sense[n_c: n_c + n_eq] = 5
        dual_start = self._lam
        tol = 1e-9 * np.maximum(hi - lo, 1e-300)
        iterations = 0
        for _ in range(MAX_ROUNDS):
            slope = np.where(high, hi, lo)
            bu[n_c + pen0:] = np.where(high, _INF, b_pen)
            bl[n_c + pen0:] = np.where(high, b_pen, -_INF)
            f_k = f + pen_rows.T @ slope
            # warm first; a start from another program's active set may not be valid here, so then cold, and a
            # cold "infeasible" once more at the looser tolerance
            attempts = ([{"dual_start": dual_start, "primal_tol": PRIMAL_TOLERANCES[0]}] if dual_start is not None
                        else []) + [{"primal_tol": tolerance} for tolerance in PRIMAL_TOLERANCES]
            for options in attempts:
                u, _, flag, info = daqp.solve(H, f_k, rows, bu.copy(), bl.copy(), sense.copy(), eps_prox=eps_prox,
                                              **options)
                iterations += int(info["iterations"])
                if flag in (1, 2) or (flag != -1 and "dual_start" not in options):
                    break
            if flag not in (1, 2):
                self._high = self._lam = None
                return _DAQP_FAILURE.get(flag, "failed"), None, None, iterations, hessian
            lam = np.asarray(info["lam"], dtype=float)
            g = slope + lam[n_c + pen0:]
            switch = np.where(high, g < lo - tol, g > hi + tol)
            if not np.any(switch):
                break
            high = high ^ switch
            dual_start = lam.copy()
            dual_start[n_c + pen0:][switch] = 0.0
        else:
            self._high = self._lam = None
            return "failed", None, None, iterations, hessian
        self._high, self._lam = high, lam
        # the whole program's primal and dual solution
        x = np.zeros(lay.n)
        x[lay.core] = u
        v = pen_rows @ u - b_pen
        g = np.clip(g, lo, hi)
        c_h, c_a = c_pen[: hinge.size], c_pen[hinge.size:]
        x[hinge.col] = np.maximum(v[: hinge.size], 0.0) / c_h
        x[ab.col] = np.abs(v[hinge.size:]) / c_a
        z = np.zeros(b.size)
        lam_rows = lam[n_c:]
        z[lay.eq_rows] = lam_rows[:n_eq]
        z[lay.ineq_rows] = np.maximum(lam_rows[n_eq: pen0], 0.0)
        lam_bound = lam[:n_c]
        up, dn = upper_row >= 0, lower_row >= 0
        z[lay.bound_rows[upper_row[up]]] = np.maximum(lam_bound[up], 0.0) / coef[upper_row[up]]
        z[lay.bound_rows[lower_row[dn]]] = np.maximum(-lam_bound[dn], 0.0) / -coef[lower_row[dn]]
        g_h, g_a = g[: hinge.size], g[hinge.size:]
        z[hinge.row] = g_h
        z[hinge.bound_row] = (q_pen[: hinge.size] - c_h * g_h) / -data[hinge.bound_coef]
        z[ab.row] = np.maximum(g_a, 0.0)
        z[ab.mirror_row] = np.maximum(-g_a, 0.0)
        z[ab.bound_row] = (q_pen[hinge.size:] - c_a * np.abs(g_a)) / -data[ab.bound_coef]
        return "optimal", x, z, iterations, hessian


def _positive_definite(H: np.ndarray) -> bool:
    """Whether Cholesky succeeds with every pivot above round-off of the largest diagonal entry."""
    scale = float(np.max(np.diag(H), initial=0.0))
    if scale <= 0:
        return False
    try:
        L = np.linalg.cholesky(H)
    except np.linalg.LinAlgError:
        return False
    return bool(np.min(np.diag(L)) ** 2 > 1e-12 * scale)


def _tightest(limit: np.ndarray, var: np.ndarray, mask: np.ndarray, n: int,
              none: float) -> tuple[np.ndarray, np.ndarray]:
    """Per variable, the smallest ``limit`` among the rows in ``mask`` and the index of that row (-1: none)."""
    best = np.full(n, none)
    which = np.full(n, -1)
    idx = np.flatnonzero(mask)
    if idx.size:
        order = idx[np.lexsort((limit[idx], var[idx]))]
        first = np.concatenate([[True], var[order][1:] != var[order][:-1]])
        chosen = order[first]
        best[var[chosen]] = limit[chosen]
        which[var[chosen]] = chosen
    return best, which


def _canonical(program: ConicProgram) -> ConicProgram:
    """``program`` with CSC matrices in canonical form (sorted indices, no duplicates)."""
    A, P = program.A, program.P
    if sp.isspmatrix_csc(A) and A.has_canonical_format and sp.isspmatrix_csc(P) and P.has_canonical_format:
        return program
    A, P = sp.csc_matrix(A, copy=True), sp.csc_matrix(P, copy=True)
    A.sum_duplicates()
    P.sum_duplicates()
    return ConicProgram(P, program.q, A, program.b, program.cones, program.constant)
