"""Assembly of the convex subproblem with a sparsity pattern fixed once.

Subproblem variables are ``z = [d, y, s_o, s_g, t]``: the step ``d`` from the
iterate ``x``, the lifted residuals ``y`` (linearized :math:`r`), and nonnegative
slacks on the output constraints, on the linearized inequalities and around the
linearized equalities (an exact l1 penalty, so every subproblem is feasible):

.. math::

    \\min\\; y^T W y + c^T d + \\rho\\,(1^T s_o + 1^T s_g + 1^T t)

    \\text{s.t.}\\quad A d = b - A x,\\quad \\nabla r\\, d - y = -r,\\quad G d \\le h - G x,\\quad
    M y - s_o \\le m,

    g + \\nabla g\\, d \\le s_g,\\quad |e + \\nabla e\\, d| \\le t,\\quad
    s_o, s_g, t \\ge 0,\\quad |d_i| \\le \\Delta\\,\\sigma_i

with :math:`\\Delta` the trust radius and :math:`\\sigma` the variable scale. The
Hessian is diagonal and the dense Jacobian of :math:`r` appears once, not in every
bound row, which keeps the KKT factorisation cheap. :class:`SubproblemAssembler`
maps block values straight into the CSC ``data`` arrays, so each iteration only
copies numbers and the backend keeps its symbolic factorisation.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram
from convexguid.scp.problem import ConstraintBlock, Evaluation, LinearConstraints, OutputConstraints


class _Pattern:
    """CSC pattern of a matrix made of dense, diagonal and fixed-sparse blocks, filled block by block."""

    def __init__(self, shape: tuple[int, int]) -> None:
        self.shape = shape
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []

    def add_dense(self, row0: int, col0: int, nrows: int, ncols: int) -> None:
        r, c = np.meshgrid(np.arange(nrows), np.arange(ncols), indexing="ij")
        self._rows.append(row0 + r.ravel())
        self._cols.append(col0 + c.ravel())

    def add_diagonal(self, row0: int, col0: int, size: int) -> None:
        self._rows.append(row0 + np.arange(size))
        self._cols.append(col0 + np.arange(size))

    def add_sparse(self, row0: int, col0: int, matrix: sp.spmatrix) -> None:
        coo = sp.coo_matrix(matrix)
        self._rows.append(row0 + coo.row)
        self._cols.append(col0 + coo.col)

    def finish(self) -> None:
        rows, cols = np.concatenate(self._rows), np.concatenate(self._cols)
        self._order = np.lexsort((rows, cols))
        counts = np.bincount(cols, minlength=self.shape[1])
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self.indices = rows[self._order].astype(np.int64)

    def matrix(self, block_values: list[np.ndarray]) -> sp.csc_matrix:
        data = np.concatenate([np.ravel(v) for v in block_values])[self._order]
        return sp.csc_matrix((data, self.indices, self.indptr), shape=self.shape)


class SubproblemAssembler:
    """Builds the trust-region subproblem for one program's block sizes."""

    def __init__(self, n: int, num_residuals: int, linear: LinearConstraints, outputs: OutputConstraints,
                 n_ineq: int, n_eq: int, scale: np.ndarray, linear_cost: np.ndarray,
                 weights: np.ndarray) -> None:
        self.n, self.m = n, num_residuals
        self.linear, self.outputs, self.scale = linear, outputs, scale
        self.linear_cost, self.weights = linear_cost, weights
        n_a, n_g, n_o = linear.A.shape[0], linear.G.shape[0], outputs.M.shape[0]
        self.n_slack = n_o + n_ineq + n_eq
        self.num_z = n + self.m + self.n_slack
        y0, so0, sg0, t0 = n, n + self.m, n + self.m + n_o, n + self.m + n_o + n_ineq
        self.cones = Cones(zero=n_a + self.m, nonneg=n_g + n_o + n_ineq + 2 * n_eq + self.n_slack + 2 * n)
        pat = _Pattern((self.cones.rows, self.num_z))
        # zero cone: A d = b - A x ; J d - y = -r
        pat.add_dense(0, 0, n_a, n)
        pat.add_dense(n_a, 0, self.m, n)
        pat.add_diagonal(n_a, y0, self.m)
        row = n_a + self.m
        # nonnegative cone, in order: G, M y - s_o, lin. ineq, +eq, -eq, -slacks, trust region
        pat.add_dense(row, 0, n_g, n)
        row += n_g
        pat.add_sparse(row, y0, outputs.M)
        pat.add_diagonal(row, so0, n_o)
        row += n_o
        pat.add_dense(row, 0, n_ineq, n)
        pat.add_diagonal(row, sg0, n_ineq)
        row += n_ineq
        for _ in range(2):
            pat.add_dense(row, 0, n_eq, n)
            pat.add_diagonal(row, t0, n_eq)
            row += n_eq
        pat.add_diagonal(row, so0, self.n_slack)
        row += self.n_slack
        pat.add_diagonal(row, 0, n)
        pat.add_diagonal(row + n, 0, n)
        pat.finish()
        self._a_pattern = pat
        self._m_data = sp.coo_matrix(outputs.M).data
        diag = np.arange(n, n + self.m)
        self.P = sp.csc_matrix((2.0 * weights, (diag, diag)), shape=(self.num_z, self.num_z))
        self.q = np.concatenate([linear_cost, np.zeros(self.m), np.zeros(self.n_slack)])

    def build(self, x: np.ndarray, ev: Evaluation, radius: float, penalty: float) -> ConicProgram:
        """The subproblem about ``x`` (``ev`` must carry Jacobians)."""
        n, lin = self.n, self.linear
        jac_g, g = _stack(ev.inequalities, n)
        jac_e, e = _stack(ev.equalities, n)
        n_o, n_ineq, n_eq = self.outputs.M.shape[0], g.size, e.size
        a_blocks = [lin.A, ev.residual_jacobian, -np.ones(self.m), lin.G,
                    self._m_data, -np.ones(n_o), jac_g, -np.ones(n_ineq),
                    jac_e, -np.ones(n_eq), -jac_e, -np.ones(n_eq),
                    -np.ones(self.n_slack), 1.0 / self.scale, -1.0 / self.scale]
        A = self._a_pattern.matrix(a_blocks)
        b = np.concatenate([lin.b - lin.A @ x, -ev.residuals, lin.h - lin.G @ x, self.outputs.m,
                            -g, -e, e, np.zeros(self.n_slack), np.full(2 * n, radius)])
        q = self.q.copy()
        q[n + self.m:] = penalty
        return ConicProgram(self.P, q, A, b, self.cones)

    def step(self, z: np.ndarray) -> np.ndarray:
        return z[: self.n]


def _stack(blocks: tuple[ConstraintBlock, ...], n: int) -> tuple[np.ndarray, np.ndarray]:
    if not blocks:
        return np.zeros((0, n)), np.zeros(0)
    return np.vstack([b.jacobian for b in blocks]), np.concatenate([b.values for b in blocks])
