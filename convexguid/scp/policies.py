"""The named rules of the SCP step: trust region, penalty weight, funnel, second-order correction. Each is a small
object built from :class:`~convexguid.scp.problem.SCPSettings` that the engine asks one question at a time, so a rule
can be read, tested and replaced on its own (what each is for, measured: docs/engine.md).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from convexguid.scp.problem import Evaluation, SCPSettings

FRACTION_TO_BOUNDARY = 0.99
"""Share of its distance to a guarded bound a variable may cover in one step (:meth:`TrustRegionPolicy.box`)."""

BOUNDARY_REACH = 1e-6
"""Scaled distance to a guarded bound from which a step may reach the bound itself (an active bound is then met in
a few iterations: the distance shrinks a hundredfold per step until it is this small)."""


@dataclass(frozen=True)
class TrustRegionPolicy:
    """Box trust region in scaled variables with the classical ratio test: the radius shrinks to a quarter of the step
    on poor agreement (ratio below ``shrink``) and doubles when the model is trusted (ratio above ``expand``) and the
    step reached the boundary (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Alg. 4.1)."""

    initial: float
    minimum: float
    maximum: float
    shrink: float
    expand: float

    @classmethod
    def from_settings(cls, s: SCPSettings) -> TrustRegionPolicy:
        return cls(s.trust_region, s.trust_region_min, s.trust_region_max, s.shrink_ratio, s.expand_ratio)

    def box(self, radius: float, x: np.ndarray, scale: np.ndarray,
            guarded: tuple[np.ndarray, np.ndarray] | None) -> float | np.ndarray:
        """The limits of the scaled step, upper then lower: the radius, and for each variable with a guarded bound (one
        beyond which the program's maps lose their meaning) at most :data:`FRACTION_TO_BOUNDARY` of its distance to
        the bound (IPOPT's fraction-to-the-boundary rule: Wachter & Biegler, Math. Program. 106, 2006, eq. 15) until
        it is within :data:`BOUNDARY_REACH` of it (docs/engine.md, 'Trust region and fraction to the boundary')."""
        if guarded is None:
            return radius
        lower, upper = guarded
        room = np.concatenate([(upper - x) / scale, (x - lower) / scale])
        return np.where(room > BOUNDARY_REACH, np.minimum(radius, FRACTION_TO_BOUNDARY * room), radius)

    def update(self, radius: float, ratio: float, step: float) -> float:
        if ratio < self.shrink:
            # a quarter of the step actually taken (a backend may overshoot the box by its tolerance)
            return max(0.25 * min(step, radius), self.minimum) if step > 0 else 0.25 * radius
        if ratio > self.expand and step >= 0.99 * radius:
            return min(2.0 * radius, self.maximum)
        return radius

    def after_failure(self, radius: float) -> float:  # a smaller, better-conditioned subproblem
        return max(0.25 * radius, self.minimum)

    def after_penalty_change(self, radius: float) -> float:  # room to move once the merit function has changed
        return max(radius, self.initial)

    def collapsed(self, radius: float) -> bool:
        return radius <= self.minimum


@dataclass(frozen=True)
class PenaltyPolicy:
    """Weight :math:`\\rho` of the exact :math:`\\ell_1` penalty. With ``unit = "objective"`` the weights are counted in
    units of the objective's size at the start (the engine passes it: :math:`|f(x_0)|`, or :math:`|c|^T \\sigma` if
    larger), with ``unit = "absolute"`` as given. The penalty is exact for any weight above the largest multiplier
    :math:`\\|\\lambda\\|_\\infty` (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Thm. 17.3), so near a feasible
    point the weight follows the last multipliers (:meth:`relaxed`). When the iterates stall infeasible it is multiplied
    by ``factor`` up to its maximum (Nocedal & Wright, Sec. 17.2); it is raised at once when a step shows it too low
    (:meth:`steered`; docs/engine.md, 'Penalty weight')."""

    start: float
    maximum: float
    unit: str
    factor: float = 10.0
    over_multipliers: float = 1.5
    slack: float = 2.0
    floor: float = 1e-3
    inactive: float = 1e-6
    retained: float = 0.5
    persistence: int = 3
    steering: float = 0.1
    steering_floor: float = 1e-3

    @classmethod
    def from_settings(cls, s: SCPSettings) -> PenaltyPolicy:
        return cls(s.penalty, s.penalty_max, s.penalty_unit)

    def scale(self, objective_size: float) -> float:
        """The unit of the weights: 1, or the objective's size at the start (at least 1e-12); 1 when that size is zero
        (a boundary-value problem's zero cost: measured in docs/engine.md, 'Penalty weight')."""
        return 1.0 if self.unit != "objective" or objective_size == 0.0 else max(abs(objective_size), 1e-12)

    def initial(self, objective_size: float) -> float:
        return self.start * self.scale(objective_size)

    def following(self, largest_multiplier: float, objective_size: float) -> float:
        """The weight that follows the multipliers: :attr:`over_multipliers` times the largest, at least the floor."""
        return max(self.over_multipliers * largest_multiplier, self.floor * self.initial(objective_size))

    def relaxed(self, rho: float, largest_multiplier: float, objective_size: float) -> float | None:
        """The weight :meth:`following` the multipliers if ``rho`` is more than :attr:`slack` times it, else None (also
        when no constraint is active: the largest multiplier below :attr:`inactive` times ``rho``); never a weight still
        needed (why, with measurements: docs/engine.md, 'Penalty weight')."""
        if largest_multiplier < self.inactive * rho:
            return None
        target = self.following(largest_multiplier, objective_size)
        return target if rho > self.slack * target else None

    def judging(self, rho: float, largest_multiplier: float, objective_size: float) -> float:
        """The weight that judges Newton's step: ``rho``, at most the one :meth:`following` the multipliers, unless
        every multiplier is below :attr:`inactive` times ``rho`` (then they say nothing of the weight needed)."""
        if largest_multiplier < self.inactive * rho:
            return rho
        return min(rho, self.following(largest_multiplier, objective_size))

    def steered(self, violation: float, linearized: float, violation_new: float | None, inside: bool,
                kept: int) -> tuple[bool, int]:
        """``(raise, kept)``: whether a step shows the weight below the multipliers its constraints need, so that it is
        raised at once (steering the penalty: Byrd, Nocedal & Waltz, "Steering exact penalty methods for nonlinear
        programming", Optim. Methods Softw. 23, 2008), and the count of steps in a row that kept the violation. Two
        signs: the step adds more than :attr:`retained` to the iterate's ``violation`` in its ``linearized`` one (the
        step 0 would not), or :attr:`persistence` accepted steps in a row inside the region (``inside``) kept more
        than :attr:`retained` of it, linearized and at the new point (``violation_new``, None if refused)."""
        keeps = (violation_new is not None and inside and linearized > self.retained * violation
                 and violation_new > self.retained * violation)
        kept = kept + 1 if keeps else 0
        return linearized > (1 + self.retained) * violation or kept >= self.persistence, kept

    def short_of_feasibility(self, violation: float, linearized: float, least: float) -> bool:
        """Whether a step removed less than :attr:`steering` of the linearized ``violation`` that the step of least
        violation in the same trust region removes (to ``least``, and at least :attr:`steering_floor` of it): the
        weight, not the region, held it back (Byrd, Nocedal & Waltz 2008, steering rule's first condition)."""
        return violation - least > self.steering_floor * violation and \
            violation - linearized < self.steering * (violation - least)

    def escalated(self, rho: float, objective_size: float) -> float | None:
        """The next weight, or ``None`` if ``rho`` is already at the maximum."""
        ceiling = self.maximum * self.scale(objective_size)
        return None if rho >= ceiling * (1 - 1e-12) else min(self.factor * rho, ceiling)


@dataclass(frozen=True)
class Funnel:
    """The funnel's state: its width on the violation, the points its h-steps left behind, ``(h, f)`` pairs, and how
    many steps in a row were refused only for returning to one of them (``blocked``: the merit or the funnel's own
    test would have taken each)."""

    width: float
    left: tuple[tuple[float, float], ...] = ()
    blocked: int = 0


@dataclass(frozen=True)
class FunnelPolicy:
    """A second way to accept a step: a funnel on the violation, for the steps the exact-penalty merit refuses only
    for their constraints' curvature (Gould & Toint, "Nonlinear programming without a penalty function or a filter",
    Math. Program. 122, 2010). The violation :math:`h` (the merit's :math:`\\ell_1` sum) must stay below the width
    :math:`\\tau`. A step whose model predicts an objective decrease :math:`\\Delta q^{2.3} \\ge h^{1.1}` (IPOPT's
    switching condition: Wachter & Biegler, Math. Program. 106, 2006, eq. 19) is an *f-step*, judged by the objective;
    any other is an *h-step*, judged by the violation, after which the funnel narrows and keeps the point left as a
    filter entry (Fletcher & Leyffer, Math. Program. 91, 2002) that no later step may fail to beat in violation or
    objective (:meth:`judge`, :meth:`decide`). Why, measured: docs/engine.md, 'Funnel'."""

    start_factor: float = 10.0
    start_floor: float = 1.0
    sufficient: float = 0.1
    narrowing: float = 0.5
    filter_margin: float = 1e-5
    held: int = 2

    def initial(self, violation: float, warm: bool = False) -> Funnel:
        """The funnel at a start of violation ``violation``: :attr:`start_factor` times it, and at least
        :attr:`start_floor` from a cold start. A warm start (a repair's re-solve from the last plan) gets no floor:
        the plan is nearly feasible and the funnel must not let it go (measured: docs/engine.md, 'Funnel')."""
        return Funnel(self.start_factor * violation if warm else max(self.start_factor * violation, self.start_floor))

    def judge(self, width: float, violation: float, violation_new: float, objective_drop: float,
              predicted_objective: float, predicted_violation: float) -> tuple[str | None, float]:
        """``("f" | "h", ratio)`` for an accepted step, ``(None, ratio)`` for a refused one; the ratio (actual over
        predicted decrease of the objective, or of the violation) is what the trust region is updated with."""
        if predicted_objective > 0 and predicted_objective ** 2.3 >= violation ** 1.1:
            ratio = objective_drop / predicted_objective
            return ("f" if violation_new <= width and ratio >= self.sufficient else None), ratio
        ratio = (violation - violation_new) / predicted_violation if predicted_violation > 0 else -1.0
        return ("h" if violation_new <= width and ratio >= self.sufficient else None), ratio

    def holds(self, funnel: Funnel | None) -> bool:
        """Whether the last :attr:`held` steps were each refused only for returning to a point left (the second at a
        quarter of the first's radius; one may be the trust region's doing). Only a step to less violation than that
        point's passes it, which no heavier penalty makes: an infeasible iterate so held is restored to feasibility
        (phase 1), as a filter method's restoration phase does (Fletcher & Leyffer, Math. Program. 91, 2002;
        measured: docs/engine.md, 'Funnel')."""
        return funnel is not None and funnel.blocked >= self.held

    def narrowed(self, width: float, violation: float, violation_new: float) -> float:
        """The width after an accepted h-step."""
        return max(self.narrowing * width, violation_new + 0.5 * (violation - violation_new))

    def decide(self, funnel: Funnel, merit_accepts: bool, merit_ratio: float, violation: float,
               violation_new: float, objective: float, objective_drop: float, predicted_objective: float,
               predicted_violation: float) -> tuple[bool, float, Funnel]:
        """``(accepted, ratio, funnel)``: a step the merit's ratio test accepts, or else one :meth:`judge` accepts
        (with its ratio), unless it returns to a point an h-step left; and the funnel after it (an accepted h-step
        narrows it; an h-step the merit refused, or any step to less violation at a higher objective, remembers the
        point it left). An accepted step's ratio is that of the rule that took it, the larger where both did; a
        refused step's is at most 0 (the radius shrinks), and the funnel then says whether only a point left refused
        it, and how many times in a row (:attr:`Funnel.blocked`)."""
        kind, ratio = self.judge(funnel.width, violation, violation_new, objective_drop, predicted_objective,
                                 predicted_violation)
        # a filter's test: no better in either measure than a point an h-step left (by a margin of its violation)
        objective_new, margin = objective - objective_drop, self.filter_margin
        returns = any(violation_new >= (1 - margin) * h and objective_new >= f - margin * h for h, f in funnel.left)
        taken = merit_accepts or kind is not None
        if not taken or returns:
            return False, min(merit_ratio, 0.0), replace(funnel, blocked=funnel.blocked + 1 if taken else 0)
        funnel = replace(funnel, blocked=0)
        if violation_new < violation:
            # a point left for less violation at a higher objective is not to be come back to, whatever accepted the
            # step: an f-step back to one a merit step had left made a pair of steps cycle (docs/engine.md, 'Funnel')
            leaves = objective_drop < 0 or (kind == "h" and not merit_accepts)
            funnel = Funnel(self.narrowed(funnel.width, violation, violation_new) if kind == "h" else funnel.width,
                            funnel.left + ((violation, objective),) if leaves else funnel.left)
        # both rules took it: the better ratio sizes the region (the merit's counts the violation's second-order
        # growth as a loss the next step removes: the minimum time to climb crawled at a radius of 0.03)
        return True, (max(merit_ratio, ratio) if kind is not None else merit_ratio if merit_accepts else ratio), funnel


@dataclass(frozen=True)
class SecondOrderCorrection:
    """Fletcher's second-order correction, tried when a step's ratio is below ``threshold`` (the Maratos effect): the
    subproblem is solved again with each constraint's constant shifted to what the trial point showed,
    :math:`c(x + d) - \\nabla c(x)\\, d`, so the corrected step cancels the curvature error to first order; it is judged
    against the original prediction and kept if its ratio is better (Nocedal & Wright, Sec. 15.6; Fletcher, *Practical
    Methods of Optimization*, 2nd ed., Sec. 14.4; measured: docs/engine.md, 'Second-order correction')."""

    threshold: float
    enabled: bool = True

    @classmethod
    def from_settings(cls, s: SCPSettings) -> SecondOrderCorrection:
        return cls(s.expand_ratio, s.second_order_correction)

    def wanted(self, ratio: float, ev: Evaluation, trial: Evaluation) -> bool:
        """Whether to correct a step from the point of ``ev`` whose trial point evaluated to ``trial``: not when a
        constraint there is not a number (the trial left the maps' domain, and the shifted subproblem would too)."""
        wanted = self.enabled and ratio < self.threshold and bool(ev.equalities or ev.inequalities)
        return wanted and all(np.all(np.isfinite(block.values)) for block in (*trial.equalities, *trial.inequalities))

    @staticmethod
    def shifted(at_x: Evaluation, at_trial: Evaluation, d: np.ndarray) -> Evaluation:
        """Constraint blocks at ``x`` whose values are :math:`c(x + d) - \\nabla c(x)\\, d` (Jacobians kept)."""
        shifted = {kind: tuple(replace(bx, values=bt.values - bx.jacobian @ d)
                               for bx, bt in zip(getattr(at_x, kind), getattr(at_trial, kind), strict=True))
                   for kind in ("inequalities", "equalities")}
        return replace(at_x, **shifted)
