"""The terminal cost :math:`\\phi(x_N, t_f)` of a transcribed problem: whether it is a linear cost, its gradient,
and a magnitude for its epigraph variable when it is not."""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:  # the transcription imports this module
    from convexguid.ocp.problem import Problem
    from convexguid.ocp.transcription import Transcription


def _terminal_symbols(program: Transcription) -> tuple[ca.SX, ca.SX]:
    """The terminal cost as an expression of ``z`` (the final node's states and the final time), and ``z``."""
    z = ca.SX.sym("z", program.num_variables)
    final_state = z[program.control_start - program.nx: program.control_start]
    tf = z[-1] if program.free_time else program.problem.tf
    return program._terminal_function(final_state, tf), z


def terminal_cost_is_linear(problem: Problem) -> bool:
    """Whether the terminal cost is ``c^T z`` exactly, affine in the final state (and the final time when it is
    free) with no constant part: then a linear cost, else an epigraph."""
    state, time = problem.state_vector(), problem.time
    expression = problem.terminal
    variables = ca.vertcat(state, time)
    jacobian = ca.jacobian(expression, variables)
    offset = ca.substitute(expression, variables, ca.DM.zeros(variables.shape[0]))
    return (not ca.depends_on(jacobian, variables) and float(ca.evalf(offset)) == 0.0
            and (problem.free_time or not ca.depends_on(expression, time)))


def terminal_gradient(program: Transcription) -> np.ndarray:
    """The linear cost ``c`` of a terminal cost :func:`terminal_cost_is_linear` said is ``c^T z``."""
    expression, z = _terminal_symbols(program)
    return np.asarray(ca.evalf(ca.substitute(ca.jacobian(expression, z), z, ca.DM.zeros(z.shape[0])))).ravel()


def terminal_scale(program: Transcription) -> float:
    """A magnitude for the terminal cost's epigraph variable: its size at the guess's final state, or the change a
    move of every final state (and a free final time) by its own scale makes in it, to second order, whichever is
    larger. (Its size alone fails a cost that is zero at the guess, such as COPS' catalyst mixing,
    :math:`-1 + x_1 + x_2`: scaled by 1e-6, the epigraph variable moved 1e-3 per iteration at the largest trust
    radius; the first order alone fails a sum of squared fit residuals started at zero, whose gradient vanishes
    there: its epigraph crawled the same way.)"""
    p = program.problem
    final = p.straight_line()[1]
    tf = p.tf_guess if program.free_time else p.tf
    state, time = p.state_vector(), p.time
    reach = ca.Function("reach", [state, time], [ca.jacobian(p.terminal, state), ca.jacobian(p.terminal, time),
                                                 ca.hessian(p.terminal, state)[0]])
    by_state, by_time, curvature = (np.abs(np.asarray(v, dtype=float)) for v in reach(final, tf))
    scales = program.state_scales
    change = float(by_state.ravel() @ scales + 0.5 * scales @ curvature @ scales)
    if program.free_time:
        change += float(by_time.ravel()[0]) * tf
    return max(abs(program._terminal_value(final, tf)), change, 1e-6)
