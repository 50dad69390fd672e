"""The first guess of a transcription when the user gives none: the straight line, with the free positions flown."""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:
    from convexguid.ocp.transcription import Transcription


def flown_free_states(program: Transcription, z: np.ndarray) -> np.ndarray:
    """``z`` of ``program`` with each state whose final value is not stated and whose rate no control drives (a
    position, a range: the integral of other states) flown from its first node by its rate along the guess (forward
    Euler at the nodes, kept within its bounds), instead of held constant. Held constant, a range whose speed is not
    zero starts the SCP with defects it cannot remove within its trust region, and it shortens the final time
    instead (measured: COPS' hang glider ended `max_iterations` at 332 m; flown, it converges at 1247.9966 m in 99
    iterations). A state a control drives stays on the straight line: its rate along the guessed control is a guess
    too (flown at the mid bank angle, Betts' shuttle turned the wrong way and ended `max_iterations`)."""
    p, u = program.problem, program.problem.control_vector()
    driven = np.array([u.shape[0] > 0 and ca.depends_on(p.rates[v.name], u) for v in p.states], dtype=bool)
    free = np.array([v.final is None for v in p.states]) & ~driven
    if not free.any():
        return z
    states, control = program.states(z).copy(), p.straight_line()[2]
    times = program.node_shares() * program.final_time(z)
    low, high = p.bounds_array(p.states)
    for k in range(program.N):
        rate = np.asarray(program.rate(states[k], control, times[k]), dtype=float).ravel()
        step = np.clip(states[k] + (times[k + 1] - times[k]) * rate, low, high)
        if not np.all(np.isfinite(step[free])):
            break
        states[k + 1, free] = step[free]
    return program.assemble(states, program.control_values(z), program.final_time(z))
