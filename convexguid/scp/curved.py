"""The curved subproblem: the trust-region QP with the Lagrangian's Hessian, made convex (the end game's SQP step). Near
a feasible point a program's sparse curvature model misses the curvature that lives only in the coupling of the
constraints (a bilinear term such as catalyst mixing's :math:`u x` or a quaternion's :math:`\\Omega(\\omega) q`), and
the steps stay pinned to the trust region. So at a feasible stall short of the KKT tolerance, and on a program of at
most :data:`CURVED_SIZE` variables within :data:`CURVED_VIOLATION` tolerances of feasibility once :data:`CRAWL` linear
steps in a row reached the trust region, the engine solves the QP of sequential quadratic programming instead,
:math:`\\min_u \\nabla f^T S u + \\tfrac12 u^T \\bar H u + \\rho \\sum(\\text{slacks})` subject to the linearized
constraints and :math:`|u_i| \\le \\Delta`. Here :math:`\\bar H` is the scaled Hessian of the Lagrangian (Gauss-Newton
part included, last multipliers) made positive semidefinite: :math:`H + \\gamma A_W^T A_W` over the working rows,
positive definite wherever the reduced Hessian is for :math:`\\gamma` large enough (Finsler's lemma; Nocedal & Wright,
*Numerical Optimization*, 2nd ed., Sec. 17.3), then any eigenvalue still below a small floor raised to it (Nocedal &
Wright Sec. 3.4). The QP is the condensed one (:mod:`convexguid.scp.condensed`), cones kept exact, on the backend of
:meth:`CurvedSubproblem.backend_name`: on Clarabel its Hessian is the sparse augmented one plus a low-rank term over a
few added variables (:func:`with_low_rank`), not the dense clipped matrix (docs/engine.md, 'Curved subproblem').
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from convexguid.backends.base import Backend, BackendResult, ConicProgram
from convexguid.scp.condensed import CondensedAssembler, CurvedTerms
from convexguid.scp.lagrangian import Multipliers, WorkingSet
from convexguid.scp.merit import max_violation
from convexguid.scp.problem import Evaluation

if TYPE_CHECKING:
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.state import IterationState

AUGMENTATION = 1e3
""":math:`\\gamma` in units of the Hessian's largest entry over the working rows' median squared norm, near
feasibility (the fewest iterations in all of the values measured, 10 to 1e4: docs/engine.md, 'Curved subproblem')."""

POLISH_AUGMENTATION = 10.0
""":math:`\\gamma` at a feasible stall (the polish), where a larger one kept a KKT point with degenerate multipliers
from being proved one (measured: docs/engine.md, 'Curved subproblem')."""

CURVED_VIOLATION = 10.0
"""Within this many feasibility tolerances of feasibility, a small program's pinned iterations take the curved step
(from 1e-4, Betts' shuttle ended at a lower local optimum: docs/engine.md, 'Curved subproblem')."""

CRAWL = 2
"""Linear steps in a row that reached the trust region before the curved step takes over near feasibility (at 1 the
flat slew took longer; 2 or 3 cost three classics nothing: docs/engine.md, 'Curved subproblem')."""

CURVED_SIZE = 600
"""Largest program (variables) that takes the curved step near feasibility (dense Hessian, eigendecomposition
and QP); a larger one takes it only at a feasible stall (measured: docs/engine.md, 'Curved subproblem')."""


def convexified(hessian: np.ndarray, rows: np.ndarray, weight: float = AUGMENTATION
                ) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """``hessian`` (symmetric, scaled) plus :math:`\\gamma A^T A` over ``rows``, its negative eigenvalues raised to zero
    (the trust region bounds the step where no curvature does); :math:`\\gamma`; and the same matrix as the augmented
    Hessian :math:`H_\\gamma` (as sparse as ``hessian`` and the rows) plus :math:`F F^T`, ``F`` one column
    :math:`\\sqrt{-\\lambda}\\, v` per negative eigenpair: the form :func:`with_low_rank` hands a sparse backend."""
    H = 0.5 * (hessian + hessian.T)
    size = max(float(np.max(np.abs(H), initial=0.0)), 1e-12)
    gamma = 0.0
    if rows.shape[0]:
        norms = np.linalg.norm(rows, axis=1)
        typical = float(np.median(norms[norms > 0])) if np.any(norms > 0) else 1.0
        gamma = weight * size / typical**2
        H = H + gamma * (rows.T @ rows)
    augmented = 0.5 * (H + H.T)
    values, vectors = np.linalg.eigh(H)
    negative = values < 0.0
    if negative.any():
        H = (vectors * np.maximum(values, 0.0)) @ vectors.T
    return 0.5 * (H + H.T), gamma, augmented, vectors[:, negative] * np.sqrt(-values[negative])


def with_low_rank(program: ConicProgram, n: int, factor: np.ndarray) -> ConicProgram:
    """``program`` (its first ``n`` variables the step ``u``) with :math:`\\tfrac12 \\|F^T u\\|^2` added to its
    objective as :math:`\\tfrac12 \\|w\\|^2` over new last variables :math:`w = F^T u` (equality rows put first)."""
    rank, size = factor.shape[1], program.num_variables
    if rank == 0:
        return program
    first = sp.hstack([sp.csr_matrix(factor.T), sp.csr_matrix((rank, size - n)), -sp.identity(rank)])
    A = sp.vstack([first, sp.hstack([program.A, sp.csr_matrix((program.A.shape[0], rank))])], format="csc")
    return ConicProgram(sp.block_diag([program.P, sp.identity(rank)], format="csc"),
                        np.concatenate([program.q, np.zeros(rank)]), A, np.concatenate([np.zeros(rank), program.b]),
                        replace(program.cones, zero=program.cones.zero + rank), program.constant)


@dataclass(frozen=True)
class CurvedModel:
    """:math:`\\bar H` (scaled), :math:`\\gamma`, the working rows :math:`A_W S` it is augmented with, and
    :math:`\\bar H` as :math:`H_\\gamma + F F^T` (:func:`convexified`)."""

    hessian: np.ndarray
    gamma: float
    augmented: np.ndarray
    factor: np.ndarray
    rows: np.ndarray
    working: WorkingSet

    def terms(self, values: np.ndarray, sparse: bool) -> CurvedTerms:
        """The subproblem's terms when the working rows take ``values`` at the iterate: the augmentation is
        :math:`\\tfrac\\gamma2 \\|A_W S u + c\\|^2` (zero where the step meets their linearization). ``sparse``: the
        Hessian as :math:`H_\\gamma` (sparse), the subproblem to be given :math:`F` by :func:`with_low_rank`."""
        hessian = sp.csc_matrix(self.augmented) if sparse else self.hessian
        return CurvedTerms(hessian, self.gamma * (self.rows.T @ values), 0.5 * self.gamma * float(values @ values))


def strongly_active(working: WorkingSet, multipliers: Multipliers) -> WorkingSet:
    """``working`` without the inequalities whose multiplier is not significant (below 1e-6 of the largest): one that
    merely touches its bound must stay free to leave it (measured: docs/engine.md, 'Curved subproblem')."""
    significant = multipliers.significant()
    return replace(working, linear_inequality=working.linear_inequality & (multipliers.linear_inequality > significant),
                   output=working.output & (multipliers.output > significant),
                   inequality=working.inequality & (multipliers.inequality > significant))


class CurvedSubproblem:
    """The curved QP of one SCP run (assembly and backend set up at the first use, then only updated)."""

    def __init__(self, algo: SCPAlgorithm) -> None:
        self.algo = algo
        self.assembler: CondensedAssembler | None = None
        self.backend: Backend | None = None

    def backend_name(self) -> tuple[str, str | None]:
        """DAQP where the run's subproblems use it (Clarabel re-solving answers not graded optimal), else Clarabel."""
        choice = self.algo.choice
        return ("daqp", "clarabel") if choice is not None and choice.backend == "daqp" else ("clarabel", None)

    def model(self, state: IterationState) -> CurvedModel | None:
        """:math:`\\bar H` at the iterate and the rows it is augmented with, if this iteration takes the curved step
        (see the module docstring; not before any multipliers)."""
        algo = self.algo
        near = max_violation(state.ev) <= CURVED_VIOLATION * algo.settings.feasibility_tolerance
        crawling = near and state.pinned >= CRAWL and not algo.phase1 and algo.program.num_variables <= CURVED_SIZE
        refused = state.curved_refused_at is not None and np.array_equal(state.curved_refused_at, state.x)
        if state.multipliers is None or not (state.polish or crawling) or refused:
            # refused: the step this QP gives here was refused, and the radius did not cut it (at the flat slew's
            # 16-node optimum, twelve polish iterations repeated one refused step of 8.7e-8: 21 iterations, not 7)
            return None
        working = strongly_active(algo.second_order.working_set(state), state.multipliers)
        model = algo.second_order.at(state, working)
        weight = POLISH_AUGMENTATION if state.polish else AUGMENTATION
        return CurvedModel(*convexified(model.hessian, model.rows, weight), model.rows, working)

    def solve(self, state: IterationState, ev: Evaluation, model: CurvedModel) -> tuple[BackendResult, float]:
        """The backend's answer and the model's merit after its step (as the engine's own subproblem gives them);
        ``ev`` the evaluation the constraints are linearized from (shifted, for a second-order correction)."""
        algo = self.algo
        linear = algo.second_order.linear
        if self.assembler is None:
            # the run's own condensed subproblem has these rows and pattern: shared (``curved`` replaces its Hessian)
            self.assembler = algo.assembler if isinstance(algo.assembler, CondensedAssembler) else \
                CondensedAssembler(algo.program.num_variables, state.raw, linear, algo.outputs, algo.scale,
                                   algo.cost, algo.weights)
        values = model.working.values(ev, linear, algo.outputs, state.x)
        name, fallback = self.backend_name()
        if name == "clarabel":
            # H_gamma and the low-rank F, whose pattern changes with the working set (a backend per solve)
            program_k = self.assembler.build(state.x, ev, algo.box(state), state.penalty,
                                             curved=model.terms(values, sparse=True))
            rank = model.factor.shape[1]
            _, result, value = algo.solved(state, with_low_rank(program_k, algo.program.num_variables, model.factor),
                                           None, name, fallback)
            if result.usable:
                return replace(result, x=result.x[: result.x.size - rank],
                               z=None if result.z is None else result.z[rank:]), value
            # that objective is convex only where w = F^T u holds: with large negative eigenvalues in H_gamma Clarabel
            # fails on it (Luus' singular problem); the same QP with the clipped matrix as it is (docs/engine.md)
        program_k = self.assembler.build(state.x, ev, algo.box(state), state.penalty,
                                         curved=model.terms(values, sparse=False))
        if name == "clarabel":
            return algo.solved(state, program_k, None, name, fallback)[1:]
        # on the run's own assembly and backend kind, the backend is the run's one's sibling (its layout shared)
        like = algo.backend if self.assembler is algo.assembler and name == algo.choice.backend else None
        self.backend, result, value = algo.solved(state, program_k, self.backend, name, fallback, like=like)
        return result, value
