"""The second-order end game: Newton's step on the constraints the last subproblem found active. The convex subproblem
finds the active constraints long before its first-order model converges, but carries none of their curvature. Near
feasibility the engine also takes the equality-constrained quadratic step on that working set :math:`\\mathcal W`,
:math:`\\min_d \\nabla f^T d + \\tfrac12 d^T \\nabla^2_{xx} L\\, d` s.t. :math:`c_{\\mathcal W} + A_{\\mathcal W} d = 0`
(the EQP step of SLQP methods: Byrd, Gould, Nocedal & Waltz, "An algorithm for nonlinear optimization using linear
programming and equality constrained subproblems", Math. Prog. 100, 2004; Nocedal & Wright, *Numerical Optimization*,
2nd ed., Sec. 18.1 and 18.6), solved in the null space of :math:`A_{\\mathcal W}` (Nocedal & Wright eqs. 16.17-16.19)
with the exact Hessian of the Lagrangian (:mod:`convexguid.scp.lagrangian`). Where the reduced Hessian :math:`Z^T
\\nabla^2 L Z` is not positive definite its most negative eigenvalue :math:`\\lambda_1` is kept with its direction (a
saddle's) and the step is taken with :math:`Z^T \\nabla^2 L Z + \\delta I`, :math:`\\delta = 1.1 |\\lambda_1|` (IPOPT's
inertia correction, its shift read off the eigenvalues: Wachter & Biegler, Math. Program. 106, 2006, Sec. 3.1;
docs/engine.md, 'Newton end game').

In an SCP iteration the step is made safe: within ``second_order_violation`` of feasibility, :func:`newton_candidate`
proposes it only once two subproblems in a row agree on the working set; on the hard equalities and within the hard
inequalities (a bound it breaks joins the working set, twice at most, else no step); inside a trust region of its own (a
quarter of a step that failed, doubled by a good cut one, freed by a good whole one) and the larger of the first-order
one and the whole length of the last good cut step (which opens the first-order one too); judged by the merit's ratio
test or else the funnel
(:meth:`~convexguid.scp.engine.SCPAlgorithm.judged`), with the weight at most the one that follows the multipliers
(:meth:`~convexguid.scp.policies.PenaltyPolicy.judging`; Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sec.
18.3); with a least-norm second-order correction when its ratio is poor (the Maratos effect). A regularized step (the
reduced Hessian indefinite) is judged by the merit alone with the iterate's own weight, and never taken when it breaks a
hard bound. The engine takes the step only if it does at least as well as the first-order one: the end game can make an
iteration better, never worse (why each rule: docs/engine.md, 'Newton end game').
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from convexguid.scp.lagrangian import Multipliers, WorkingSet, objective_gradient
from convexguid.scp.merit import max_violation
from convexguid.scp.problem import Evaluation, OutputConstraints

if TYPE_CHECKING:
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.policies import Funnel
    from convexguid.scp.state import IterationState

RANK_TOLERANCE = 1e-6
"""Rows of the working set whose pivots fall below this share of the largest are taken as dependent."""

REGULARIZATION = 0.1
"""A reduced Hessian with negative curvature is shifted by its most negative eigenvalue and this share of it again."""


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


def null_space_split(rows: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(Y, Z, R, pivots, norms)``: bases of the range and null space of the rows, ``R`` and ``pivots`` of the
    independent ones, and every row's norm, from the pivoted QR factorization :math:`(D^{-1} A)^T P = Q R` of the rows
    each divided by its norm (:math:`D`): independence judged by direction, not units (docs/engine.md, 'Newton end
    game'). Rows whose pivot is below :data:`RANK_TOLERANCE` of the largest depend on the others (a quaternion's unit
    norm, kept by the dynamics, fixed at both ends) and are left out."""
    n = rows.shape[1]
    norms = np.linalg.norm(rows, axis=1)
    norms = np.where(norms > 0, norms, 1.0)
    if rows.shape[0] == 0:
        return np.zeros((n, 0)), np.eye(n), np.zeros((0, 0)), np.zeros(0, dtype=int), norms
    Q, R, pivots = la.qr((rows / norms[:, None]).T, pivoting=True, mode="full")
    diag = np.abs(np.diag(R))
    rank = int(np.sum(diag > RANK_TOLERANCE * max(diag[0], 1e-300))) if diag.size else 0
    return Q[:, :rank], Q[:, rank:], R[:rank, :rank], pivots[:rank], norms


