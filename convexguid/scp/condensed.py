"""The trust-region subproblem with the lifted residuals eliminated (the condensed form).

:mod:`convexguid.scp.assembly` keeps :math:`y = r + J d` as variables so that the dense
Jacobian :math:`J` appears once in a large sparse KKT system. When :math:`n` is small and the
Jacobians are dense, the opposite is cheaper: substitute :math:`y` and solve a small dense QP in
the step alone. With the scaled step :math:`u = S^{-1} d` (:math:`S = \\operatorname{diag}\\sigma`)
the variables are ``z = [u, s_o, s_g, t, s_c]`` and

.. math::

    \\min\\; u^T S (J^T W J + \\tfrac12 H) S u + (2 J^T W r + c)^T S u + r^T W r
    + \\rho\\,(1^T s_o + 1^T s_g + 1^T t + 1^T s_c)

    \\text{s.t.}\\quad A S u = b - A x,\\quad G S u \\le h - G x,\\quad
    M J S u - s_o \\le m - M r,

    g + \\nabla g\\, S u \\le s_g,\\quad |e + \\nabla e\\, S u| \\le t,\\quad
    \\|v_{1:} + F_{1:} S u\\| \\le v_0 + F_0 S u + s_c,\\quad
    s_o, s_g, t, s_c \\ge 0,\\quad |u_i| \\le \\Delta,

which is the lifted subproblem with :math:`y` substituted: the same optimal step and value (the
constant :math:`r^T W r` rides along in :attr:`ConicProgram.constant`, so
``program.objective(z)`` is the model value the engine compares with the merit). Hard linear
constraints stay hard; slacks stay exactly where the lifted form has them, so the two
subproblems are the same problem, and the row blocks come in the lifted form's order (less its
``J d - y = -r`` rows). :class:`CondensedAssembler` has the interface of
:class:`~convexguid.scp.assembly.SubproblemAssembler`.

The program is handed over in the usual CSC form with a pattern fixed once (the ``u`` columns
of every row dense, the slacks' identity blocks sparse), so any backend takes it; the dense
backend (:class:`~convexguid.backends.dense.DaqpBackend`) reads the slack columns off the
pattern and solves in ``u`` alone, which is what makes this form fast.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram
from convexguid.scp.assembly import (
    DualLayout,
    _add_jacobian,
    _jacobian_data,
    _Pattern,
    _values,
    add_cone_rows,
    add_softened_rows,
)
from convexguid.scp.lagrangian import Multipliers
from convexguid.scp.problem import Evaluation, LinearConstraints, OutputConstraints


@dataclass(frozen=True)
class CurvedTerms:
    """A model Hessian in the scaled step ``u`` that replaces the condensed one, with the linear and constant terms
    that come with it (:mod:`convexguid.scp.curved`)."""

    hessian: np.ndarray
    linear: np.ndarray
    constant: float


class CondensedAssembler:
    """Builds the condensed trust-region subproblem (same arguments and methods as ``SubproblemAssembler``).

    Row layout of ``A z + s = b``: zero cone ``A S u = b - A x``; nonnegative cone, in order,
    ``G``, outputs, linearized inequalities, ``+eq``, ``-eq``, ``-slacks <= 0``, ``u <= radius``,
    ``-u <= radius``; then each second-order cone ``v + F S u`` with its slack on its first row (the lifted form's,
    less its ``J d - y = -r`` rows). ``P`` is dense on ``u`` and zero on the slacks; the output rows ``M J`` are
    dense. A program with cones goes to a conic backend (the curved subproblem's Clarabel); the dense one takes
    none.
    """

    def __init__(self, n: int, first: Evaluation, linear: LinearConstraints, outputs: OutputConstraints,
                 scale: np.ndarray, linear_cost: np.ndarray, weights: np.ndarray,
                 curvature: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        self.n, self.m = n, first.residuals.size
        linear = linear.sparse()
        self.linear, self.outputs, self.scale = linear, outputs, scale
        self.linear_cost, self.weights, self.curvature = linear_cost, weights, curvature
        self.n_ineq = sum(b.values.size for b in first.inequalities)
        self.n_eq = sum(b.values.size for b in first.equalities)
        n_a, n_g, n_o = linear.A.shape[0], linear.G.shape[0], outputs.M.shape[0]
        cone_sizes = tuple(size for block in first.cones for size in block.sizes)
        self.n_cones, n_cone_rows = len(cone_sizes), sum(cone_sizes)
        self.n_slack = n_o + self.n_ineq + self.n_eq + self.n_cones
        self.num_z = n + self.n_slack
        so0, sg0, t0 = n, n + n_o, n + n_o + self.n_ineq
        self.cones = Cones(zero=n_a, nonneg=n_g + n_o + self.n_ineq + 2 * self.n_eq + self.n_slack + 2 * n,
                           soc=cone_sizes)
        self.layout = DualLayout(n_a, 0, n_g, n_o, self.n_ineq, self.n_eq, n_cone_rows)
        pat = _Pattern((self.cones.rows, self.num_z))
        _add_jacobian(pat, 0, linear.A, n_a, n)
        row = n_a
        _add_jacobian(pat, row, linear.G, n_g, n)
        row += n_g
        pat.add_dense(row, 0, n_o, n)
        pat.add_diagonal(row, so0, n_o)
        row += n_o
        row = add_softened_rows(pat, row, first, n, (so0, sg0, t0), (self.n_ineq, self.n_eq, self.n_slack))
        add_cone_rows(pat, row, first.cones, cone_sizes, t0 + self.n_eq)
        pat.finish()
        self._a_pattern = pat
        self._M = sp.csr_matrix(outputs.M)
        column_scale = np.concatenate([scale, np.ones(self.n_slack)])
        self._a_data_scale = column_scale[np.repeat(np.arange(self.num_z), np.diff(pat.indptr))]
        # P: the dense upper triangle of the u block
        self._p_rows, self._p_cols = np.triu_indices(n)
        order = np.lexsort((self._p_rows, self._p_cols))
        self._p_rows, self._p_cols = self._p_rows[order], self._p_cols[order]
        counts = np.bincount(self._p_cols, minlength=self.num_z)
        self._p_indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self._p_indices = self._p_rows.astype(np.int64)
        self._cost_u = np.asarray(linear_cost, dtype=float) * scale

    def build(self, x: np.ndarray, ev: Evaluation, radius: float, penalty: float,
              hessian: np.ndarray | None = None, curved: CurvedTerms | None = None) -> ConicProgram:
        """The subproblem about ``x`` (``ev`` must carry Jacobians; ``hessian``: the curvature model's entries on the
        pattern ``curvature``, positive semidefinite).

        ``curved`` replaces the model's whole Hessian in ``u`` (scaled, positive semidefinite, the Gauss-Newton part
        included) and adds its linear and constant terms (:mod:`convexguid.scp.curved`)."""
        n, lin, scale = self.n, self.linear, self.scale
        n_o = self._M.shape[0]
        r = ev.residuals
        jac = ev.residual_jacobian
        J = jac.toarray() if sp.issparse(jac) else np.asarray(jac, dtype=float).reshape(self.m, n)
        g = _values(ev.inequalities)
        e = _values(ev.equalities)
        jac_g = [_jacobian_data(b.jacobian) for b in ev.inequalities]
        jac_e = [_jacobian_data(b.jacobian) for b in ev.equalities]
        a_blocks = [_jacobian_data(lin.A), _jacobian_data(lin.G), self._M @ J, -np.ones(n_o),
                    *jac_g, -np.ones(self.n_ineq), *jac_e, -np.ones(self.n_eq), *[-j for j in jac_e],
                    -np.ones(self.n_eq), -np.ones(self.n_slack), 1.0 / scale, -1.0 / scale,
                    *(-_jacobian_data(block.jacobian) for block in ev.cones), -np.ones(self.n_cones)]
        A = self._a_pattern.matrix(a_blocks)
        A.data *= self._a_data_scale
        room = lin.h - lin.G @ x
        # a hard inequality the iterate meets only to the backend's tolerance must not make d = 0 infeasible
        room[(room < 0) & (room > -1e-7 * (1 + np.abs(lin.h)))] = 0.0
        b = np.concatenate([lin.b - lin.A @ x, room, self.outputs.m - self._M @ r, -g, -e, e,
                            np.zeros(self.n_slack), np.full(2 * n, radius), _values(ev.cones)])
        J_u = J * scale
        WJ = self.weights[:, None] * J_u
        hess = 2.0 * (J_u.T @ WJ)
        if self.curvature is not None and hessian is not None:
            rows, cols = self.curvature
            entries = hessian * scale[rows] * scale[cols]
            np.add.at(hess, (rows, cols), entries)
            off = rows != cols
            np.add.at(hess, (cols[off], rows[off]), entries[off])
        if curved is not None:
            hess = curved.hessian
        P = sp.csc_matrix((hess[self._p_rows, self._p_cols], self._p_indices, self._p_indptr),
                          shape=(self.num_z, self.num_z))
        q = np.full(self.num_z, float(penalty))
        q[:n] = 2.0 * (WJ.T @ r) + self._cost_u
        constant = float(self.weights @ r**2)
        if curved is not None:
            q[:n] += curved.linear
            constant += curved.constant
        return ConicProgram(P, q, A, b, self.cones, constant=constant)

    def multipliers(self, z: np.ndarray) -> Multipliers:
        """The nonlinear program's multipliers from the subproblem's row duals (see ``DualLayout``)."""
        return self.layout.multipliers(z)

    def step(self, z: np.ndarray) -> np.ndarray:
        """The step ``d`` from a subproblem solution (whose first block is ``d`` in scaled units)."""
        return z[: self.n] * self.scale
