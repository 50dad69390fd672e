"""What a formulation hands to the SCP engine, which solves

.. math::

    \\min_x\\; \\sum_i w_i\\, r_i(x)^2 + c^T x
    \\quad\\text{s.t.}\\quad A x = b,\\; G x \\le h,\\; g(x) \\le 0,\\; e(x) = 0,\\; F_i x + f_i \\in \\mathcal{Q}_i,

where :math:`r` (least-squares residuals, e.g. torques), :math:`g` and :math:`e` are nonlinear and linearized about
each iterate, :math:`A, b, G, h, c` are constant and the second-order cones :math:`\\mathcal Q_i` on affine maps
(:class:`ConeBlock`: a thrust magnitude, an approach cone) stay exact. Bounds linear in the residuals
(:class:`OutputConstraints`, e.g. :math:`|u_i| \\le u_{max}` at nodes and interpolated points) stay sparse: the engine
lifts :math:`y = r(x)` into the subproblem and bounds :math:`y`. A formulation implements :class:`NonconvexProgram`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Protocol

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class ConstraintBlock:
    """A named group of nonlinear constraints and their Jacobian at the current iterate: ``values <= 0`` for
    inequalities, ``values == 0`` for equalities, in ``unit`` (for diagnostics). ``jacobian`` is a dense array, or a
    ``scipy.sparse.coo_matrix`` with the same ``(row, col)`` entries, in the same order, at every evaluation."""

    name: str
    values: np.ndarray
    jacobian: np.ndarray | None = None
    unit: str = ""
    labels: tuple[str, ...] = ()
    """What each row is (optional): a violation message names the worst row by it."""


@dataclass(frozen=True)
class ConeBlock:
    """Second-order cones kept exact in every subproblem: :math:`\\|v_{1:}\\| \\le v_0` for each cone's part :math:`v`
    of ``values``, an affine map of the variables (its constant ``jacobian`` a ``scipy.sparse.coo_matrix`` of fixed
    pattern). ``sizes`` lists each cone's length, in order; ``unit`` is that of :math:`v_0`. Each cone is softened only
    by one penalized slack on :math:`v_0` (an exact penalty, so every subproblem is feasible)."""

    name: str
    values: np.ndarray
    jacobian: sp.coo_matrix | None
    sizes: tuple[int, ...]
    unit: str = ""

    def violations(self, values: np.ndarray | None = None) -> np.ndarray:
        """How far each cone is broken, :math:`\\max(0, \\|v_{1:}\\| - v_0)` (of ``values``, default its own)."""
        values = self.values if values is None else values
        ends = np.cumsum(self.sizes)
        return np.array([max(float(np.linalg.norm(values[end - size + 1: end])) - float(values[end - size]), 0.0)
                         for end, size in zip(ends, self.sizes, strict=True)])

    def as_inequality(self) -> ConstraintBlock:
        """The cones' violations as an inequality block (no Jacobian): what the merit and the reports count."""
        return ConstraintBlock(self.name, self.violations(), None, self.unit)


def stacked_values(blocks: tuple[ConstraintBlock | ConeBlock, ...]) -> np.ndarray:
    """The blocks' values, one block after another."""
    return np.concatenate([b.values for b in blocks]) if blocks else np.zeros(0)


def per_block(blocks: tuple[ConstraintBlock | ConeBlock, ...], rows: np.ndarray) -> Iterator[tuple]:
    """Each block with its part of ``rows``, an array over the blocks' rows one block after another."""
    start = 0
    for block in blocks:
        yield block, rows[start: start + block.values.size]
        start += block.values.size


@dataclass(frozen=True)
class Evaluation:
    """Nonlinear maps of a :class:`NonconvexProgram` at one point (Jacobians optional)."""

    residuals: np.ndarray
    residual_jacobian: np.ndarray | None = None
    inequalities: tuple[ConstraintBlock, ...] = ()
    equalities: tuple[ConstraintBlock, ...] = ()
    cones: tuple[ConeBlock, ...] = ()


