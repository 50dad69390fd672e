"""The magnitude of a state whose size the statement does not give: what its rate can do over the horizon.

The trust region is a box in scaled variables, and the defects and the final-state check are measured in the same
scales, so a state scaled far from its size crawls or breaks every subproblem: COPS' particle steering, a position
near 12 scaled by 1, held every step to 0.03-0.5 (100 iterations, no convergence); Dymos' single stage to orbit, a
vertical speed started at 1e-6 m/s and scaled so, had defects of 1e7 and every subproblem failed.

A state with a stated ``scale`` keeps it. Otherwise its scale is the largest magnitude of its bounds and boundary
values (``scale_from == "values"``) or 1 (``"none"``), and the rate estimate replaces it

* for a state with nothing stated: the change its rate can make over the horizon, :math:`t_f \\max |f_i|` over the
  straight-line guess (at five instants) with each control at its guess and across its range in turn (nine values
  between its bounds, a missing bound replaced by the guess less or plus the control's scale: :func:`swept_values`),
  when that is above 1;
* for a state whose stated values are all below :data:`NEGLIGIBLE` of what its rate can reach: that reach, the
  same change, except that a rate that pulls the state back (:math:`\\partial f_i / \\partial x_i < 0`) moves it
  only for its relaxation time :math:`1 / |\\partial f_i / \\partial x_i|` when that is shorter than the horizon.
  Rao and Mease's hypersensitive problem as Betts and GPOPS-II state it (:math:`x' = -x^3 + u` from 1 to 1.5 over
  10000) has :math:`|f| = 3.4` on its guess: over the horizon that is 33750, which replaced the stated 1.5 and made
  every subproblem fail; the relaxation time 0.15 keeps 1.5.

A control swept so has its stated scale, or its bounds' largest magnitude, or without either (and no period) the
size the straight-line guess asks of it (:func:`implied_control_scales`).

A user's guess (``Problem.initial_guess``) says more than the rate: a state it moves gets the largest magnitude of
its guessed values in place of the rate's change (at least its stated values; at least 1 when nothing is stated).
Dymos' cannonball, its speed guessed at 150-200 m/s and nothing stated of its size, was scaled by 1 and ran off to a
range of 268978 m (the published 3183.25 m).

Once a nearly feasible plan exists, an estimated scale it exceeds more than :data:`FOLLOW_FACTOR` times grows to its
size (:func:`following_plan`, asked once by the check-repair loop's first solve). A run that ends short of a verified
plan names the estimated scales its last plan outgrew (:func:`scale_advice`): a stated ``scale`` is then the remedy.

The estimate is crude, so values of a sensible size are kept (raised to it, Betts' shuttle took 491 iterations, not
169).
"""

from __future__ import annotations

import copy
from dataclasses import replace
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:  # the problem module imports this one
    from convexguid.ocp.declarations import Variable
    from convexguid.ocp.problem import Problem
    from convexguid.ocp.transcription import Transcription

NEGLIGIBLE = 1e-4
"""A state's bounds and boundary values give its scale unless all are below this share of what its rate can reach
over the horizon."""


def implied_control_scales(problem: Problem) -> np.ndarray:
    """Each control's scale: as stated, else the largest magnitude of its bounds; a control with neither and no period
    (scaled by 1) takes the size the straight-line guess asks of it where that is above 1: the least-squares control
    that makes the guess's rates its slopes (the rows each divided by its state's stated size), its largest magnitude
    over five instants. The straight line of CTProblems' minimum-energy transfer to the geostationary orbit holds
    the spacecraft still against a gravity of 2.9e3 km/h^2; its thrust, unbounded, scaled by 1, and its cost scaled
    from that, crawled to ``max_iterations`` (the cost grew by 10 trust radii an iteration)."""
    scales = np.array([v.scale for v in problem.controls], dtype=float)
    unknown = [j for j, v in enumerate(problem.controls) if v.scale_from == "none" and v.period is None]
    if not unknown:
        return scales
    size = np.max(np.abs(straight_line_controls(problem)), axis=0, initial=0.0)
    scales[unknown] = np.maximum(scales[unknown], size[unknown])
    return scales


