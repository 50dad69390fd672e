"""Controls that are angles: the period by which a plan's values of a control may be shifted.

A control stated with ``period`` (:meth:`~convexguid.ocp.problem.Problem.control`) has it. An unbounded control
stated without one is an angle all the same when everything the transcription evaluates with it (the dynamics, the
path constraints) is unchanged by a whole turn of it, as Zermelo's heading enters his ship's speed only through
:math:`\\cos\\theta` and :math:`\\sin\\theta` (Bryson & Ho, *Applied Optimal Control*, 1975, Sec. 2.7). The
collocation then sees its values only through those functions, and a plan may hold a node's value and its
neighbour's a whole turn apart: flown or tabulated as they are, the control sweeps through every angle in between.
Measured on Zermelo's problem stated with ``p.control("theta")`` (50 intervals): the first plan wrapped from 3.02
to -3.16 rad between two nodes, failed its dense check, and took five repair rounds and 50 SCP iterations in all
(IPOPT 22 on the first grid); with the turn recognized it is verified at once.

The test is numerical: at a few points (states and controls drawn at random around the straight-line guess, times
across the horizon), every such expression moved by a turn of the control must stay within 1e-9 of its size. An
expression built from :math:`\\sin`, :math:`\\cos` and the like passes it to rounding; any other fails it by far
more. A control in the objective's integrand of minimum energy or fuel never passes (that integrand is not
periodic).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from convexguid.ocp.scaling import implied_control_scales

if TYPE_CHECKING:  # the problem module imports this one
    from convexguid.ocp.problem import Problem

TURN = 2.0 * math.pi
"""The period recognized without being stated."""

TRIALS = 4
"""Points at which a control's turn is tried."""

SAME = 1e-9
"""How close, relative to its size, every expression must stay after the turn."""


def control_periods(problem: Problem, turning: list[int]) -> tuple[float | None, ...]:
    """Each control's period: stated, :data:`TURN` when the control is unbounded and among the ``turning`` ones
    (:func:`turning_controls`), else None."""
    stated = [v.period for v in problem.controls]
    for j in turning:
        if problem.controls[j].lower is None and problem.controls[j].upper is None:
            stated[j] = TURN
    return tuple(stated)


def control_scales(problem: Problem, turning: list[int]) -> np.ndarray:
    """Each control's scale: as stated or estimated (:func:`~convexguid.ocp.scaling.implied_control_scales`), except
    that an angle that a turn changes nothing of, unbounded or bounded more than a turn wide, is measured in radians.
    Scaled by its bounds, the trust region let it jump by whole turns: the PROPT/PSOPT obstacle avoidance, a heading
    within [-10, 10] rad, held -4.47 and 0.82 at neighbouring nodes after eight iterations, and the flight between
    them swept through every heading. ``turning``: :func:`turning_controls`."""
    scales = implied_control_scales(problem)
    for j in turning:  # bounded (its bounds' magnitude) or not (the size the guess asks of it): in radians
        if problem.controls[j].scale_from != "stated":
            scales[j] = min(scales[j], 1.0)
    return scales


def turning_controls(problem: Problem) -> list[int]:
    """The controls without a stated period, unbounded or bounded more than a turn wide, of which a turn changes
    nothing the transcription evaluates (see the module docstring)."""
    candidates = [j for j, v in enumerate(problem.controls)
                  if v.period is None and (v.lower is None or v.upper is None or v.upper - v.lower > TURN)]
    if not candidates or problem.objective in ("energy", "fuel"):
        return []
    x, u, t = problem.state_vector(), problem.control_vector(), problem.time
    outputs = ca.vertcat(problem.rate_vector(), *(c.expression for c in problem.constraints))
    evaluate = ca.Function("periodic_outputs", [x, u, t], [outputs])
    rng = np.random.default_rng(0)
    start, end, guess = problem.straight_line()
    horizon = problem.tf if problem.tf is not None else problem.tf_guess
    points = []
    for _ in range(TRIALS):
        share = rng.uniform()
        state = start + share * (end - start) + rng.normal(0.0, 0.1, start.size) * (1.0 + np.abs(start))
        points.append((state, guess + rng.normal(0.0, 1.0, guess.size), share * horizon))
    return [j for j in candidates
            if ca.depends_on(outputs, u[j]) and all(_turn_changes_nothing(evaluate, point, j) for point in points)]


def _turn_changes_nothing(evaluate: ca.Function, point: tuple, j: int) -> bool:
    state, control, time = point
    turned = control.copy()
    turned[j] += TURN
    before = np.asarray(evaluate(state, control, time), dtype=float).ravel()
    after = np.asarray(evaluate(state, turned, time), dtype=float).ravel()
    if not (np.all(np.isfinite(before)) and np.all(np.isfinite(after))):
        return False
    return bool(np.all(np.abs(after - before) <= SAME * (1.0 + np.abs(before))))
