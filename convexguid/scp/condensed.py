"""The trust-region subproblem with the lifted residuals eliminated (the condensed form). When :math:`n` is small and
the Jacobians are dense, substituting the lifted :math:`y = r + J d` of :mod:`convexguid.scp.assembly` leaves a small
dense QP in the scaled step :math:`u = S^{-1} d` (:math:`S = \\operatorname{diag}\\sigma`), with variables ``z = [u,
s_o, s_g, t, s_c]``:

.. math::

    \\min\\; u^T S (J^T W J + \\tfrac12 H) S u + (2 J^T W r + c)^T S u + r^T W r
    + \\rho\\,(1^T s_o + 1^T s_g + 1^T t + 1^T s_c)

    \\text{s.t.}\\quad A S u = b - A x,\\quad G S u \\le h - G x,\\quad M J S u - s_o \\le m - M r,

    g + \\nabla g\\, S u \\le s_g,\\quad |e + \\nabla e\\, S u| \\le t,\\quad
    \\|v_{1:} + F_{1:} S u\\| \\le v_0 + F_0 S u + s_c,\\quad s_o, s_g, t, s_c \\ge 0,\\quad |u_i| \\le \\Delta,

the lifted subproblem with :math:`y` substituted: the same step and value (:math:`r^T W r` rides along in
:attr:`ConicProgram.constant`, so ``program.objective(z)`` is the model value), the same slacks, and its rows in the
lifted order less ``J d - y = -r``. :class:`CondensedAssembler` has the interface of
:class:`~convexguid.scp.assembly.SubproblemAssembler`; the dense backend solves it in ``u`` alone (docs/engine.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from convexguid.backends import ConicProgram
from convexguid.scp.assembly import SubproblemRows, _jacobian_data, _Pattern
from convexguid.scp.problem import Evaluation, LinearConstraints, OutputConstraints


@dataclass(frozen=True)
class CurvedTerms:
    """The curved subproblem's Hessian in ``u`` (replacing the condensed one) with its linear and constant terms."""

    hessian: np.ndarray | sp.csc_matrix
    linear: np.ndarray
    constant: float


class CondensedAssembler(SubproblemRows):
    """Builds the condensed trust-region subproblem: the output rows ``M J`` dense on ``u``; ``P`` dense on ``u``, zero
    on the slacks. With cones it needs a conic backend (the curved subproblem's Clarabel): the dense one takes none."""

    def __init__(self, n: int, first: Evaluation, linear: LinearConstraints, outputs: OutputConstraints,
                 scale: np.ndarray, linear_cost: np.ndarray, weights: np.ndarray,
                 curvature: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        super().__init__(n, first, linear, outputs, scale, weights, curvature, lifted=False)
        self._M = sp.csr_matrix(outputs.M)
        # P: the dense upper triangle of the u block
        rows, cols = np.triu_indices(n)
        self._p_pattern = _Pattern((self.num_z, self.num_z))
        self._p_pattern.add_entries(rows, cols)
        self._p_pattern.finish()
        self._p_flat = rows * n + cols  # the upper triangle's entries in the dense Hessian
        self._cost_u = np.asarray(linear_cost, dtype=float) * scale

    def build(self, x: np.ndarray, ev: Evaluation, radius: float, penalty: float,
              hessian: np.ndarray | None = None, curved: CurvedTerms | None = None) -> ConicProgram:
        """The subproblem about ``x`` (as :meth:`~convexguid.scp.assembly.SubproblemAssembler.build` makes it), with
        the :class:`CurvedTerms` ``curved`` if given (its Hessian positive semidefinite, Gauss-Newton part included)."""
        n, scale = self.n, self.scale
        r, jac = ev.residuals, ev.residual_jacobian
        J = jac.toarray() if sp.issparse(jac) else np.asarray(jac, dtype=float).reshape(self.m, n)
        head = [_jacobian_data(self.linear.A), _jacobian_data(self.linear.G), self._M @ J, -np.ones(self._M.shape[0])]
        A, b = self.constraints(x, ev, radius, head, [np.zeros(0), self.outputs.m - self._M @ r])
        J_u = J * scale
        WJ = self.weights[:, None] * J_u
        hess = 2.0 * (J_u.T @ WJ) if curved is None else curved.hessian
        if curved is None and self.curvature is not None and hessian is not None:
            rows, cols = self.curvature
            entries = hessian * scale[rows] * scale[cols]
            np.add.at(hess, (rows, cols), entries)
            off = rows != cols
            np.add.at(hess, (cols[off], rows[off]), entries[off])
        if sp.issparse(hess):
            # a sparse curved Hessian keeps its own pattern (the program is then set up afresh, not updated)
            P = sp.block_diag([sp.triu(hess), sp.csc_matrix((self.num_z - n, self.num_z - n))], format="csc")
        else:  # on the fixed dense pattern: the upper triangle on u, zero on the slacks
            P = self._p_pattern.matrix([hess.ravel()[self._p_flat]])
        q = np.full(self.num_z, float(penalty))
        q[:n] = 2.0 * (WJ.T @ r) + self._cost_u
        constant = float(self.weights @ r**2)
        if curved is not None:
            q[:n] += curved.linear
            constant += curved.constant
        return ConicProgram(P, q, A, b, self.cones, constant=constant)