def straight_line_controls(problem: Problem) -> np.ndarray:
    """The controls the straight-line guess asks for at five instants, one row each: the guessed controls moved by
    the least-squares change that makes the guess's rates its slopes (the rows each divided by its state's stated
    size; a row is left out where the rates are not numbers there)."""
    horizon = problem.tf if problem.tf is not None else problem.tf_guess
    start, end, guess = problem.straight_line()
    x, u, t = problem.state_vector(), problem.control_vector(), problem.time
    rate = ca.Function("rate", [x, u, t], [problem.rate_vector(), ca.jacobian(problem.rate_vector(), u)])
    rows = 1.0 / np.array([v.scale for v in problem.states])
    asked = []
    for share in np.linspace(0.0, 1.0, 5):
        value, jacobian = (np.asarray(a, dtype=float) for a in rate(start + share * (end - start), guess,
                                                                      share * horizon))
        wanted = rows * ((end - start) / horizon - value.ravel())
        if np.all(np.isfinite(wanted)) and np.all(np.isfinite(jacobian)):
            asked.append(guess + np.linalg.lstsq(rows[:, None] * jacobian, wanted, rcond=None)[0])
    return np.array(asked).reshape(-1, guess.size)


def estimated_scales(problem: Problem) -> np.ndarray:
    """Each state's magnitude (the module docstring)."""
    scales = np.array([v.scale for v in problem.states])
    unknown = [i for i, v in enumerate(problem.states) if v.scale_from != "stated"]
    if not unknown:
        return scales
    horizon = problem.tf if problem.tf is not None else problem.tf_guess
    start, end, guess = problem.straight_line()
    samples = [guess]
    for j, (v, scale) in enumerate(zip(problem.controls, implied_control_scales(problem), strict=True)):
        samples += [np.where(np.arange(guess.size) == j, value, guess) for value in swept_values(v, guess[j], scale)]
    x, u, t = problem.state_vector(), problem.control_vector(), problem.time
    rate = ca.Function("rate", [x, u, t], [problem.rate_vector(), ca.diag(ca.jacobian(problem.rate_vector(), x))])
    change, reach = np.zeros(len(problem.states)), np.zeros(len(problem.states))
    for share in np.linspace(0.0, 1.0, 5):
        for control in samples:
            value, pull = (np.asarray(a, dtype=float).ravel()
                           for a in rate(start + share * (end - start), control, share * horizon))
            speed = np.where(np.isfinite(value), np.abs(value), 0.0)
            relaxation = np.where(pull < 0, 1.0 / np.where(pull < 0, -pull, 1.0), np.inf)  # NaN pulls: none
            change = np.maximum(change, horizon * speed)
            reach = np.maximum(reach, speed * np.minimum(horizon, relaxation))
    guessed = None if problem.guess_nodes is None else np.max(np.abs(problem.guess_nodes[0]), axis=0)
    for i in unknown:
        if guessed is not None and guessed[i] > 0:
            scales[i] = max(scales[i] if problem.states[i].scale_from == "values" else 1.0, guessed[i])
        elif problem.states[i].scale_from == "none":
            scales[i] = max(change[i], 1.0)
        if problem.states[i].scale_from == "values" and scales[i] < NEGLIGIBLE * reach[i]:
            scales[i] = reach[i]
    return scales


def swept_values(control: Variable, guess: float, scale: float) -> np.ndarray:
    """Nine values across a control's range for the rate estimate: between its bounds; where a bound is not stated,
    its guess less (or plus) its ``scale`` stands for it. Betts' linear tangent steering states its angle without
    bounds and guesses 0, where the vertical speed's rate is 0: swept only at its guess, that speed was scaled by 1 and
    reached 14 (132 SCP iterations, IPOPT 8; with it, 8)."""
    lower = control.lower if control.lower is not None else guess - scale
    upper = control.upper if control.upper is not None else guess + scale
    return np.linspace(lower, max(upper, lower), 9)