@dataclass(frozen=True)
class LinearConstraints:
    """Constant constraints ``A x = b`` and ``G x <= h`` (kept hard in every subproblem)."""

    A: np.ndarray
    b: np.ndarray
    G: np.ndarray
    h: np.ndarray

    @classmethod
    def none(cls, n: int) -> LinearConstraints:
        return cls(np.zeros((0, n)), np.zeros(0), np.zeros((0, n)), np.zeros(0))

    def sparse(self) -> LinearConstraints:
        """The same constraints with ``A`` and ``G`` as COO matrices of their nonzeros only (the assemblers fix their
        pattern from them: a dense block would put every explicit zero into the solver's KKT system)."""
        A, G = (sp.coo_matrix(matrix, dtype=float) for matrix in (self.A, self.G))
        for matrix in (A, G):
            matrix.sum_duplicates()
            matrix.eliminate_zeros()
        return replace(self, A=A, G=G)

    def in_unit_rows(self, scale: np.ndarray, within: float = 0.0) -> tuple[LinearConstraints, np.ndarray, np.ndarray]:
        """The same constraints (COO, as :meth:`sparse`) with each row divided by its norm in the scaled variables (the
        rows of :math:`A S` and :math:`G S`), except a row whose norm is within a factor ``within`` of 1; and the
        factors the rows of ``A`` and of ``G`` were multiplied by (why: the Delta III launch, docs/engine.md,
        'Restoration and phase 1')."""
        stated = self.sparse()

        def unit(M: sp.coo_matrix) -> np.ndarray:
            norms = np.sqrt(np.bincount(M.row, weights=(M.data * scale[M.col]) ** 2, minlength=M.shape[0]))
            far = (norms > 0) & ((norms > within) | (norms * within < 1))
            return np.where(far, 1.0 / np.where(far, norms, 1.0), 1.0)

        unit_a, unit_g = unit(stated.A), unit(stated.G)
        A, G = (sp.coo_matrix((M.data * u[M.row], (M.row, M.col)), shape=M.shape)
                for M, u in ((stated.A, unit_a), (stated.G, unit_g)))
        return LinearConstraints(A, stated.b * unit_a, G, stated.h * unit_g), unit_a, unit_g

    def onto_equalities(self, x: np.ndarray, scale: np.ndarray) -> np.ndarray:
        """The least change :math:`v` (scaled, least norm) with :math:`A (x + S v) = b`."""
        if not self.A.shape[0]:
            return np.zeros(x.size)
        dense = self.A.toarray() if sp.issparse(self.A) else np.asarray(self.A, dtype=float)
        return np.linalg.lstsq(dense * scale, self.b - dense @ x, rcond=None)[0]

    def gap(self, x: np.ndarray) -> np.ndarray:
        """``G x - h``: positive where ``x`` breaks a hard inequality."""
        return self.G @ x - self.h if self.G.shape[0] else np.zeros(0)


@dataclass(frozen=True)
class OutputBlock:
    """Rows ``rows`` of :class:`OutputConstraints` form the named constraint ``name`` (unit ``unit``)."""

    name: str
    rows: slice
    unit: str = ""


@dataclass(frozen=True)
class OutputConstraints:
    """Constant constraints ``M r(x) <= m`` on the residuals (sparse ``M``), softened by penalized slacks."""

    M: sp.csr_matrix
    m: np.ndarray
    blocks: tuple[OutputBlock, ...]

    @classmethod
    def none(cls, num_residuals: int) -> OutputConstraints:
        return cls(sp.csr_matrix((0, num_residuals)), np.zeros(0), ())

    @cached_property
    def transposed(self) -> sp.csr_matrix:
        """:math:`M^T` as CSR, made once for :math:`M^T \\nu` at every iteration (a view made each time cost more)."""
        return sp.csr_matrix(self.M.T)

    def gap(self, residuals: np.ndarray) -> np.ndarray:
        """``M r - m``: positive where the residuals ``r`` break a bound."""
        return self.M @ residuals - self.m if self.M.shape[0] else np.zeros(0)

    def blocks_at(self, residuals: np.ndarray) -> tuple[ConstraintBlock, ...]:
        """The constraint values ``M r - m`` split into named blocks (no Jacobians: they are linear in r)."""
        values = self.gap(residuals)
        return tuple(ConstraintBlock(b.name, values[b.rows], None, b.unit) for b in self.blocks)


@dataclass(frozen=True)
class CurvatureModel:
    """A positive semidefinite model :math:`\\bar H \\succeq 0` of the Lagrangian's curvature that every subproblem
    carries (the Gauss-Newton part of the residuals excluded: the subproblem has it already). ``rows`` and ``cols``
    list the upper triangle of its pattern (``rows <= cols``), fixed for the run; ``values(x, weights)`` gives its
    entries there for :class:`~convexguid.scp.lagrangian.CurvatureWeights` ``weights`` (the last multipliers)."""

    rows: np.ndarray
    cols: np.ndarray
    values: Callable[[np.ndarray, object], np.ndarray]


