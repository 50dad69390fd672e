"""Assembly of the convex subproblem with a sparsity pattern fixed once. Its variables are ``z = [d, y, s_o, s_g, t_+,
t_-, s_c]``: the step ``d`` from the iterate ``x``, the lifted residuals ``y`` (linearized :math:`r`), and nonnegative
slacks on the output constraints, the linearized inequalities, either side of the linearized equalities and on each
second-order cone (an exact l1 penalty, so every subproblem is feasible):

.. math::

    \\min\\; y^T W y + c^T d + \\rho\\,(1^T s_o + 1^T s_g + 1^T t_+ + 1^T t_- + 1^T s_c)

    \\text{s.t.}\\quad A d = b - A x,\\quad \\nabla r\\, d - y = -r,\\quad G d \\le h - G x,\\quad M y - s_o \\le m,

    g + \\nabla g\\, d \\le s_g,\\quad e + \\nabla e\\, d = t_+ - t_-,\\quad
    \\|v_{1:} + F_{1:} d\\| \\le v_0 + F_0 d + s_c,\\quad s_o, s_g, t_\\pm, s_c \\ge 0,
    \\quad |d_i| \\le \\Delta\\,\\sigma_i

with :math:`\\Delta` the trust radius, :math:`\\sigma` the variable scale and :math:`v = Fx + f` each cone's affine map
(:class:`~convexguid.scp.problem.ConeBlock`, exact); the backend sees the scaled step :math:`d_i/\\sigma_i`.
:class:`SubproblemAssembler` maps block values straight into the CSC ``data`` arrays, so each iteration only copies
numbers (why this form: docs/engine.md, 'Subproblem assembly: lifted and condensed').
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram
from convexguid.scp.lagrangian import Multipliers
from convexguid.scp.problem import Evaluation, LinearConstraints, OutputConstraints, stacked_values


class _Pattern:
    """CSC pattern of a matrix made of dense, diagonal and fixed-sparse blocks, filled block by block."""

    def __init__(self, shape: tuple[int, int]) -> None:
        self.shape = shape
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []

    def add_entries(self, rows: np.ndarray, cols: np.ndarray) -> None:
        self._rows.append(np.asarray(rows, dtype=int))
        self._cols.append(np.asarray(cols, dtype=int))

    def add_dense(self, row0: int, col0: int, nrows: int, ncols: int) -> None:
        r, c = np.meshgrid(np.arange(nrows), np.arange(ncols), indexing="ij")
        self.add_entries(row0 + r.ravel(), col0 + c.ravel())

    def add_diagonal(self, row0: int, col0: int, size: int) -> None:
        self.add_entries(row0 + np.arange(size), col0 + np.arange(size))

    def add_sparse(self, row0: int, col0: int, matrix: sp.spmatrix) -> None:
        coo = sp.coo_matrix(matrix)
        self.add_entries(row0 + coo.row, col0 + coo.col)

    def finish(self) -> None:
        """Fix the pattern: ``indices`` and ``indptr`` in the integer type scipy keeps for them (int32 where the sizes
        allow), so the matrix made at every iteration takes them neither converted nor scanned (docs/engine.md)."""
        rows, cols = np.concatenate(self._rows), np.concatenate(self._cols)
        # by column, then row: the order np.lexsort((rows, cols)) gives, found by a stable sort of one key
        self._order = np.argsort(cols * self.shape[0] + rows, kind="stable")
        indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=self.shape[1]))])
        # scipy's rule for the (data, indices, indptr) form
        dtype = np.int32 if max(*self.shape, rows.size) <= np.iinfo(np.int32).max else np.int64
        self.indices, self.indptr = np.asarray(rows[self._order], dtype=dtype), np.asarray(indptr, dtype=dtype)

    def matrix(self, block_values: list[np.ndarray]) -> sp.csc_matrix:
        data = np.concatenate([np.ravel(v) for v in block_values])[self._order]
        return sp.csc_matrix((data, self.indices, self.indptr), shape=self.shape)


UNIT_ROWS = 100.0
"""A hard linear row whose norm in the scaled step is more than this factor from 1 enters the subproblem divided by
it. Clarabel solved the Delta III launch's failing subproblem with the rows beyond 100 so divided, not with those
beyond 1e5 alone; dividing every row moved Bilimoria and Wie's slew to a local minimum 1.3% slower."""


