"""The funnel that takes steps the exact-penalty merit refuses (convexguid.scp.policies.FunnelPolicy): its f- and
h-steps, the points it leaves and refuses to return to, and what the engine does when such a point is all that holds
the iterate (docs/engine.md, 'Funnel')."""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import pytest

from convexguid.ocp import Problem
from convexguid.scp.policies import Funnel, FunnelPolicy


def test_the_funnel_takes_an_objective_step_inside_it_and_refuses_one_outside():
    funnel = FunnelPolicy()
    # predicted objective decrease 0.1 against a violation of 1e-4 (0.1^2.3 >= 1e-4^1.1): an f-step, the objective
    # fell as predicted, the violation grew to 1e-2: inside a funnel of width 1, outside one of 1e-3
    assert funnel.judge(1.0, 1e-4, 1e-2, 0.1, 0.1, 1e-4) == ("f", pytest.approx(1.0))
    assert funnel.judge(1e-3, 1e-4, 1e-2, 0.1, 0.1, 1e-4)[0] is None
    assert funnel.judge(1.0, 1e-4, 1e-2, 0.001, 0.1, 1e-4)[0] is None
    # a large violation: an h-step, judged by the violation's decrease
    kind, ratio = funnel.judge(10.0, 1.0, 0.5, -0.1, 1e-3, 0.8)
    assert kind == "h" and ratio == pytest.approx(0.625)
    assert funnel.narrowed(10.0, 1.0, 0.5) == pytest.approx(5.0)


def test_the_funnel_refuses_a_step_back_to_a_point_its_h_step_left():
    """The merit and the funnel must not take turns between two points (the tumor problem's 280-iteration cycle):
    the numbers are that cycle's, violation 1.857e-7 <-> 1.084e-7, objective 7571.4192 <-> 7571.434."""
    policy = FunnelPolicy()
    funnel = policy.initial(1e-3)
    low, high, f_low, f_high = 1.084e-7, 1.857e-7, 7571.434, 7571.4192
    # the merit refuses (ratio -1.1), the funnel takes it as an h-step: the violation fell as predicted
    accepted, ratio, funnel = policy.decide(funnel, False, -1.1, high, low, f_high, f_high - f_low, 5.5e-5, 1.856e-7)
    assert accepted and ratio == pytest.approx(0.4165, abs=1e-4) and funnel.left == ((high, f_high),)
    # the merit would take the step back (its ratio 0.31): it returns to the point left, so it is refused
    accepted, ratio, after = policy.decide(funnel, True, 0.31, low, high, f_low, f_low - f_high, 2.9e-2, 1.083e-7)
    assert not accepted and ratio <= 0 and after == replace(funnel, blocked=1)
    # a step that lowers the objective below that point's is taken, by both rules: the funnel's objective ratio
    # (0.0248 of 0.029 predicted) sizes the region, not the merit's 0.31
    accepted, ratio, _ = policy.decide(funnel, True, 0.31, low, high, f_low, f_low - (f_high - 0.01), 2.9e-2, 1e-7)
    assert accepted and ratio == pytest.approx(0.0248 / 0.029, rel=1e-3)


def test_the_funnel_refuses_a_step_back_to_a_point_a_merit_step_left():
    """The other way round (Betts' underwater vehicle with one state's scale stated at 0.5, 300 iterations of a
    2-cycle): the merit takes a step to less violation at a higher objective, and the funnel took the f-step back to
    where it started, inside its width of 8.86. The point the merit step left is now a filter entry."""
    policy = FunnelPolicy()
    funnel = Funnel(8.86)
    # its model had the objective falling (an f-step to the funnel, which then takes no h-step and keeps its width)
    accepted, ratio, funnel = policy.decide(funnel, True, 0.878, 2.229, 0.02349, 237.743, 237.743 - 818.285, 10.0,
                                            2.229)
    assert accepted and ratio == 0.878 and funnel.left == ((2.229, 237.743),) and funnel.width == 8.86
    # the merit refuses the step back (ratio -8.31); as an f-step it is inside the width and drops the objective as
    # predicted, but it returns to the point left
    accepted, ratio, after = policy.decide(funnel, False, -8.31, 0.02349, 2.229, 818.285, 818.285 - 237.757, 600.0,
                                           0.02349)
    assert not accepted and ratio <= 0 and after == replace(funnel, blocked=1)
    # a merit step that lowers the violation and the objective leaves no entry
    assert policy.decide(Funnel(8.86), True, 0.9, 2.229, 0.02349, 237.743, 1.0, 1.0, 2.229)[2].left == ()