def least_norm_step(split: tuple[np.ndarray, ...], values: np.ndarray) -> np.ndarray:
    """:math:`-Y (R^T)^{-1} (D^{-1} c)_P`: the least-norm step onto the linearized rows of a split."""
    Y, _, R, pivots, norms = split
    if not pivots.size:
        return np.zeros(Y.shape[0])
    return Y @ la.solve_triangular(R, -(values / norms)[pivots], trans="T")


def newton_step(gradient: np.ndarray, hessian: np.ndarray, rows: np.ndarray, values: np.ndarray) -> NewtonStep:
    """The EQP step for gradient ``g``, Hessian ``H``, working-set rows ``A`` and values ``c`` (all scaled): range
    part :math:`d_Y` from :func:`least_norm_step`, null-space part from :math:`Z^T H Z\\, p = -Z^T (g + H d_Y)`,
    multipliers from :math:`R\\, (D y)_P = -Y^T (g + H d)` (zero on dependent rows; :func:`null_space_split`)."""
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
    """Builds the :class:`LocalModel` s of one SCP run: its program's Lagrangian Hessian, scales and constant data."""

    def __init__(self, algo: SCPAlgorithm) -> None:
        self.hessian = algo.program.lagrangian_hessian
        # CSR once: every model reads rows of A and G (a program's COO pattern would be converted each time)
        A, G = (sp.csr_matrix(m) if sp.issparse(m) else m for m in (algo.linear.A, algo.linear.G))
        self.linear = replace(algo.linear, A=A, G=G)
        self.scale, self.weights, self.cost, self.outputs = algo.scale, algo.weights, algo.cost, algo.outputs
        self.tolerance = algo.settings.feasibility_tolerance

    def gauss_newton(self, raw: Evaluation) -> np.ndarray:
        """:math:`2 S J_r^T W J_r S` (scaled, dense)."""
        n = self.scale.size
        jac = raw.residual_jacobian
        if jac is None or raw.residuals.size == 0:
            return np.zeros((n, n))
        J = (jac.toarray() if sp.issparse(jac) else np.asarray(jac, dtype=float)) * self.scale
        return 2.0 * J.T @ (self.weights[:, None] * J)

    def working_set(self, state: IterationState) -> WorkingSet:
        """The working set at the iterate of the subproblem that gave the state's multipliers (and penalty weight)."""
        return WorkingSet.at(state.raw, state.multipliers, self.linear, self.outputs, state.x, self.tolerance,
                             state.penalty)

    def at(self, state: IterationState, working: WorkingSet) -> LocalModel:
        """The model at the iterate, with the state's multipliers, on ``working``."""
        x, raw, multipliers = state.x, state.raw, state.multipliers
        curvature = self.hessian(x, multipliers.curvature_weights(raw.residuals, self.weights, self.outputs))
        # S H S, dense: a sparse Hessian entry by entry, a dense one as it is (no round trip through a sparse matrix)
        outer = np.outer(self.scale, self.scale)
        scaled = (sp.csr_matrix(curvature).multiply(outer).toarray() if sp.issparse(curvature)
                  else np.asarray(curvature, dtype=float) * outer)
        hessian = self.gauss_newton(raw) + scaled
        gradient = objective_gradient(raw, self.weights, self.cost)
        rows = working.rows(raw, self.linear, self.outputs) * self.scale
        return LocalModel(hessian, gradient * self.scale, working, rows,
                          working.values(raw, self.linear, self.outputs, x))

    def with_bounds(self, model: LocalModel, state: IterationState, added: np.ndarray) -> LocalModel:
        """``model`` with the hard inequality rows ``added`` (a mask of ``G``'s rows) put into its working set."""
        working = replace(model.working, linear_inequality=model.working.linear_inequality | added)
        rows = working.rows(state.raw, self.linear, self.outputs) * self.scale
        return replace(model, working=working, rows=rows,
                       values=working.values(state.raw, self.linear, self.outputs, state.x))

    def onto_equalities(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The scaled step ``u`` moved (least change) so that ``x + S u`` meets ``A x = b`` exactly (the working set
        may have dropped a hard boundary condition as dependent)."""
        return u + self.linear.onto_equalities(x + u * self.scale, self.scale)

    def broken_bounds(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Mask of the hard inequality rows ``G x <= h`` that the scaled step ``u`` from ``x`` breaks."""
        return self.linear.gap(x + u * self.scale) > 1e-9 * (1 + np.abs(self.linear.h))


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


BOUND_ROUNDS = 2
"""Times the working set may grow by the hard bounds a Newton step breaks before the step is cut short."""


@dataclass(frozen=True)
class Candidate:
    """Newton's trial point: where, its merit (with ``penalty``), how it was judged, the working set's multipliers."""

    x: np.ndarray
    merit: float
    penalty: float
    ratio: float
    step: float
    predicted: float
    whole: bool
    """Newton's step as solved (not shortened by a trust region or a bound): a small one means convergence."""
    length: float
    """The length of Newton's step as solved (scaled, the largest entry), before any trust region cut it."""
    accepted: bool
    funnel: Funnel | None
    """The funnel after the step (:meth:`~convexguid.scp.engine.SCPAlgorithm.judged`)."""
    multipliers: Multipliers


def newton_candidate(algo: SCPAlgorithm, state: IterationState) -> Candidate | None:
    """Newton's trial point at ``state`` (whose multipliers are its subproblem's), or None."""
    models = algo.second_order
    # not with a cone holding with equality: the EQP step knows no cones (the curved and first-order steps finish)
    if (models is None or algo.phase1 or state.multipliers is None
            or max_violation(state.ev) > algo.settings.second_order_violation or state.multipliers.cone_active()):
        return None
    working = models.working_set(state)
    settled, state.working_set = working == state.working_set, working
    if not settled:  # the subproblems' working set still changes: not yet Newton's turn
        return None
    model, newton = _within_bounds(algo, state, models.at(state, working))
    if newton.step is None:  # a bound outside the working set stops the step: it is not settled
        return None
    length = float(np.max(np.abs(newton.step), initial=0.0))
    radius = min(max(state.radius, state.newton_earned), state.newton_radius)
    whole = length <= radius and not newton.shift
    if length > radius:
        newton = replace(newton, step=newton.step * (radius / length))
    # a regularized step is judged with the iterate's own weight: the multipliers of a working set whose reduced
    # Hessian is indefinite are no measure of the weight it needs, nor are a curved subproblem's (they understate it)
    rho = (state.penalty if newton.shift or state.augmented else
           algo.penalty.judging(state.penalty, state.multipliers.largest(), algo.objective_size))
    merit = algo.merit(state.ev, state.x, rho)
    linearized = linearized_violation(state.raw, algo.outputs, newton.step * algo.scale)
    predicted = merit - (state.objective + model.quadratic(newton.step) + rho * linearized)
    trial = algo.trial(state, state.x + newton.step * algo.scale, rho, merit, predicted)
    if trial.ratio < algo.correction.threshold:
        values = model.working.values(trial.raw, models.linear, algo.outputs, trial.x)
        corrected = models.onto_equalities(state.x, newton.step + model.correction(values))
        if (np.max(np.abs(corrected), initial=0.0) <= 2.0 * state.radius
                and not np.any(models.broken_bounds(state.x, corrected))):
            soc = algo.trial(state, state.x + corrected * algo.scale, rho, merit, predicted)
            trial = soc if soc.ratio > trial.ratio else trial
    step = float(np.max(np.abs(trial.x - state.x) / algo.scale, initial=0.0))
    if newton.shift:  # the merit alone judges a regularized step
        accepted, ratio, funnel = trial.ratio >= algo.settings.accept_ratio, trial.ratio, state.funnel
    else:
        accepted, ratio, funnel = algo.judged(state, trial, -model.quadratic(newton.step), linearized)
    multipliers = model.working.multipliers(newton.multipliers, models.linear.A.shape[0])
    return Candidate(trial.x, trial.merit, rho, ratio, step, predicted, whole, length, accepted, funnel, multipliers)


def _within_bounds(algo: SCPAlgorithm, state: IterationState, model: LocalModel) -> tuple[LocalModel, NewtonStep]:
    """Newton's step on the hard equalities and within the hard inequalities (see the module docstring)."""
    models = algo.second_order
    for rounds in range(BOUND_ROUNDS + 1):
        newton = model.newton()
        newton = replace(newton, step=models.onto_equalities(state.x, newton.step))
        broken = models.broken_bounds(state.x, newton.step)
        if not np.any(broken) or newton.shift or rounds == BOUND_ROUNDS:
            break
        model = models.with_bounds(model, state, broken)
    # a bound still broken stops the step (a regularized step says nothing of which belong in the working set)
    return model, (replace(newton, step=None) if np.any(broken) else newton)