class SubproblemRows:
    """The constraint rows the lifted and the condensed subproblem share, their pattern fixed once from the first
    :class:`Evaluation`: a dense Jacobian block gets a dense pattern, a ``scipy.sparse.coo_matrix`` keeps its own (see
    :class:`~convexguid.scp.problem.ConstraintBlock`). ``lifted`` keeps the residuals as variables (``J d - y = -r``
    rows, the output constraints on ``y``); otherwise the output constraints take ``M J`` on the step, dense."""

    def __init__(self, n: int, first: Evaluation, linear: LinearConstraints, outputs: OutputConstraints,
                 scale: np.ndarray, weights: np.ndarray, curvature: tuple[np.ndarray, np.ndarray] | None,
                 lifted: bool) -> None:
        self.n, self.m = n, first.residuals.size
        stated = linear.sparse()
        # each hard row far from unit size in units of its norm in the scaled step (its multiplier read back per unit
        # as stated); the rows of a unit's size are left as stated, as the backends' own equilibration handles them
        self.linear, *self._row_units = stated.in_unit_rows(scale, within=UNIT_ROWS)
        linear = self.linear
        # a hard inequality met to the backend's tolerance (1e-7 of 1 + |h| as stated) must not make d = 0 infeasible
        self._room_floor = -1e-7 * self._row_units[1] * (1 + np.abs(stated.h))
        self.outputs, self.scale, self.weights, self.curvature = outputs, scale, weights, curvature
        self.n_ineq = sum(b.values.size for b in first.inequalities)
        self.n_eq = sum(b.values.size for b in first.equalities)
        cone_sizes = tuple(size for block in first.cones for size in block.sizes)
        self.n_cones = len(cone_sizes)
        n_a, n_g, n_o = linear.A.shape[0], linear.G.shape[0], outputs.M.shape[0]
        lifted_rows = self.m if lifted else 0
        self.split = lifted  # an equality: one zero-cone row between two slacks, or (condensed) a +/- pair
        zero_eq, pair_rows, eq_slacks = (self.n_eq, 0, 2 * self.n_eq) if lifted else (0, self.n_eq, self.n_eq)
        self.n_slack = n_o + self.n_ineq + eq_slacks + self.n_cones
        self.num_z = n + lifted_rows + self.n_slack
        so0 = n + lifted_rows  # the first output, inequality and equality slack columns
        sg0, t0 = so0 + n_o, so0 + n_o + self.n_ineq
        self.cones = Cones(zero=n_a + lifted_rows + zero_eq,
                           nonneg=n_g + n_o + self.n_ineq + 2 * pair_rows + self.n_slack + 2 * n, soc=cone_sizes)
        # the rows of each multiplier among the duals: the zero cone's A, J d - y = -r and (lifted) equalities, then
        # the nonnegative cone's G, outputs, inequalities and (condensed) equalities as + and - rows; the cones last
        self._dual_sizes = [n_a, lifted_rows, zero_eq, n_g, n_o, self.n_ineq, pair_rows, pair_rows]
        self._cone_rows = sum(cone_sizes)
        pat = _Pattern((self.cones.rows, self.num_z))
        # zero cone: A d = b - A x (; J d - y = -r; the equalities, whose entries the pattern takes last)
        _add_jacobian(pat, 0, linear.A, n_a, n)
        if lifted:
            _add_jacobian(pat, n_a, first.residual_jacobian, self.m, n)
            pat.add_diagonal(n_a, n, self.m)
        row = n_a + lifted_rows + zero_eq
        # nonnegative cone, in order: G, the outputs, the linearized inequalities and the paired equalities (+, -),
        # each less its slacks, then every slack's bound and the trust region on the step
        _add_jacobian(pat, row, linear.G, n_g, n)
        row += n_g
        if lifted:
            pat.add_sparse(row, n, outputs.M)
        else:
            pat.add_dense(row, 0, n_o, n)
        pat.add_diagonal(row, so0, n_o)
        row = _add_blocks(pat, row + n_o, first.inequalities, n)
        pat.add_diagonal(row - self.n_ineq, sg0, self.n_ineq)
        for _ in range(2 if pair_rows else 0):
            row = _add_blocks(pat, row, first.equalities, n)
            pat.add_diagonal(row - pair_rows, t0, pair_rows)
        pat.add_diagonal(row, so0, self.n_slack)
        row += self.n_slack
        pat.add_diagonal(row, 0, n)
        pat.add_diagonal(row + n, 0, n)
        # the second-order cones: each cone's map v + F d, and its slack on its first row
        row = _add_blocks(pat, row + 2 * n, first.cones, n) - self._cone_rows
        pat.add_entries(row + np.cumsum((0, *cone_sizes))[:-1], t0 + eq_slacks + np.arange(self.n_cones))
        if lifted:  # e + J_e d - t+ + t- = 0
            _add_blocks(pat, n_a + lifted_rows, first.equalities, n)
            pat.add_diagonal(n_a + lifted_rows, t0, self.n_eq)
            pat.add_diagonal(n_a + lifted_rows, t0 + self.n_eq, self.n_eq)
        pat.finish()
        self._a_pattern = pat
        # the subproblem is solved for the scaled step d / scale, which keeps it well conditioned
        self._column_scale = np.concatenate([scale, np.ones(self.num_z - n)])
        self._a_data_scale = self._column_scale[np.repeat(np.arange(self.num_z), np.diff(pat.indptr))]
        self._unit_scale = bool(np.all(scale == 1.0))  # the column scaling then changes no number
        # the fixed entries of the softened rows, the slacks' bounds and the trust region
        self._fixed = {"ineq": -np.ones(self.n_ineq), "eq": -np.ones(self.n_eq), "slack": -np.ones(self.n_slack),
                       "box": (1.0 / scale, -1.0 / scale), "cone": -np.ones(self.n_cones), "eq_t-": np.ones(self.n_eq)}

    def constraints(self, x: np.ndarray, ev: Evaluation, radius: float | np.ndarray, head: list[np.ndarray],
                    head_rhs: list[np.ndarray]) -> tuple[sp.csc_matrix, np.ndarray]:
        """``(A, b)`` about ``x`` (``radius``: the box on the scaled step, or its upper then lower limits per variable):
        ``head`` the values of the rows up to the output constraints' slacks (in pattern order), ``head_rhs`` their
        right-hand sides after ``A``'s and ``G``'s (which this fills in)."""
        lin, fixed = self.linear, self._fixed
        jac_e = [_jacobian_data(b.jacobian) for b in ev.equalities]
        pairs = [] if self.split else [*jac_e, fixed["eq"], *(-j for j in jac_e), fixed["eq"]]
        split = [*jac_e, fixed["eq"], fixed["eq_t-"]] if self.split else []
        A = self._a_pattern.matrix([
            *head, *(_jacobian_data(b.jacobian) for b in ev.inequalities), fixed["ineq"], *pairs, fixed["slack"],
            *fixed["box"], *(-_jacobian_data(b.jacobian) for b in ev.cones), fixed["cone"], *split])
        if not self._unit_scale:
            A.data *= self._a_data_scale
        room = lin.h - lin.G @ x
        room[(room < 0) & (room > self._room_floor)] = 0.0
        e = stacked_values(ev.equalities)
        lifted_rhs, output_rhs = head_rhs
        zero_eq, pairs = ([-e], []) if self.split else ([], [-e, e])
        b = np.concatenate([lin.b - lin.A @ x, lifted_rhs, *zero_eq, room, output_rhs,
                            -stacked_values(ev.inequalities), *pairs, np.zeros(self.n_slack),
                            np.broadcast_to(radius, 2 * self.n), stacked_values(ev.cones)])
        return A, b

    def multipliers(self, z: np.ndarray) -> Multipliers:
        """The program's multipliers from the row duals (a condensed equality's: its ``+`` row's less its ``-``)."""
        ends = np.cumsum(self._dual_sizes)
        a, _, e, g, o, i, plus, minus = (z[end - size: end] for end, size in zip(ends, self._dual_sizes, strict=True))
        cone = z[z.size - self._cone_rows:].copy() if self._cone_rows else np.zeros(0)
        return Multipliers(equality=e.copy() if self.split else plus - minus, inequality=i.copy(), output=o.copy(),
                           linear_equality=a * self._row_units[0], linear_inequality=g * self._row_units[1],
                           cone=cone)

    def step(self, z: np.ndarray) -> np.ndarray:
        """The step ``d`` from a subproblem solution (whose first block is ``d`` in scaled units)."""
        return z[: self.n] * self.scale


