"""The Lagrangian of the nonlinear program: multipliers, its exact Hessian, and a convex model of it.

The engine's subproblem linearizes the constraints. Near a solution that is a first-order model of
a problem whose curvature lives in its constraints (the rigid-body defects, the keep-out cones, the
unit-thrust direction), and the iteration converges like a first-order method: linearly, with a
trust region that has to shrink onto the answer. Sequential quadratic programming keeps the
curvature: with the multipliers :math:`(\\omega, \\mu, \\lambda)` of the last subproblem,

.. math::

    \\nabla^2_{xx} L = 2 J_r^T W J_r + \\sum_i \\omega_i \\nabla^2 r_i + \\sum_j \\mu_j \\nabla^2 g_j
    + \\sum_k \\lambda_k \\nabla^2 e_k ,

where :math:`\\omega = 2 W r + M^T \\nu` collects the objective's and the output constraints' weight
on the residuals. The first term is the Gauss-Newton part every subproblem already has; this module
supplies the rest (:meth:`LagrangianHessian.curvature`) and makes the sum convex where it is not
(:func:`convexified`): the quadratic subproblem must stay convex for the conic solvers, and it
only needs to be convex on the directions the active constraints leave free. Adding
:math:`\\gamma A^T A` over the active constraint rows :math:`A` does not change the model on those
directions and, for :math:`\\gamma` large enough, makes the Hessian positive definite whenever its
reduced Hessian is (Finsler's lemma; Nocedal & Wright, *Numerical Optimization*, 2nd ed.,
Thm. 12.6 and Sec. 17.3, the augmented Lagrangian). Where the reduced Hessian itself is indefinite
a multiple of the identity is added (Levenberg; Nocedal & Wright Sec. 3.4) and the direction of
negative curvature is kept: a stationary point with one is not a minimum
(:func:`negative_curvature`).

**Second derivatives.** A program may give the curvature term itself (``lagrangian_hessian(x,
weights)``, exact where its maps are symbolic). Otherwise it is computed from the program's own
Jacobians by differences of the gradient :math:`J^T y` along a few combined directions: columns
that share no row of the Hessian's sparsity pattern, nor a neighbour in it, are perturbed together
(a distance-2 colouring: Gebremedhin, Manne & Pothen, "What color is your Jacobian?", SIAM Review
47(4), 2005), and columns that touch nearly every row (a free final time) alone. Forward
differences with steps of :data:`DIFFERENCE_STEP` in scaled units leave errors near
:math:`10^{-7}` relative: Newton's method then converges superlinearly all the same, and the
converged point is fixed by the KKT conditions, not by the Hessian.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from convexguid.scp.problem import Evaluation, LinearConstraints, NonconvexProgram, OutputConstraints

DIFFERENCE_STEP = 1e-7
"""Forward-difference step of the Hessian, in scaled variables (whose trust box is about 1)."""

DENSE_COLUMN_FACTOR = 4.0
"""A column whose Hessian row reaches more than this many times the median row's columns is differenced alone."""

MAX_DENSE_SIZE = 3000
"""Programs with more variables keep the first-order model (the end game works on dense matrices)."""



@dataclass(frozen=True)
class Multipliers:
    """Multipliers of the nonlinear program, read off a subproblem's dual.

    ``equality`` (:math:`\\lambda`, free) and ``inequality`` (:math:`\\mu \\ge 0`) belong to the
    program's own nonlinear blocks in their order; ``output`` (:math:`\\nu \\ge 0`) to the output
    constraints :math:`M r \\le m`; ``linear_equality`` and ``linear_inequality`` to :math:`Ax = b` and
    :math:`Gx \\le h`; ``cone`` (each in its second-order cone) to the program's cones, row by row. Each is in
    the objective's units per unit of its constraint.
    """

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

    def significant(self) -> float:
        """The size from which a multiplier counts (1e-6 of the largest of any constraint): an interior-point solver
        leaves tiny positive duals on inactive rows."""
        everything = np.concatenate([self.linear_inequality, self.output, self.inequality, self.equality, [0.0]])
        return 1e-6 * max(float(np.max(np.abs(everything))), 1e-300)

    def residual_weights(self, residuals: np.ndarray, weights: np.ndarray, outputs_M: sp.spmatrix) -> np.ndarray:
        """:math:`\\omega = 2 W r + M^T \\nu`: the weight of each residual's curvature in the Lagrangian."""
        return 2.0 * weights * residuals + (outputs_M.T @ self.output if self.output.size else 0.0)


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
        start = 0
        for block in blocks:
            size = block.values.size
            total = total + _transpose_times(block.jacobian, values[start: start + size])
            start += size
    return np.asarray(total, dtype=float).ravel()


def _transpose_times(jacobian, y: np.ndarray):
    if jacobian is None or y.size == 0:
        return 0.0
    return jacobian.T @ y


