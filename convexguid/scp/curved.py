"""The curved subproblem: the trust-region QP with the Lagrangian's Hessian, made convex (the polish's SQP step).

The engine's subproblem carries no curvature of the constraints. Far from a solution that is what keeps it
robust; near one it converges linearly, and when the active set keeps changing (a minimum-time slew whose
switching times move by a fraction of a node each iteration) the equality-constrained Newton step of
:mod:`convexguid.scp.newton` never gets its turn. Once the iterates have stalled at a feasible point short of the
KKT tolerance, the engine therefore solves the QP of sequential quadratic programming instead, whose solver picks
the active set itself:

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
dense solver, or to Clarabel (:meth:`CurvedSubproblem.backend_name`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from convexguid.backends.base import Backend, BackendResult
from convexguid.scp.condensed import CondensedAssembler, CurvedTerms
from convexguid.scp.lagrangian import Multipliers, WorkingSet
from convexguid.scp.problem import Evaluation

if TYPE_CHECKING:
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.state import IterationState

AUGMENTATION = 10.0
""":math:`\\gamma` in units of the Hessian's largest entry over the working rows' median squared norm."""

def convexified(hessian: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, float]:
    """``hessian`` (symmetric, scaled) plus :math:`\\gamma A^T A` over ``rows``, its negative eigenvalues raised to
    zero (the trust region bounds the step where no curvature does); and :math:`\\gamma`."""
    H = 0.5 * (hessian + hessian.T)
    size = max(float(np.max(np.abs(H), initial=0.0)), 1e-12)
    gamma = 0.0
    if rows.shape[0]:
        norms = np.linalg.norm(rows, axis=1)
        typical = float(np.median(norms[norms > 0])) if np.any(norms > 0) else 1.0
        gamma = AUGMENTATION * size / typical**2
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

    @staticmethod
    def applies(algo: SCPAlgorithm, first: Evaluation) -> bool:
        """The program has an end game (a Hessian to use) and no second-order cones (the condensed QP has none)."""
        return algo.second_order is not None and not first.cones

    def hessian(self, state: IterationState) -> CurvedModel | None:
        """:math:`\\bar H` at the iterate and the rows it is augmented with (None before any multipliers)."""
        algo = self.algo
        if state.multipliers is None:
            return None
        working = strongly_active(algo.second_order.working_set(state.x, state.raw, state.multipliers,
                                                                algo.settings.feasibility_tolerance, state.penalty),
                                  state.multipliers)
        model = algo.second_order.at(state.x, state.raw, state.multipliers, working)
        return CurvedModel(*convexified(model.hessian, model.rows), model.rows, working)

    def solve(self, state: IterationState, ev: Evaluation, model: CurvedModel) -> tuple[BackendResult, float]:
        """The backend's answer and the model's merit after its step (as the engine's own subproblem gives them);
        ``ev`` the evaluation the constraints are linearized from (shifted, for a second-order correction)."""
        algo = self.algo
        linear = algo.second_order.linear
        if self.assembler is None:
            self.assembler = CondensedAssembler(algo.program.num_variables, state.raw, linear, algo.outputs,
                                                algo.scale, algo.cost, algo.weights)
        values = model.working.values(ev, linear, algo.outputs, state.x)
        program_k = self.assembler.build(state.x, ev, state.radius, state.penalty, curved=model.terms(values))
        self.backend, result, value = algo.solved(state, program_k, self.backend, *self.backend_name())
        return result, value
