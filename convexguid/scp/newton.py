"""Newton's candidate step for one SCP iteration: the end game of :mod:`convexguid.scp.endgame`, made safe.

Within ``second_order_violation`` of feasibility, :func:`newton_candidate` proposes the equality-constrained
quadratic step on the working set of the subproblem just solved: only once two subproblems in a row agree on it; on
the hard equalities and within the hard inequalities (a bound it breaks joins the working set, twice at most, else
no step); inside a trust region of its own (a quarter of a step that failed, doubled by a good cut one, freed by a
good whole one) and the first-order one (which a good cut one opens to the whole step's length); judged by the
merit's ratio test or else the funnel (:meth:`~convexguid.scp.engine.SCPAlgorithm.judged`), with the weight at most
the one that follows the multipliers (:meth:`~convexguid.scp.policies.PenaltyPolicy.judging`; Nocedal & Wright,
*Numerical Optimization*, 2nd ed., Sec. 18.3); with a least-norm second-order correction when its ratio is poor (the
Maratos effect). A regularized step (the reduced Hessian indefinite) is judged by the merit alone with the iterate's
own weight, and never taken when it breaks a hard bound. The engine takes the step only if it does at least as well
as the first-order one: the end game can make an iteration better, never worse (why each rule: docs/engine.md,
'Newton end game').
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from convexguid.scp.endgame import LocalModel, NewtonStep, linearized_violation
from convexguid.scp.merit import max_violation
from convexguid.scp.problem import Evaluation

if TYPE_CHECKING:
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.policies import Funnel
    from convexguid.scp.state import IterationState

BOUND_ROUNDS = 2
"""Times the working set may grow by the hard bounds a Newton step breaks before the step is cut short."""


@dataclass(frozen=True)
class Candidate:
    """A trial point: where, its evaluation, its merit (with ``penalty``), and how it was judged."""

    x: np.ndarray
    ev: Evaluation
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
    model: LocalModel | None = None
    newton: NewtonStep | None = None


def newton_candidate(algo: SCPAlgorithm, state: IterationState) -> Candidate | None:
    """Newton's trial point at ``state`` (whose multipliers are its subproblem's), or None."""
    s, models = algo.settings, algo.second_order
    # not with a cone holding with equality: the EQP step knows no cones (the curved and first-order steps finish)
    if (models is None or algo.phase1 or state.multipliers is None
            or max_violation(state.ev) > s.second_order_violation or state.multipliers.cone_active()):
        return None
    working = models.working_set(state.x, state.raw, state.multipliers, s.feasibility_tolerance, state.penalty)
    settled, state.working_set = working == state.working_set, working
    if not settled:
        # the subproblems' working set still changes from one iteration to the next: not yet Newton's turn
        return None
    model = models.at(state.x, state.raw, state.multipliers, working)
    model, newton = _within_bounds(algo, state, model)
    if newton.step is None:
        # no step: the working set is not settled (a bound outside it stops the step)
        return None
    length = float(np.max(np.abs(newton.step), initial=0.0))
    radius = min(state.radius, state.newton_radius)
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
    ratio = trial.ratio
    if newton.shift:  # the merit alone judges a regularized step
        accepted, funnel = ratio >= algo.settings.accept_ratio, state.funnel
    else:
        accepted, ratio, funnel = algo.judged(state, ratio, trial.x, trial.ev, -model.quadratic(newton.step),
                                              linearized)
    return Candidate(trial.x, trial.ev, trial.merit, rho, ratio, step, predicted, whole, length, accepted, funnel,
                     model, newton)


def _within_bounds(algo: SCPAlgorithm, state: IterationState, model: LocalModel) -> tuple[LocalModel, NewtonStep]:
    """Newton's step on the hard equalities and within the hard inequalities (see the module docstring)."""
    models = algo.second_order
    for rounds in range(BOUND_ROUNDS + 1):
        newton = model.newton()
        newton = replace(newton, step=models.onto_equalities(state.x, newton.step))
        broken = models.broken_bounds(state.x, newton.step)
        if not np.any(broken) or newton.shift or rounds == BOUND_ROUNDS:
            break
        model = models.with_bounds(model, state.raw, state.x, broken)
    # a bound still broken stops the step (a regularized step says nothing of which belong in the working set)
    return model, (replace(newton, step=None) if np.any(broken) else newton)