@dataclass(frozen=True)
class ProgramSize:
    """Dimensions of the nonlinear program (what a paper's table counts)."""

    num_variables: int
    num_equality_constraints: int
    num_inequality_constraints: int


class NonconvexProgram(Protocol):
    """Interface between a formulation and :func:`convexguid.scp.engine.solve_scp`. Optional:
    ``curvature_model() -> CurvatureModel``, a convex model of the Lagrangian's curvature that every subproblem carries
    once the first has given multipliers. ``lagrangian_hessian(x, weights) -> matrix``, the exact
    :math:`\\sum \\omega_i \\nabla^2 r_i + \\sum \\mu_j \\nabla^2 g_j + \\sum \\lambda_k \\nabla^2 e_k` for
    :class:`~convexguid.scp.lagrangian.CurvatureWeights` ``weights``, without which there is no end game. ``A`` and
    ``G`` of :meth:`linear_constraints` may be dense or ``scipy.sparse``. ``affine``: every nonlinear map is in fact
    affine (the first step takes the widest trust region). ``guarded_bounds() -> (lower, upper)``: bounds beyond which
    the maps lose their meaning (:meth:`~convexguid.scp.policies.TrustRegionPolicy.box`). ``with_jacobians(x, values)``:
    ``evaluate(x)`` made from ``values = evaluate(x, jacobians=False)`` (:mod:`convexguid.scp.evaluations`)."""

    num_variables: int

    def initial_guess(self) -> np.ndarray: ...
    def residual_weights(self) -> np.ndarray: ...
    def linear_cost(self) -> np.ndarray: ...
    def linear_constraints(self) -> LinearConstraints: ...
    def output_constraints(self) -> OutputConstraints: ...
    def evaluate(self, x: np.ndarray, jacobians: bool = True) -> Evaluation: ...

    def variable_scale(self) -> np.ndarray:
        """Typical magnitude of each variable; the trust region is a box in scaled units."""


@dataclass
class SCPSettings:
    """Settings of the SCP loop. ``tolerance`` bounds the scaled step and the relative predicted decrease at
    convergence; ``feasibility_tolerance`` the worst nonlinear-constraint violation (in each block's own unit).
    ``penalty`` and ``penalty_max`` are counted in ``penalty_unit``, ``"absolute"`` or ``"objective"``
    (:class:`~convexguid.scp.policies.PenaltyPolicy`). ``max_backend_failures`` backend failures in a row are retried
    with a smaller trust region. ``iterative_refinement`` refines the interior-point backend's KKT solves (Clarabel's
    default). ``second_order`` enables the end game (:mod:`convexguid.scp.lagrangian`); ``kkt_tolerance`` bounds the
    relative stationarity and complementarity at convergence (:mod:`convexguid.scp.optimality`); ``funnel`` lets a
    funnel take steps the merit refuses (:class:`~convexguid.scp.policies.FunnelPolicy`)."""

    backend: str = "auto"
    max_iterations: int = 50
    tolerance: float = 1e-6
    feasibility_tolerance: float = 1e-7
    trust_region: float = 0.5
    trust_region_min: float = 1e-7
    trust_region_max: float = 1e3
    penalty: float = 1e3
    penalty_max: float = 1e7
    penalty_unit: str = "absolute"
    accept_ratio: float = 1e-4
    shrink_ratio: float = 0.25
    expand_ratio: float = 0.75
    backend_tolerance: float = 1e-8
    max_backend_failures: int = 3
    second_order_correction: bool = True
    iterative_refinement: bool = True
    second_order: bool = True
    second_order_violation: float = 1e-4
    kkt_tolerance: float = 1e-6
    funnel: bool = True

    @classmethod
    def from_spec(cls, solver, **overrides) -> SCPSettings:
        """Settings from a problem file's ``solver`` section (:class:`convexguid.spec.common.SolverSettings`)."""
        values = {"backend": solver.backend, "max_iterations": solver.max_iterations, "tolerance": solver.tolerance,
                  "trust_region": solver.trust_region, "penalty": solver.penalty,
                  "kkt_tolerance": solver.kkt_tolerance, "second_order": solver.second_order}
        return cls(**{**values, **overrides})
