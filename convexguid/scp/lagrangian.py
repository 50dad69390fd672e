"""The Lagrangian of the nonlinear program: its multipliers, its gradient, and the working set they define. With the
multipliers :math:`(\\omega, \\mu, \\lambda)` of the last subproblem (:class:`Multipliers`) its Hessian is

.. math::

    \\nabla^2_{xx} L = 2 J_r^T W J_r + \\sum_i \\omega_i \\nabla^2 r_i + \\sum_j \\mu_j \\nabla^2 g_j
    + \\sum_k \\lambda_k \\nabla^2 e_k ,

where :math:`\\omega = 2 W r + M^T \\nu` (:class:`CurvatureWeights`). Every subproblem has the Gauss-Newton part; the
rest comes from the program (``lagrangian_hessian(x, weights)``, exact), and a program without one gets no end game
(:mod:`convexguid.scp.endgame`, :mod:`convexguid.scp.curved`): no Hessian is differenced in the loop.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
import scipy.sparse as sp

from convexguid.scp.problem import Evaluation, LinearConstraints, OutputConstraints, per_block, stacked_values

MAX_DENSE_SIZE = 3000
"""Programs with more variables keep the first-order model (the end game works on dense matrices)."""


@dataclass(frozen=True)
class Multipliers:
    """Multipliers of the nonlinear program, read off a subproblem's dual, in the objective's units per unit of their
    constraint: ``equality`` (:math:`\\lambda`, free) and ``inequality`` (:math:`\\mu \\ge 0`) of the program's own
    nonlinear blocks in their order; ``output`` (:math:`\\nu \\ge 0`) of :math:`M r \\le m`; ``linear_equality`` and
    ``linear_inequality`` of :math:`Ax = b` and :math:`Gx \\le h`; ``cone`` (each in its cone) row by row."""

    equality: np.ndarray
    inequality: np.ndarray
    output: np.ndarray
    linear_equality: np.ndarray
    linear_inequality: np.ndarray
    cone: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def largest(self) -> float:
        """The largest multiplier of a nonlinear, output or cone constraint, in absolute value (at least 1e-12)."""
        return max(float(np.max(np.abs(np.concatenate([self.equality, self.inequality, self.output, self.cone])),
                                initial=0.0)), 1e-12)

    def cone_active(self) -> bool:
        """Whether some second-order cone holds with equality (its dual above round-off): the working-set models of
        the end game (:mod:`convexguid.scp.endgame`) know no cones, so their reduced space is then too large."""
        return bool(self.cone.size) and float(np.max(np.abs(self.cone))) > 1e-9 * (1.0 + self.largest())

    def significant(self) -> float:
        """The size from which a multiplier counts (1e-6 of the largest of any constraint): an interior-point solver
        leaves tiny positive duals on inactive rows."""
        everything = np.concatenate([self.linear_inequality, self.output, self.inequality, self.equality, [0.0]])
        return 1e-6 * max(float(np.max(np.abs(everything))), 1e-300)

    def curvature_weights(self, residuals: np.ndarray, weights: np.ndarray,
                          outputs: OutputConstraints) -> CurvatureWeights:
        """The Lagrangian's weights on each map's curvature: :math:`\\omega = 2 W r + M^T \\nu` on the residuals'."""
        omega = 2.0 * weights * residuals + (outputs.transposed @ self.output if self.output.size else 0.0)
        return CurvatureWeights(omega, self.inequality, self.equality)


@dataclass(frozen=True)
class CurvatureWeights:
    """What the curvature term weighs: :math:`\\omega` on the residuals, :math:`\\mu, \\lambda` on the blocks."""

    residual: np.ndarray
    inequality: np.ndarray
    equality: np.ndarray


def objective_gradient(ev: Evaluation, weights: np.ndarray, cost: np.ndarray) -> np.ndarray:
    """:math:`\\nabla f = c + 2 J_r^T W r` from an evaluation with Jacobians."""
    gradient = np.asarray(cost, dtype=float)
    if ev.residuals.size:
        gradient = gradient + 2.0 * (ev.residual_jacobian.T @ (weights * ev.residuals))
    return gradient


def lagrangian_gradient(ev: Evaluation, weights: CurvatureWeights) -> np.ndarray:
    """:math:`J_r^T \\omega + J_g^T \\mu + J_e^T \\lambda` from an evaluation with Jacobians."""
    total = _transpose_times(ev.residual_jacobian, weights.residual)
    for blocks, values in ((ev.inequalities, weights.inequality), (ev.equalities, weights.equality)):
        for block, part in per_block(blocks, values):
            total = total + _transpose_times(block.jacobian, part)
    return np.asarray(total, dtype=float).ravel()


