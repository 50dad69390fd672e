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
from convexguid.scp.merit import decrease_ratio, max_violation
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
    if models is None or algo.phase1 or state.multipliers is None:
        return None
    if max_violation(state.ev) > s.second_order_violation:
        return None
    if state.multipliers.cone_active():
        # a cone holds with equality: the EQP step knows no cones (the curved and first-order steps finish the run)
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
    x_new, ev_new, raw_new = algo.trial(state, newton.step)
    merit_new = algo.merit(ev_new, x_new, rho)
    ratio = decrease_ratio(merit - merit_new, predicted)
    if ratio < algo.correction.threshold:
        corrected = newton.step + model.correction(model.working.values(raw_new, models.linear, algo.outputs, x_new))
        corrected = models.onto_equalities(state.x, corrected)
        if (np.max(np.abs(corrected), initial=0.0) <= 2.0 * state.radius
                and not np.any(models.broken_bounds(state.x, corrected))):
            x_soc, ev_soc, _ = algo.trial(state, corrected)
            merit_soc = algo.merit(ev_soc, x_soc, rho)
            ratio_soc = decrease_ratio(merit - merit_soc, predicted)
            if ratio_soc > ratio:
                x_new, ev_new, merit_new, ratio = x_soc, ev_soc, merit_soc, ratio_soc
    step = float(np.max(np.abs(x_new - state.x) / algo.scale, initial=0.0))
    if newton.shift:  # the merit alone judges a regularized step
        accepted, funnel = ratio >= algo.settings.accept_ratio, state.funnel
    else:
        accepted, ratio, funnel = algo.judged(state, ratio, x_new, ev_new, -model.quadratic(newton.step), linearized)
    return Candidate(x_new, ev_new, merit_new, rho, ratio, step, predicted, whole, length, accepted, funnel, model,
                     newton)


def _within_bounds(algo: SCPAlgorithm, state: IterationState, model: LocalModel) -> tuple[LocalModel, NewtonStep]:
    """Newton's step on the hard equalities and within the hard inequalities (see the module docstring)."""
    models = algo.second_order

    def on_equalities(newton: NewtonStep) -> NewtonStep:
        return newton if newton.step is None else replace(newton, step=models.onto_equalities(state.x, newton.step))

    newton = on_equalities(model.newton())
    for _ in range(BOUND_ROUNDS):
        if newton.step is None:
            return model, newton
        broken = models.broken_bounds(state.x, newton.step)
        if not np.any(broken):
            return model, newton
        if newton.shift:  # a regularized step says nothing of which bounds belong in the working set
            return model, replace(newton, step=None)
        model = models.with_bounds(model, state.raw, state.x, broken)
        newton = on_equalities(model.newton())
    if newton.step is not None and np.any(models.broken_bounds(state.x, newton.step)):
        newton = replace(newton, step=None)
    return model, newton
