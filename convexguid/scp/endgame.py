"""The second-order end game: Newton's step on the constraints the last subproblem found active.

The convex subproblem finds the active constraints long before its first-order model converges, but carries none of
their curvature. Near feasibility the engine also takes the equality-constrained quadratic step on that working set
:math:`\\mathcal W`, :math:`\\min_d \\nabla f^T d + \\tfrac12 d^T \\nabla^2_{xx} L\\, d` s.t.
:math:`c_{\\mathcal W} + A_{\\mathcal W} d = 0` (the EQP step of SLQP methods: Byrd, Gould, Nocedal & Waltz, "An
algorithm for nonlinear optimization using linear programming and equality constrained subproblems", Math. Prog. 100,
2004; Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sec. 18.1 and 18.6), solved in the null space of
:math:`A_{\\mathcal W}` (Nocedal & Wright eqs. 16.17-16.19) with the exact Hessian of the Lagrangian
(:mod:`convexguid.scp.lagrangian`). Where the reduced Hessian :math:`Z^T \\nabla^2 L Z` is not positive definite its
most negative eigenvalue :math:`\\lambda_1` is kept with its direction (a saddle's) and the step is taken with
:math:`Z^T \\nabla^2 L Z + \\delta I`, :math:`\\delta = 1.1 |\\lambda_1|` (IPOPT's inertia correction, its shift read
off the eigenvalues: Wachter & Biegler, Math. Program. 106, 2006, Sec. 3.1; docs/engine.md, 'Newton end game').
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from convexguid.scp.lagrangian import CurvatureWeights, Multipliers, WorkingSet, objective_gradient
from convexguid.scp.problem import Evaluation, LinearConstraints, NonconvexProgram, OutputConstraints

RANK_TOLERANCE = 1e-6
"""Rows of the working set whose pivots fall below this share of the largest are taken as dependent."""

REGULARIZATION = 0.1
"""Where the reduced Hessian has negative curvature, :func:`newton_step` shifts it by its most negative eigenvalue
and this share of it again."""


@dataclass(frozen=True)
class NewtonStep:
    """The EQP step (scaled variables), the multipliers of the working set, and the reduced Hessian's verdict:
    ``shift``, what was added to its diagonal where it is not positive definite (the step is then regularized, not
    Newton's), its ``smallest_eigenvalue`` and ``negative_direction`` (scaled, unit max-norm, deterministic sign).
    ``step`` is ``None`` only when a hard bound outside the working set cut it off."""

    step: np.ndarray | None
    multipliers: np.ndarray | None
    smallest_eigenvalue: float
    negative_direction: np.ndarray | None = None
    shift: float = 0.0


class NullSpaceSplit(NamedTuple):
    """Bases of the range (``Y``) and null space (``Z``) of the rows, ``R`` and ``pivots`` of the independent ones,
    and every row's ``norms``."""

    Y: np.ndarray
    Z: np.ndarray
    R: np.ndarray
    pivots: np.ndarray
    norms: np.ndarray


def null_space_split(rows: np.ndarray) -> NullSpaceSplit:
    """The pivoted QR factorization :math:`(D^{-1} A)^T P = Q R` of the rows each divided by its norm (:math:`D`):
    independence judged by direction, not units (docs/engine.md, 'Newton end game'). Rows whose pivot is below
    :data:`RANK_TOLERANCE` of the largest depend on the others (a quaternion's unit norm, kept by the dynamics, fixed
    at both ends) and are left out."""
    n = rows.shape[1]
    norms = np.linalg.norm(rows, axis=1)
    norms = np.where(norms > 0, norms, 1.0)
    if rows.shape[0] == 0:
        return NullSpaceSplit(np.zeros((n, 0)), np.eye(n), np.zeros((0, 0)), np.zeros(0, dtype=int), norms)
    Q, R, pivots = la.qr((rows / norms[:, None]).T, pivoting=True, mode="full")
    diag = np.abs(np.diag(R))
    rank = int(np.sum(diag > RANK_TOLERANCE * max(diag[0], 1e-300))) if diag.size else 0
    return NullSpaceSplit(Q[:, :rank], Q[:, rank:], R[:rank, :rank], pivots[:rank], norms)


def least_norm_step(split: NullSpaceSplit, values: np.ndarray) -> np.ndarray:
    """:math:`-Y (R^T)^{-1} (D^{-1} c)_P`: the least-norm step onto the linearized rows of a split."""
    Y, _, R, pivots, norms = split
    if not pivots.size:
        return np.zeros(Y.shape[0])
    return Y @ la.solve_triangular(R, -(values / norms)[pivots], trans="T")


def newton_step(gradient: np.ndarray, hessian: np.ndarray, rows: np.ndarray, values: np.ndarray) -> NewtonStep:
    """The EQP step for gradient ``g``, Hessian ``H``, working-set rows ``A`` and values ``c`` (all scaled): range
    part :math:`d_Y = -Y (R^T)^{-1} (D^{-1} c)_P` (least norm onto the linearized working set), null-space part from
    :math:`Z^T H Z\\, p = -Z^T (g + H d_Y)`, multipliers from :math:`R\\, (D y)_P = -Y^T (g + H d)` (zero on
    dependent rows; :func:`null_space_split` for :math:`D`)."""
    split = null_space_split(rows)
    Y, Z, R, pivots, norms = split
    range_step = least_norm_step(split, values)
    reduced = Z.T @ hessian @ Z
    reduced = 0.5 * (reduced + reduced.T)
    smallest, direction, shift = np.inf, None, 0.0
    if reduced.shape[0] == 0:
        step = range_step
    else:
        right = -(Z.T @ (gradient + hessian @ range_step))
        try:
            null = la.cho_solve(la.cho_factor(reduced, lower=True, check_finite=False), right)
        except la.LinAlgError:
            eigenvalues, vectors = la.eigh(reduced)
            smallest = float(eigenvalues[0])
            direction = Z @ vectors[:, 0]
            direction = direction / np.max(np.abs(direction))
            direction = direction * np.sign(direction[np.argmax(np.abs(direction))])
            floor = RANK_TOLERANCE * abs(eigenvalues[-1])
            if floor == 0.0:  # no curvature at all in the null space: a step of unit size (scaled) down the gradient
                floor = max(float(np.max(np.abs(right))), 1.0)
            shift = -smallest + max(REGULARIZATION * -smallest, floor)
            null = vectors @ ((vectors.T @ right) / (eigenvalues + shift))
        step = range_step + Z @ null
    multipliers = np.zeros(rows.shape[0])
    if pivots.size:
        multipliers[pivots] = la.solve_triangular(R, -(Y.T @ (gradient + hessian @ step))) / norms[pivots]
    return NewtonStep(step, multipliers, smallest, direction, shift)


@dataclass(frozen=True)
class LocalModel:
    """The second-order model at one iterate, in scaled variables :math:`u = S^{-1} d`: ``hessian`` the whole
    :math:`S \\nabla^2_{xx} L S` (Gauss-Newton part included), ``gradient`` :math:`S \\nabla f`, ``rows`` and
    ``values`` the working set's :math:`A S` and :math:`c`."""

    hessian: np.ndarray
    gradient: np.ndarray
    working: WorkingSet
    rows: np.ndarray
    values: np.ndarray

    def newton(self) -> NewtonStep:
        """:func:`newton_step` on this model."""
        return newton_step(self.gradient, self.hessian, self.rows, self.values)

    def correction(self, values: np.ndarray) -> np.ndarray:
        """The least-norm scaled step :math:`-A^+ c` back onto the working set from where its values are ``values``:
        added to a trial step whose working set came out so, it cancels them to first order (Fletcher's second-order
        correction in its least-norm form, Nocedal & Wright eq. 18.53)."""
        return least_norm_step(null_space_split(self.rows), values)

    def quadratic(self, u: np.ndarray) -> float:
        """:math:`\\nabla f^T d + \\tfrac12 u^T H u`: the objective part of the model."""
        return float(self.gradient @ u + 0.5 * u @ (self.hessian @ u))


class SecondOrderModels:
    """Builds :class:`LocalModel` s of one program: its Lagrangian Hessian, scales and constant data."""

    def __init__(self, program: NonconvexProgram, linear: LinearConstraints, scale: np.ndarray, weights: np.ndarray,
                 cost: np.ndarray, outputs: OutputConstraints) -> None:
        self.hessian = program.lagrangian_hessian
        # CSR once: every model reads rows of A and G (a program's COO pattern would be converted each time)
        self.linear = replace(linear, A=_csr(linear.A), G=_csr(linear.G))
        self.scale, self.weights, self.cost, self.outputs = scale, weights, cost, outputs

    def gauss_newton(self, raw: Evaluation) -> np.ndarray:
        """:math:`2 S J_r^T W J_r S` (scaled, dense)."""
        n = self.scale.size
        jac = raw.residual_jacobian
        if jac is None or raw.residuals.size == 0:
            return np.zeros((n, n))
        J = (jac.toarray() if sp.issparse(jac) else np.asarray(jac, dtype=float)) * self.scale
        return 2.0 * J.T @ (self.weights[:, None] * J)

    def working_set(self, x: np.ndarray, raw: Evaluation, multipliers: Multipliers, tolerance: float,
                    penalty: float) -> WorkingSet:
        """The working set at ``x`` of a subproblem with penalty weight ``penalty`` and these ``multipliers``."""
        return WorkingSet.at(raw, multipliers, self.linear, self.outputs, x, tolerance, penalty)

    def at(self, x: np.ndarray, raw: Evaluation, multipliers: Multipliers, working: WorkingSet) -> LocalModel:
        """The model at ``x`` (``raw``: the program's evaluation there, with Jacobians) on ``working``."""
        omega = multipliers.residual_weights(raw.residuals, self.weights, self.outputs)
        curvature = self.hessian(x, CurvatureWeights(omega, multipliers.inequality, multipliers.equality))
        hessian = self.gauss_newton(raw) + _scaled_dense(curvature, self.scale)
        gradient = objective_gradient(raw, self.weights, self.cost)
        rows = working.rows(raw, self.linear, self.outputs) * self.scale
        return LocalModel(hessian, gradient * self.scale, working, rows,
                          working.values(raw, self.linear, self.outputs, x))

    def with_bounds(self, model: LocalModel, raw: Evaluation, x: np.ndarray, added: np.ndarray) -> LocalModel:
        """``model`` with the hard inequality rows ``added`` (a mask of ``G``'s rows) put into its working set."""
        working = replace(model.working, linear_inequality=model.working.linear_inequality | added)
        rows = working.rows(raw, self.linear, self.outputs) * self.scale
        return replace(model, working=working, rows=rows, values=working.values(raw, self.linear, self.outputs, x))

    def onto_equalities(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The scaled step ``u`` moved (least change) so that ``x + S u`` meets ``A x = b`` exactly (the working set
        may have dropped a hard boundary condition as dependent)."""
        return u + self.linear.onto_equalities(x + u * self.scale, self.scale)

    def broken_bounds(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Mask of the hard inequality rows ``G x <= h`` that the scaled step ``u`` from ``x`` breaks."""
        if not self.linear.G.shape[0]:
            return np.zeros(0, dtype=bool)
        gap = self.linear.G @ (x + u * self.scale) - self.linear.h
        return gap > 1e-9 * (1 + np.abs(self.linear.h))


def linearized_violation(raw: Evaluation, outputs: OutputConstraints, d: np.ndarray) -> float:
    """The :math:`\\ell_1` violation of the constraints linearized at ``raw`` 's point, after the step ``d``."""
    total = 0.0
    if outputs.M.shape[0]:
        moved = raw.residuals + raw.residual_jacobian @ d
        total += float(np.maximum(outputs.M @ moved - outputs.m, 0.0).sum())
    for block in raw.inequalities:
        total += float(np.maximum(block.values + block.jacobian @ d, 0.0).sum())
    for block in raw.equalities:
        total += float(np.abs(block.values + block.jacobian @ d).sum())
    for cone in raw.cones:  # affine: its value after the step is exact
        total += float(cone.violations(cone.values + cone.jacobian @ d).sum())
    return total


def _scaled_dense(curvature: np.ndarray | sp.spmatrix, scale: np.ndarray) -> np.ndarray:
    """:math:`S \\nabla^2 S` as a dense array, each entry times :math:`\\sigma_i \\sigma_j`: a sparse Hessian entry by
    entry, a dense one as it is (no round trip through a sparse matrix)."""
    outer = np.outer(scale, scale)
    if sp.issparse(curvature):
        return sp.csr_matrix(curvature).multiply(outer).toarray()
    return np.asarray(curvature, dtype=float) * outer


def _csr(matrix):
    """``matrix`` as CSR if it is sparse, as it is if dense."""
    return sp.csr_matrix(matrix) if sp.issparse(matrix) else matrix
