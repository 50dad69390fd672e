"""Newton's candidate step for one SCP iteration: the end game of :mod:`convexguid.scp.endgame`, made safe.

Every iteration solves the convex subproblem first. Once the iterate is within
``second_order_violation`` of feasibility, :func:`newton_candidate` also proposes the
equality-constrained quadratic step on that subproblem's working set:

* only once two subproblems in a row agree on the working set (an active set that still changes
  would make the step, and the Hessian it costs, a waste);
* on the hard equalities and within the hard inequalities (a bound it breaks joins the working set,
  twice at most; when one is still broken, the working set is not settled and no step is proposed);
* inside a trust region of its own (a quarter of a step that failed, doubled by a good cut one,
  freed by a good whole one), and the first-order one;
* judged as every step is: the merit's ratio test, or else the funnel on the violation, whose objective ratio then
  sizes the radius (:meth:`~convexguid.scp.engine.SCPAlgorithm.judged`). On COPS' hang glider Newton's steps gained
  what their model predicted but broke the constraints by their second-order error (1e-9 to 1e-8, feasible), a loss
  to the merit: each refused step quartered Newton's radius, 56 SCP iterations; with the funnel, 34;
* the merit with the penalty weight at most the one that follows the multipliers
  (:meth:`~convexguid.scp.policies.PenaltyPolicy.judging`): any weight above the multipliers makes the
  penalty exact, and a far larger one (an escalation that has served its purpose) only magnifies the
  curvature error of a long step (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sec. 18.3). Not when
  every multiplier is inactive: they then say nothing of the weight needed, and a weight brought down to its
  floor that way left a test program crawling along a cone it broke by 0.68 for 100 iterations
  (tests/test_ocp_cones.py, its multiplier then equal to the weight, so the penalty was not exact);
* with a least-norm second-order correction when its ratio is poor (the Maratos effect);
* a regularized step (the reduced Hessian indefinite, :func:`~convexguid.scp.endgame.newton_step`) by the merit
  alone, with the iterate's own weight, and not at all when it breaks a hard bound: its multipliers measure
  nothing, and a funnel that let it through (Betts' three-phase Goddard rocket, whose singular arc makes the
  reduced Hessian indefinite) alternated it with first-order steps back to feasibility for 300 iterations.

The engine takes it only if it is accepted and it does at least as well as the first-order step
on the same merit: the end game can make an iteration better, never worse.
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
        # a cone holds with equality: the equality-constrained step knows no cones (the curved and first-order
        # steps, which keep each cone exact, finish the run)
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
    return Candidate(x_new, ev_new, merit_new, rho, ratio, step, predicted, whole, accepted, funnel, model, newton)


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