class SubproblemAssembler(SubproblemRows):
    """Builds the lifted trust-region subproblem for one program's block structure (:class:`SubproblemRows`). With
    ``curvature`` (the upper triangle ``(rows, cols)`` of a pattern) the Hessian gets that block on ``d``: the convex
    model of the Lagrangian's curvature (:class:`~convexguid.scp.problem.CurvatureModel`)."""

    def __init__(self, n: int, first: Evaluation, linear: LinearConstraints, outputs: OutputConstraints,
                 scale: np.ndarray, linear_cost: np.ndarray, weights: np.ndarray,
                 curvature: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        super().__init__(n, first, linear, outputs, scale, weights, curvature, lifted=True)
        self._m_data = sp.coo_matrix(outputs.M).data
        # P: the curvature model's upper triangle on d (if any), then the residuals' diagonal 2W on y
        rows, cols = curvature if curvature is not None else (np.zeros(0, int), np.zeros(0, int))
        diagonal = np.arange(n, n + self.m)
        self._p_rows, self._p_cols = np.concatenate([rows, diagonal]), np.concatenate([cols, diagonal])
        self._p_pattern = _Pattern((self.num_z, self.num_z))
        self._p_pattern.add_entries(self._p_rows, self._p_cols)
        self._p_pattern.finish()
        self._p_residual = 2.0 * weights
        self.q = np.concatenate([linear_cost, np.zeros(self.m), np.zeros(self.n_slack)])

    def build(self, x: np.ndarray, ev: Evaluation, radius: float, penalty: float,
              hessian: np.ndarray | None = None) -> ConicProgram:
        """The subproblem about ``x`` (``ev`` with Jacobians; ``hessian``: the curvature model's entries)."""
        head = [_jacobian_data(self.linear.A), _jacobian_data(ev.residual_jacobian), -np.ones(self.m),
                _jacobian_data(self.linear.G), self._m_data, -np.ones(self.outputs.M.shape[0])]
        A, b = self.constraints(x, ev, radius, head, [-ev.residuals, self.outputs.m])
        p_data = self._p_residual
        if self.curvature is not None:
            h = np.zeros(self.curvature[0].size) if hessian is None else hessian
            p_data = np.concatenate([h, p_data])
        P = self._p_pattern.matrix([p_data * self._column_scale[self._p_rows] * self._column_scale[self._p_cols]])
        q = self.q.copy()
        q[self.n + self.m:] = penalty
        q *= self._column_scale
        return ConicProgram(P, q, A, b, self.cones)


def _add_blocks(pat: _Pattern, row: int, blocks: tuple, n: int) -> int:
    """Each block's Jacobian from ``row`` on, one after another; returns the next row."""
    for block in blocks:
        _add_jacobian(pat, row, block.jacobian, block.values.size, n)
        row += block.values.size
    return row


def _add_jacobian(pat: _Pattern, row0: int, jacobian: np.ndarray | sp.spmatrix | None, rows: int, n: int) -> None:
    if sp.issparse(jacobian):
        pat.add_sparse(row0, 0, jacobian)
    else:
        pat.add_dense(row0, 0, rows, n)


def _jacobian_data(jacobian: np.ndarray | sp.spmatrix) -> np.ndarray:
    """Values in pattern order: row-major for dense blocks, COO order for sparse ones."""
    return jacobian.data if sp.issparse(jacobian) else np.asarray(jacobian)