FOLLOW_FACTOR = 4.0
"""An estimated scale that the plan's size exceeds by more than this factor follows the plan once
(:func:`followed_scales`)."""


def followed_scales(problem: Problem, scales: np.ndarray, sizes: np.ndarray) -> np.ndarray | None:
    """The scales once the plan is known: each state whose scale the statement does not give takes its size in
    ``sizes`` (its largest magnitude along a nearly feasible plan) when that is more than :data:`FOLLOW_FACTOR` times
    its scale; None when none moves. Never smaller: a state the plan has barely moved yet (a symmetric slew's idle
    axes at 1e-9) is not small, and shrunk to that size it sent Bilimoria & Wie's slew to a local minimum 9% slower.
    Measured on Betts' underwater vehicle (docs/engine.md, 'Scales that follow the plan')."""
    estimated = np.array([v.scale_from != "stated" for v in problem.states])
    grown = estimated & (sizes > FOLLOW_FACTOR * scales)
    return np.where(grown, sizes, scales) if grown.any() else None


def plan_scales(program: Transcription, z: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The states' largest magnitudes over the nodes of the plan ``z``, and the scales :func:`followed_scales` gives
    for them; None when no scale would move."""
    sizes = np.max(np.abs(program.states(z)), axis=0)
    scales = followed_scales(program.problem, program.state_scales, sizes)
    return None if scales is None else (sizes, scales)


def following_plan(program: Transcription, z: np.ndarray) -> Transcription | None:
    """``program`` restated on its grid with its scales :func:`followed_scales` at the plan ``z``, the changes listed
    in its ``scales_followed``; or None when they stay."""
    followed = plan_scales(program, z)
    if followed is None:
        return None
    scales = followed[1]
    twin = copy.copy(program.problem)
    twin.states = [replace(v, scale=float(scale), scale_from="stated") for v, scale in zip(twin.states, scales,
                                                                                          strict=True)]
    restated = program.restated(twin)
    restated.scales_followed = ", ".join(f"{v.name} {old:.3g} -> {new:.3g}" for v, old, new in
                                         zip(program.problem.states, program.state_scales, scales, strict=True)
                                         if new != old)
    return restated


RAN_AWAY = 1e6
"""A state this many times its scale is no size to state: the plan ran away (:func:`scale_advice`)."""


def scale_advice(program: Transcription, z: np.ndarray) -> str:
    """A clause naming each state whose scale was estimated (not stated) and that the plan ``z`` outgrew more than
    :data:`FOLLOW_FACTOR` times (those :func:`followed_scales` would move), with its scale and size; "" when none
    did. Told with a run that did not end verified: Park and Ramirez's fed-batch volume, scaled by its initial
    value 1, grew past 14. A plan beyond :data:`RAN_AWAY` times a scale ran away, and the clause says so instead:
    Dymos' launch to orbit stated without a floor on the mass flew through zero mass to positions of 1e73 m,
    which were no sizes to state."""
    followed = plan_scales(program, z)
    if followed is None:
        return ""
    sizes, scales = followed
    outgrown = [(v.name, old, size) for v, old, new, size in
                zip(program.problem.states, program.state_scales, scales, sizes, strict=True) if new != old]
    ran_away = [f"{name} {size:.3g}, {size / old:.3g} times its scale" for name, old, size in outgrown
                if size > RAN_AWAY * old]
    if ran_away:
        return (f"the last plan ran away ({'; '.join(ran_away)}): not a scale to state, but what sent it there (a "
                "state through zero in a division, a bound the physics needs)")
    grown = [f"{name} ({old:.3g}, reached {size:.3g})" for name, old, size in outgrown]
    return (f"the last plan outgrew the scales estimated for {', '.join(grown)}: state their sizes (p.state(..., "
            "scale=)), and those of the controls that drive them (p.control(..., scale=))")