def jacobian_structure(ev: Evaluation, n: int) -> sp.csr_matrix:
    """Boolean rows of every nonlinear map (residuals, inequalities, equalities): the pattern of their Jacobians.

    Dense blocks count as dense (their zeros may fill in later); sparse ones keep their fixed pattern.
    """
    parts = [ev.residual_jacobian, *(b.jacobian for b in (*ev.inequalities, *ev.equalities))]
    rows = []
    for block in parts:
        if block is None or block.shape[0] == 0:
            continue
        if sp.issparse(block):
            coo = sp.coo_matrix(block)
            rows.append(sp.csr_matrix((np.ones(coo.nnz), (coo.row, coo.col)), shape=coo.shape))
        else:
            rows.append(sp.csr_matrix(np.ones((block.shape[0], n))))
    if not rows:
        return sp.csr_matrix((0, n))
    stacked = sp.vstack(rows).tocsr()
    stacked.data[:] = 1.0
    return stacked


class LagrangianHessian:
    """The curvature :math:`\\sum\\omega_i\\nabla^2 r_i + \\sum\\mu_j\\nabla^2 g_j + \\sum\\lambda_k\\nabla^2 e_k`.

    Exact when the program has ``lagrangian_hessian(x, weights)``; otherwise forward differences of
    :func:`lagrangian_gradient` along the colour groups of the pattern (see the module docstring).
    ``pattern`` is the symmetric boolean pattern every curvature term fits in.
    """

    def __init__(self, program: NonconvexProgram, first: Evaluation, scale: np.ndarray) -> None:
        self.program, self.scale = program, scale
        n = program.num_variables
        structure = jacobian_structure(first, n)
        pattern = (structure.T @ structure).tocsr()
        pattern.data[:] = 1.0
        self.pattern = pattern
        self.exact = getattr(program, "lagrangian_hessian", None)
        self.groups = [] if self.exact is not None else _colour_groups(pattern)
        self._alone = np.zeros(n, dtype=bool)
        for group, alone in self.groups:
            self._alone[group] = alone

    @property
    def evaluations(self) -> int:
        """Program evaluations one finite-difference Hessian costs (0 when the program gives it exactly)."""
        return len(self.groups)

    def curvature(self, x: np.ndarray, weights: CurvatureWeights) -> sp.csr_matrix:
        """The curvature term at ``x`` (symmetric, within :attr:`pattern`)."""
        if self.exact is not None:
            return sp.csr_matrix(self.exact(x, weights))
        n = x.size
        rows, cols, vals = [], [], []
        base = lagrangian_gradient(self.program.evaluate(x, True), weights)
        for group, alone in self.groups:
            direction = np.zeros(n)
            step = DIFFERENCE_STEP * self.scale[group]
            direction[group] = step
            change = lagrangian_gradient(self.program.evaluate(x + direction, True), weights) - base
            for j, h in zip(group, step, strict=True):
                reach = self.pattern.indices[self.pattern.indptr[j]: self.pattern.indptr[j + 1]]
                if alone:
                    # a lone column: its whole column, mirrored into the rows the grouped passes skip
                    mirror = reach[~self._alone[reach]]
                    rows += [reach, np.full(mirror.size, j)]
                    cols += [np.full(reach.size, j), mirror]
                    vals += [change[reach] / h, change[mirror] / h]
                else:
                    # row i of the difference belongs to the one column of the group it neighbours
                    reach = reach[~self._alone[reach]]
                    rows.append(reach)
                    cols.append(np.full(reach.size, j))
                    vals.append(change[reach] / h)
        if not rows:
            return sp.csr_matrix((n, n))
        hessian = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
        # every off-diagonal entry was read twice (once from each of its columns): the mean of the two
        return (0.5 * (hessian + hessian.T)).tocsr()


def _colour_groups(pattern: sp.csr_matrix) -> list[tuple[np.ndarray, bool]]:
    """Column groups for differencing the Hessian: ``(columns, alone)``.

    Columns whose row reaches more than :data:`DENSE_COLUMN_FACTOR` times the median row's columns, or half
    the columns, are differenced alone (``alone=True``: their whole column is read off). The others are
    coloured greedily so that no two columns of a group are within distance two in the pattern's graph
    without the lone columns: every row then sees at most one column of the group, and its difference
    belongs to that column.
    The entries between a lone column and the others are read off the lone column's difference.
    """
    degree = np.diff(pattern.indptr)
    alone = degree > max(min(DENSE_COLUMN_FACTOR * float(np.median(degree)), 0.5 * degree.size), 8)
    groups: list[tuple[np.ndarray, bool]] = [(np.array([j]), True) for j in np.flatnonzero(alone)]
    keep = ~alone
    reduced = pattern[keep][:, keep].tocsr()
    index = np.flatnonzero(keep)
    two_step = (reduced @ reduced).tocsr()
    colour = np.full(index.size, -1)
    for v in range(index.size):
        near = two_step.indices[two_step.indptr[v]: two_step.indptr[v + 1]]
        used = set(colour[near][colour[near] >= 0].tolist())
        c = 0
        while c in used:
            c += 1
        colour[v] = c
    for c in range(colour.max(initial=-1) + 1):
        groups.append((index[colour == c], False))
    return groups


