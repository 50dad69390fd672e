"""The Lagrangian's curvature of a transcription, made convex constraint by constraint.

Each subproblem of the SCP engine may carry a positive semidefinite model of
:math:`\\nabla^2_{xx} L = \\sum_i w_i \\nabla^2 c_i` (:math:`w` the last subproblem's multipliers, :math:`c` the
defects, path constraints and the objective's epigraph). The exact sum is indefinite in general, and clipping the
eigenvalues of the whole sparse matrix would fill it in. A transcription's rows are small functions, each of a few
variables (one interval's states and controls and the final time), so the sum is partially separable and each
term can be made convex on its own: :math:`\\bar H = \\sum_i [w_i \\nabla^2 c_i]_+`, every element's negative
eigenvalues raised to zero (the partitioned model of Griewank & Toint, "Partitioned variable metric updates for
large structured optimization problems", Numer. Math. 39, 1982). :math:`\\bar H` keeps the sparsity of the exact
Hessian, equals it wherever no element is indefinite, and costs one CasADi evaluation and a batch of small
symmetric eigendecompositions per iteration.

On a row the subproblem leaves unmet, its multiplier is :math:`\\pm\\rho` and the element is the curvature of
:math:`\\rho |c_i|` itself: the model then predicts the merit function's second-order change, and the ratio test
no longer shrinks steps whose only fault is the constraints' curvature.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp


class ElementCurvature:
    """:math:`\\bar H(z, w) = \\sum_i [w_i \\nabla^2 c_i(z)]_+` for the rows ``rows`` of symbols ``z`` (SX).

    :attr:`rows_upper`, :attr:`cols_upper` give the upper triangle of the pattern, in a fixed order;
    :meth:`values` fills it.
    """

    def __init__(self, z: ca.SX, rows: ca.SX) -> None:
        n = z.shape[0]
        jacobian = ca.jacobian(rows, z)
        jac_rows, jac_cols = (np.asarray(v, dtype=int) for v in jacobian.sparsity().get_triplet())
        blocks, self.row_of_element, variables = [], [], []
        order = np.argsort(jac_rows, kind="stable")
        starts = np.searchsorted(jac_rows[order], np.arange(rows.shape[0] + 1))
        for i in range(rows.shape[0]):
            cols = jac_cols[order[starts[i]: starts[i + 1]]]
            if cols.size == 0:
                continue
            gradient = ca.vertcat(*(jacobian[i, int(c)] for c in cols))
            hessian = ca.jacobian(gradient, ca.vertcat(*(z[int(c)] for c in cols)))
            h_rows, h_cols = hessian.sparsity().get_triplet()
            curved = np.unique(np.concatenate([h_rows, h_cols]).astype(int))
            if curved.size == 0:
                continue  # the row is linear in z
            blocks.append(ca.vec(ca.densify(hessian[curved.tolist(), curved.tolist()])))
            self.row_of_element.append(i)
            variables.append(cols[curved])
        self.num_variables = n
        self.row_of_element = np.asarray(self.row_of_element, dtype=int)
        self._function = ca.Function("element_hessians", [z], [ca.vertcat(*blocks) if blocks else ca.SX(0, 1)])
        # elements grouped by size, for batched eigendecompositions; each entry's place in the pattern
        sizes = np.array([v.size for v in variables], dtype=int)
        offsets = np.concatenate([[0], np.cumsum(sizes**2)])
        rows_all, cols_all = [], []
        for v in variables:
            r, c = np.meshgrid(v, v, indexing="ij")
            rows_all.append(r.ravel())
            cols_all.append(c.ravel())
        rows_all = np.concatenate(rows_all) if rows_all else np.zeros(0, int)
        cols_all = np.concatenate(cols_all) if cols_all else np.zeros(0, int)
        upper = rows_all <= cols_all
        keys = rows_all[upper] * n + cols_all[upper]
        unique, self._target = np.unique(keys, return_inverse=True)
        self.rows_upper, self.cols_upper = unique // n, unique % n
        self._upper = upper
        self._groups = []
        for size in np.unique(sizes):
            members = np.flatnonzero(sizes == size)
            entries = (offsets[members][:, None] + np.arange(size * size)[None, :]).ravel()
            self._groups.append((int(size), members, entries))
        self._entries_total = int(offsets[-1])

    @property
    def elements(self) -> int:
        return self.row_of_element.size

    def values(self, z: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """The entries of :math:`\\bar H` on the upper-triangle pattern, for multipliers ``weights`` (one per row)."""
        raw = np.asarray(self._function(z), dtype=float).ravel()
        clipped = np.empty(self._entries_total)
        w = weights[self.row_of_element]
        for size, members, entries in self._groups:
            block = raw[entries].reshape(members.size, size, size) * w[members, None, None]
            block = 0.5 * (block + np.swapaxes(block, 1, 2))
            eigenvalues, vectors = np.linalg.eigh(block)
            np.maximum(eigenvalues, 0.0, out=eigenvalues)
            clipped[entries] = np.einsum("kij,kj,klj->kil", vectors, eigenvalues, vectors).ravel()
        return np.bincount(self._target, weights=clipped[self._upper], minlength=self.rows_upper.size)

    def matrix(self, z: np.ndarray, weights: np.ndarray) -> sp.csr_matrix:
        """:math:`\\bar H` as a symmetric sparse matrix (for tests and diagnostics)."""
        upper = sp.coo_matrix((self.values(z, weights), (self.rows_upper, self.cols_upper)),
                              shape=(self.num_variables,) * 2)
        return (upper + sp.triu(upper, k=1).T).tocsr()