def test_a_step_both_rules_take_sizes_the_trust_region_by_the_better_ratio():
    """The merit charges a step's second-order growth of the violation at its penalty weight, which the next step
    removes; where the funnel takes the same step as an f-step (the objective fell as predicted, the violation stayed
    inside the width), the trust region grows by the funnel's ratio. Dymos' minimum time to climb crawled at a radius
    of 0.03 on merit ratios near 0.5 (docs/engine.md, 'Funnel')."""
    policy = FunnelPolicy()
    # violation 1e-4 -> 2e-4 at a weight of 1e4 (a merit ratio of 0.52); the objective fell 0.95 of the 2.0 predicted
    accepted, ratio, funnel = policy.decide(Funnel(6e-3), True, 0.52, 1e-4, 2e-4, 350.0, 1.9, 2.0, 1e-4)
    assert accepted and ratio == pytest.approx(0.95) and funnel == Funnel(6e-3)
    # outside the width the funnel does not take it: the merit's ratio alone
    accepted, ratio, _ = policy.decide(Funnel(1e-4), True, 0.52, 1e-4, 2e-4, 350.0, 1.9, 2.0, 1e-4)
    assert accepted and ratio == 0.52
    # the merit's ratio where it is the better one
    assert policy.decide(Funnel(6e-3), True, 0.9, 1e-4, 2e-4, 350.0, 1.0, 2.0, 1e-4)[1] == 0.9


def test_the_funnel_counts_the_steps_in_a_row_that_only_a_point_left_refused():
    """The tumor cycle's numbers (above): the step back is refused for the point left, once and twice in a row; a
    step the merit and the funnel both refuse, or one taken, starts the count again."""
    policy = FunnelPolicy()
    low, high, f_low, f_high = 1.084e-7, 1.857e-7, 7571.434, 7571.4192
    funnel = Funnel(1e-2, ((high, f_high),))
    back = (True, 0.31, low, high, f_low, f_low - f_high, 2.9e-2, 1.083e-7)
    _, _, once = policy.decide(funnel, *back)
    _, _, twice = policy.decide(once, *back)
    assert (once.blocked, twice.blocked) == (1, 2)
    # the merit refuses and the funnel too (the violation outgrew the width): not the point's doing
    accepted, _, other = policy.decide(twice, False, -3.0, low, 0.5, f_low, 1.0, 1.0, 1e-7)
    assert not accepted and other.blocked == 0
    accepted, _, taken = policy.decide(twice, True, 0.31, low, high, f_low, f_low - (f_high - 0.01), 2.9e-2, 1e-7)
    assert accepted and taken.blocked == 0


def kelly_cart_pole(intervals: int) -> Problem:
    """The cart-pole swing-up of Kelly, "An introduction to trajectory optimization", SIAM Review 59(4), 2017,
    Appendix E: cart 1 kg, pole 0.3 kg and 0.5 m, from hanging at rest at x = 0 to upright at rest at x = 1 m in 2 s,
    |x| <= 2 m, |u| <= 20 N, least integral of u^2; the final force held at zero as Dymos' statement of it does."""
    cart, pole, length, g = 1.0, 0.3, 0.5, 9.81
    p = Problem("cart-pole")
    x = p.state("x", bounds=(-2.0, 2.0), initial=0.0, final=1.0, unit="m")
    q = p.state("q", initial=0.0, final=math.pi, unit="rad")
    dx = p.state("dx", initial=0.0, final=0.0, unit="m/s")
    dq = p.state("dq", initial=0.0, final=0.0, unit="rad/s")
    u = p.control("u", bounds=(-20.0, 20.0), unit="N")
    sin, cos = ca.sin(q), ca.cos(q)
    p.dynamics({x: dx, q: dq,
                dx: (length * pole * sin * dq**2 + u + pole * g * cos * sin) / (cart + pole * sin**2),
                dq: -(length * pole * cos * sin * dq**2 + u * cos + (cart + pole) * g * sin)
                / (length * (cart + pole * sin**2))})
    p.final_time(fixed=2.0)
    p.point_equality("final_force", u, at=1.0, unit="N")
    p.minimize_integral(u**2, name="J")
    p.transcription(intervals)
    return p


def test_an_iterate_held_by_a_point_the_funnel_left_restores_feasibility_instead_of_raising_the_penalty():
    """On the cart-pole's 50 intervals a Newton step the funnel took at iteration 28 left a nearly feasible plan for a
    violation of 1e-2; every step back towards feasibility then raised the objective above a point the funnel had
    left, and was refused for it. Before, the engine read the stalls as a penalty too low: it raised the weight ten
    times from 2.4e4 to 2.4e9 over 100 iterations before phase 1 restored feasibility, and converged after 233
    iterations (IPOPT: 27). Now the second such refusal in a row restores feasibility at once (62 iterations to the
    first plan)."""
    solution = kelly_cart_pole(50).solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    start = solution.history[0].penalty
    assert max(record.penalty for record in solution.history) < 100 * start
    assert solution.iterations < 120
