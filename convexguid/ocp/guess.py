"""The first guess of a transcription when the user gives none: the straight line, with the free positions flown."""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from convexguid.ocp.parts import runge_kutta
from convexguid.ocp.scaling import straight_line_controls

if TYPE_CHECKING:
    from convexguid.ocp.problem import Problem
    from convexguid.ocp.transcription import Transcription


def flown_free_states(program: Transcription, z: np.ndarray) -> np.ndarray:
    """``z`` of ``program`` with each state whose final value is not stated and whose rate no control drives (a
    position, a range: the integral of other states) flown from its first node by its rate along the guess (forward
    Euler at the nodes, kept within its bounds), instead of held constant. Held constant, a range whose speed is not
    zero starts the SCP with defects it cannot remove within its trust region, and it shortens the final time
    instead (measured: COPS' hang glider ended `max_iterations` at 332 m; flown, it converges at 1247.9966 m in 99
    iterations). A state a control drives stays on the straight line: its rate along the guessed control is a guess
    too (flown at the mid bank angle, Betts' shuttle turned the wrong way and ended `max_iterations`), unless the
    straight line cannot be flown at all (:func:`unflyable`): then every state is flown."""
    p, u = program.problem, program.problem.control_vector()
    driven = np.array([u.shape[0] > 0 and ca.depends_on(p.rates[v.name], u) for v in p.states], dtype=bool)
    whole = unflyable(p)
    free = np.array([v.final is None for v in p.states]) & (~driven | whole)
    if not free.any():
        return z
    states, control = program.states(z).copy(), p.straight_line()[2]
    times = program.node_shares() * program.final_time(z)
    low, high = p.bounds_array(p.states)
    def rate(x: np.ndarray, t: float) -> np.ndarray:
        return np.asarray(program.rate(x, control, t), dtype=float).ravel()

    for k in range(program.N):
        h = times[k + 1] - times[k]  # the whole state by Runge-Kutta, four steps an interval; a position by Euler
        flown = runge_kutta(rate, states[k], h / 4, 4, times[k]) if whole else states[k] + h * rate(states[k], times[k])
        step = np.clip(flown, low, high)
        if not np.all(np.isfinite(step[free])):
            break
        states[k + 1, free] = step[free]
    return program.assemble(states, program.control_values(z), program.final_time(z))


def unflyable(problem: Problem) -> bool:
    """Whether nothing pins the end (no state has a final value) and the straight line, which then holds every state
    at its initial value, asks for controls outside their bounds (beyond 1e-6 of their scales:
    :func:`~convexguid.ocp.scaling.straight_line_controls`). Its guess is then the flight from the initial state under
    the guessed controls, which the vehicle can fly. CTProblems' minimum-time transfer to the geostationary orbit, its
    thrust bounded by 648 km/h^2, was held still on its straight line against a gravity of 2.9e3 km/h^2: `infeasible`
    on a local certificate (IPOPT on the same program: `Infeasible_Problem_Detected`); from the coasting orbit,
    converged and verified at 13.403204 h (the published 13.403182). Its minimum-energy twin, the thrust unbounded,
    can hold still and keeps the straight line: from the coast it crawled to `max_iterations`."""
    if problem.controls == [] or any(v.final is not None for v in problem.states):
        return False
    asked = straight_line_controls(problem)
    low, high = problem.bounds_array(problem.controls)
    margin = 1e-6 * np.array([v.scale for v in problem.controls])
    return bool(np.any((asked < low - margin) | (asked > high + margin)))