def _transpose_times(jacobian, y: np.ndarray):
    return 0.0 if jacobian is None or y.size == 0 else jacobian.T @ y


def has_jacobian(ev: Evaluation) -> bool:
    """Whether a nonlinear map (residuals, inequalities, equalities) has a Jacobian entry (sparse: by its pattern)."""
    blocks = [ev.residual_jacobian, *(b.jacobian for b in (*ev.inequalities, *ev.equalities))]
    return any(b is not None and b.shape[0] > 0 and (not sp.issparse(b) or b.nnz > 0) for b in blocks)


@dataclass(frozen=True)
class WorkingSet:
    """The constraints taken as active, row by row in the order ``A``, ``G``, outputs, ``g`` blocks, ``e`` blocks: the
    hard equalities ``A x = b`` always; a nonlinear equality unless its multiplier reached the penalty weight (the
    subproblem paid to leave it unmet); an inequality (hard ``G x <= h``, output ``M r <= m``, nonlinear ``g``) when its
    multiplier is significant (and below the penalty weight, if softened) or its value is within the tolerance of its
    bound."""

    linear_inequality: np.ndarray
    output: np.ndarray
    inequality: np.ndarray
    equality: np.ndarray

    def __eq__(self, other: object) -> bool:
        return isinstance(other, WorkingSet) and all(np.array_equal(getattr(self, f.name), getattr(other, f.name))
                                                     for f in fields(self))

    __hash__ = None

    @classmethod
    def at(cls, ev: Evaluation, multipliers: Multipliers, linear: LinearConstraints, outputs: OutputConstraints,
           x: np.ndarray, tolerance: float, penalty: float) -> WorkingSet:
        significant, elastic = multipliers.significant(), 0.999 * penalty
        near_bound = linear.gap(x) >= -tolerance * (1 + np.abs(linear.h))
        return cls((multipliers.linear_inequality > significant) | near_bound,
                   ((multipliers.output > significant) | (outputs.gap(ev.residuals) >= -tolerance))
                   & (multipliers.output < elastic),
                   ((multipliers.inequality > significant) | (stacked_values(ev.inequalities) >= -tolerance))
                   & (multipliers.inequality < elastic),
                   np.abs(multipliers.equality) < elastic)

    def values(self, ev: Evaluation, linear: LinearConstraints, outputs: OutputConstraints,
               x: np.ndarray) -> np.ndarray:
        """The working rows' values at ``x`` (``ev``: the program's evaluation there): zero on their bounds."""
        return np.concatenate([linear.A @ x - linear.b if linear.A.shape[0] else np.zeros(0),
                               linear.gap(x)[self.linear_inequality], outputs.gap(ev.residuals)[self.output],
                               stacked_values(ev.inequalities)[self.inequality],
                               stacked_values(ev.equalities)[self.equality]])

    def rows(self, ev: Evaluation, linear: LinearConstraints, outputs: OutputConstraints) -> np.ndarray:
        """The working rows' dense Jacobian at ``ev`` 's point (end-game programs are small: :data:`MAX_DENSE_SIZE`)."""
        parts = [_dense_rows(linear.A, None), _dense_rows(linear.G, self.linear_inequality)]
        if outputs.M.shape[0]:
            parts.append(_dense_rows(outputs.M @ ev.residual_jacobian, self.output))
        for blocks, mask in ((ev.inequalities, self.inequality), (ev.equalities, self.equality)):
            parts += [_dense_rows(block.jacobian, part) for block, part in per_block(blocks, mask)]
        return np.vstack(parts)

    def multipliers(self, y: np.ndarray, linear_equalities: int) -> Multipliers:
        """The working rows' multipliers ``y`` (``A x = b`` 's first) spread over every constraint, zero off the set."""
        start, spread = linear_equalities, []
        for mask in (self.linear_inequality, self.output, self.inequality, self.equality):
            values = np.zeros(mask.size)
            values[mask] = y[start: start + int(mask.sum())]
            spread.append(values)
            start += int(mask.sum())
        g, o, i, e = spread
        return Multipliers(equality=e, inequality=i, output=o, linear_equality=y[:linear_equalities].copy(),
                           linear_inequality=g)


def _dense_rows(matrix, mask: np.ndarray | None) -> np.ndarray:
    """The rows of ``matrix`` (dense or sparse) that ``mask`` selects (all without one), as a dense array."""
    if sp.issparse(matrix):
        matrix = sp.csr_matrix(matrix)
        return (matrix if mask is None else matrix[mask]).toarray()
    matrix = np.asarray(matrix, dtype=float)
    return matrix if mask is None else matrix[mask]