@dataclass(frozen=True)
class WorkingSet:
    """The constraints taken as active: which rows of each kind, so their values can be read at any point.

    The hard equalities ``A x = b`` are always in it. A nonlinear equality ``e`` is, unless its multiplier
    reached the penalty weight: the subproblem then paid to leave it unmet (its linearization conflicts with
    the others), and Newton's step must not insist on it either. An inequality (hard ``G x <= h``, output
    ``M r <= m``, nonlinear ``g``) is in it when its multiplier is significant (and below the penalty
    weight, for the softened ones) or its value is within the tolerance of its bound. Rows come in the
    order: ``A``, ``G``, outputs, ``g`` blocks, ``e`` blocks.
    """

    linear_inequality: np.ndarray
    output: np.ndarray
    inequality: np.ndarray
    equality: np.ndarray

    def __eq__(self, other: object) -> bool:
        return isinstance(other, WorkingSet) and all(
            np.array_equal(a, b) for a, b in zip(self.masks, other.masks, strict=True))

    __hash__ = None

    @property
    def masks(self) -> tuple[np.ndarray, ...]:
        return self.linear_inequality, self.output, self.inequality, self.equality

    @classmethod
    def at(cls, ev: Evaluation, multipliers: Multipliers, linear: LinearConstraints, outputs: OutputConstraints,
           x: np.ndarray, tolerance: float, penalty: float) -> WorkingSet:
        significant = multipliers.significant()
        gap = linear.G @ x - linear.h if linear.G.shape[0] else np.zeros(0)
        out = outputs.M @ ev.residuals - outputs.m if outputs.M.shape[0] else np.zeros(0)
        values = _values_of(ev.inequalities)
        elastic = 0.999 * penalty
        return cls((multipliers.linear_inequality > significant) | (gap >= -tolerance * (1 + np.abs(linear.h))),
                   ((multipliers.output > significant) | (out >= -tolerance)) & (multipliers.output < elastic),
                   ((multipliers.inequality > significant) | (values >= -tolerance))
                   & (multipliers.inequality < elastic),
                   np.abs(multipliers.equality) < elastic)

    def values(self, ev: Evaluation, linear: LinearConstraints, outputs: OutputConstraints,
               x: np.ndarray) -> np.ndarray:
        """The working rows' values at ``x`` (``ev``: the program's evaluation there): zero on their bounds."""
        parts = [linear.A @ x - linear.b if linear.A.shape[0] else np.zeros(0)]
        parts.append((linear.G @ x - linear.h)[self.linear_inequality] if linear.G.shape[0] else np.zeros(0))
        parts.append((outputs.M @ ev.residuals - outputs.m)[self.output] if outputs.M.shape[0] else np.zeros(0))
        parts.append(_values_of(ev.inequalities)[self.inequality])
        parts.append(_values_of(ev.equalities)[self.equality])
        return np.concatenate(parts)

    def rows(self, ev: Evaluation, linear: LinearConstraints, outputs: OutputConstraints) -> sp.csr_matrix:
        """The working rows' Jacobian at the point ``ev`` was evaluated (with Jacobians)."""
        n = ev.residual_jacobian.shape[1] if ev.residual_jacobian is not None else None
        parts = [sp.csr_matrix(linear.A, dtype=float), sp.csr_matrix(linear.G, dtype=float)[self.linear_inequality]]
        n = parts[0].shape[1] if n is None else n
        if outputs.M.shape[0]:
            parts.append(sp.csr_matrix(outputs.M @ ev.residual_jacobian)[self.output])
        for blocks, mask in ((ev.inequalities, self.inequality), (ev.equalities, self.equality)):
            start = 0
            for block in blocks:
                size = block.values.size
                parts.append(sp.csr_matrix(block.jacobian)[mask[start: start + size]])
                start += size
        parts = [p for p in parts if p.shape[0]]
        return sp.vstack(parts).tocsr() if parts else sp.csr_matrix((0, n))

    def multipliers(self, y: np.ndarray, like: Multipliers) -> Multipliers:
        """Working-set multipliers ``y`` (in row order) spread back over every constraint (zero off the set)."""
        sizes = [like.linear_equality.size, int(self.linear_inequality.sum()), int(self.output.sum()),
                 int(self.inequality.sum()), int(self.equality.sum())]
        ends = np.cumsum(sizes)
        a, g, o, i, e = (y[end - size: end] for end, size in zip(ends, sizes, strict=True))

        def spread(mask: np.ndarray, values: np.ndarray) -> np.ndarray:
            out = np.zeros(mask.size)
            out[mask] = values
            return out

        return Multipliers(equality=spread(self.equality, e), inequality=spread(self.inequality, i),
                           output=spread(self.output, o),
                           linear_equality=a.copy(), linear_inequality=spread(self.linear_inequality, g))


def _values_of(blocks) -> np.ndarray:
    return np.concatenate([b.values for b in blocks]) if blocks else np.zeros(0)
