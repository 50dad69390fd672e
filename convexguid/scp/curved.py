"""The curved subproblem: the trust-region QP with the Lagrangian's Hessian, made convex (the end game's SQP step).

Far from a solution the engine's subproblem carries the program's own sparse curvature model (or none), which
keeps it robust and cheap. Near a feasible point that model is not enough wherever the curvature that matters lives
only in the coupling of the constraints: a bilinear term (catalyst mixing's :math:`u x`, a quaternion's
:math:`\\Omega(\\omega) q`) is indefinite in every interval, yet positive along the dynamics, and a model made
convex interval by interval keeps none of it; the iteration then converges like a first-order method, its steps
pinned to the trust region (measured on COPS' catalyst mixing: 112 iterations to ``unverified``, 3.9e-5 short).
So once the iterate is within :data:`CURVED_VIOLATION` feasibility tolerances of feasibility on a program of at most
:data:`CURVED_SIZE` variables and the last :data:`CRAWL` linear steps reached their trust region (the model had no
curvature to stop them), and at any feasible stall short of the KKT tolerance, the engine solves the QP of
sequential quadratic programming instead, whose solver picks the active set itself:

.. math::

    \\min_u\\; \\nabla f^T S u + \\tfrac12 u^T \\bar H u + \\rho \\sum(\\text{slacks})
    \\quad\\text{s.t. the linearized constraints and } |u_i| \\le \\Delta ,

with :math:`\\bar H` the scaled Hessian of the Lagrangian (Gauss-Newton part included, weighted by the last
subproblem's multipliers) made positive semidefinite: first :math:`H + \\gamma A_W^T A_W` over the working set's
rows :math:`A_W`, which leaves the model unchanged on the directions those constraints leave free and, for
:math:`\\gamma` large enough, makes the Hessian positive definite wherever the reduced Hessian is (Finsler's lemma;
Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sec. 17.3), then any eigenvalue still below a small floor
raised to it (a reduced Hessian that is indefinite: Nocedal & Wright Sec. 3.4). The QP is the condensed one
(:mod:`convexguid.scp.condensed`, the residuals substituted, a dense Hessian in the step) and goes to the run's own
dense solver, or to Clarabel (:meth:`CurvedSubproblem.backend_name`). Second-order cones stay in it exact, as in
every subproblem (one penalized slack a cone): measured on the nonconvex powered descent (examples/powered_descent.py,
its thrust and glide-slope cones), ``unverified`` after 156 iterations without the curved step there, converged and
verified in 40 with it, at IPOPT's final mass. Without any curved step the classics benchmark left catalyst mixing
and Goddard's rocket ``unverified`` and OpenSCvx's 6-DoF descent at ``max_iterations``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from convexguid.backends.base import Backend, BackendResult
from convexguid.scp.condensed import CondensedAssembler, CurvedTerms
from convexguid.scp.lagrangian import Multipliers, WorkingSet
from convexguid.scp.merit import max_violation
from convexguid.scp.problem import Evaluation

if TYPE_CHECKING:
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.state import IterationState

AUGMENTATION = 1e3
""":math:`\\gamma` in units of the Hessian's largest entry over the working rows' median squared norm, near
feasibility. Measured on the classics with the curved step at every iteration within :data:`CURVED_VIOLATION`
(before it waited for a pinned step; catalyst mixing, Goddard's rocket, the hang glider: SCP iterations): at 10,
102 (``unverified``), 29, 52; at 100, 61, 26, 51; at 1e3, 29, 23, 51; at 1e4, 26, 26, 56 (the augmentation then
crowds out the reduced Hessian's own eigenvalues)."""

POLISH_AUGMENTATION = 10.0
""":math:`\\gamma` at a feasible stall (the polish). Measured: the flat slew with its torque box and sun cone both
active (tests/test_verified_loop.py), whose multipliers are not unique, is proved a KKT point at 10; at 1e3 its
polish collapsed the trust region 2.1e-5 short of stationarity."""

CURVED_VIOLATION = 10.0
"""Within this many feasibility tolerances of feasibility, a small program's pinned iterations take the curved step.
Measured with every iteration there taking it (catalyst mixing, Goddard's rocket, the hang glider: SCP iterations;
Betts' shuttle: its crossrange) from a violation of 1e-4, 1e-5, 1e-6 and 1e-7 (the tolerance): 13, 11, 32, and the
shuttle at 34.0803 deg, 1.8e-3 short of Betts' figure (a lower local optimum, where IPOPT's 34.0613 is too); 18,
12, 51; 29, 23, 51, and the shuttle at 34.14087 deg; 37, 18, 50, the shuttle the same. Waiting for a pinned step
as well (OpenSCvx's proximity operation, examples/proxops_openscvx.py, stalled ``unverified`` after curved steps
it did not need): 29, 33, 56."""

CRAWL = 2
"""Linear steps in a row that reached the trust region before the curved step takes over near feasibility. Measured:
at 1, the flat slew (problems/cai2018_flat_attitude.yaml) took 8 iterations and 0.35 s warm, against 6 and 0.08 s;
at 2 and 3 catalyst mixing, Goddard's rocket and the hang glider took the same 29, 33 and 56 iterations as at 1."""

CURVED_SIZE = 600
"""Largest program (variables) that takes the curved step near feasibility (once pinned): its Hessian, the
eigendecomposition and the QP are dense. Measured from a violation of 1e-4: Betts' slew (1311 variables) took
990 s so, against 5 s with the sparse model (the same plan); larger programs take it only at a feasible stall."""

def convexified(hessian: np.ndarray, rows: np.ndarray, weight: float = AUGMENTATION) -> tuple[np.ndarray, float]:
    """``hessian`` (symmetric, scaled) plus :math:`\\gamma A^T A` over ``rows``, its negative eigenvalues raised to
    zero (the trust region bounds the step where no curvature does); and :math:`\\gamma`."""
    H = 0.5 * (hessian + hessian.T)
    size = max(float(np.max(np.abs(H), initial=0.0)), 1e-12)
    gamma = 0.0
    if rows.shape[0]:
        norms = np.linalg.norm(rows, axis=1)
        typical = float(np.median(norms[norms > 0])) if np.any(norms > 0) else 1.0
        gamma = weight * size / typical**2
        H = H + gamma * (rows.T @ rows)
    values, vectors = np.linalg.eigh(H)
    if values[0] < 0.0:
        H = (vectors * np.maximum(values, 0.0)) @ vectors.T
    return 0.5 * (H + H.T), gamma


@dataclass(frozen=True)
class CurvedModel:
    """:math:`\\bar H` (scaled), :math:`\\gamma`, and the working rows :math:`A_W S` it is augmented with."""

    hessian: np.ndarray
    gamma: float
    rows: np.ndarray
    working: WorkingSet

    def terms(self, values: np.ndarray) -> CurvedTerms:
        """The subproblem's terms when the working rows take ``values`` at the iterate: the augmentation is
        :math:`\\tfrac\\gamma2 \\|A_W S u + c\\|^2`, zero wherever the step meets their linearization, so neither
        the model's value nor the subproblem's multipliers carry it there."""
        return CurvedTerms(self.hessian, self.gamma * (self.rows.T @ values), 0.5 * self.gamma * float(values @ values))


def strongly_active(working: WorkingSet, multipliers: Multipliers) -> WorkingSet:
    """``working`` without the inequalities whose multiplier is not significant (below 1e-6 of the largest).

    The augmentation :math:`\\gamma A_W^T A_W` holds each row it covers to its linearization; an inequality that
    merely touches its bound (a keep-out cone met between check points) must stay free to leave it, or the step and
    the multipliers bend around a constraint that does not bind (measured on the flat slew with the sun cone active:
    stationarity 0.54 with it in).
    """
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
        """DAQP (Clarabel re-solving an answer it does not grade optimal) where the run's own subproblems went to it,
        else Clarabel. Measured: the flat slew's one curved step took 75 ms on Clarabel, mostly set-up, against
        2 ms on DAQP; the two-instrument slew's curved steps on DAQP never certified its KKT point (20 steps,
        stationarity 4.5e-6), on Clarabel one step did."""
        choice = self.algo.choice
        return ("daqp", "clarabel") if choice is not None and choice.backend == "daqp" else ("clarabel", None)

    def wanted(self, state: IterationState) -> bool:
        """Whether this iteration takes the curved step: at a feasible stall short of the KKT tolerance (the polish),
        or on a small program near feasibility whose linear steps keep reaching the trust region (see the module
        docstring)."""
        algo = self.algo
        near = max_violation(state.ev) <= CURVED_VIOLATION * algo.settings.feasibility_tolerance
        return bool(state.polish) or (near and state.pinned >= CRAWL and not algo.phase1
                                      and algo.program.num_variables <= CURVED_SIZE)

    def hessian(self, state: IterationState) -> CurvedModel | None:
        """:math:`\\bar H` at the iterate and the rows it is augmented with (None before any multipliers)."""
        algo = self.algo
        if state.multipliers is None:
            return None
        working = strongly_active(algo.second_order.working_set(state.x, state.raw, state.multipliers,
                                                                algo.settings.feasibility_tolerance, state.penalty),
                                  state.multipliers)
        model = algo.second_order.at(state.x, state.raw, state.multipliers, working)
        weight = POLISH_AUGMENTATION if state.polish else AUGMENTATION
        return CurvedModel(*convexified(model.hessian, model.rows, weight), model.rows, working)

    def solve(self, state: IterationState, ev: Evaluation, model: CurvedModel) -> tuple[BackendResult, float]:
        """The backend's answer and the model's merit after its step (as the engine's own subproblem gives them);
        ``ev`` the evaluation the constraints are linearized from (shifted, for a second-order correction)."""
        algo = self.algo
        linear = algo.second_order.linear
        if self.assembler is None:
            # the run's own condensed subproblem has these rows and this pattern (its curvature model is not used
            # here: ``curved`` replaces the whole Hessian), so it is shared rather than set up a second time
            self.assembler = algo.assembler if isinstance(algo.assembler, CondensedAssembler) else \
                CondensedAssembler(algo.program.num_variables, state.raw, linear, algo.outputs, algo.scale,
                                   algo.cost, algo.weights)
        values = model.working.values(ev, linear, algo.outputs, state.x)
        program_k = self.assembler.build(state.x, ev, algo.box(state), state.penalty, curved=model.terms(values))
        name, fallback = self.backend_name()
        # on the run's own assembly and backend kind, the backend is the run's one's sibling (its layout shared)
        like = algo.backend if self.assembler is algo.assembler and name == algo.choice.backend else None
        self.backend, result, value = algo.solved(state, program_k, self.backend, name, fallback, like=like)
        return result, value
