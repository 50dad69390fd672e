"""The boundary constraints of a transcription: an affine one as hard linear rows ``A z = b``, a nonlinear one as an
equality the engine linearizes, divided by its magnitude, and checked on the re-propagated state
(:meth:`~convexguid.ocp.problem.Problem.boundary_constraint`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:  # the transcription imports this module
    from convexguid.ocp.transcription import Transcription


def affine_rows(program: Transcription) -> tuple[sp.coo_matrix, np.ndarray] | None:
    """The affine boundary constraints ``a^T x_0 + c = 0`` or ``a^T x_N + c = 0`` as rows ``A z = b`` (None without
    any)."""
    p, nx = program.problem, program.nx
    x = p.state_vector()
    blocks, values = [], []
    for _, expression, at in p.boundary_constraints:
        if not p.boundary_is_affine(expression):
            continue
        node = 0 if at == "initial" else program.N
        function = ca.Function("boundary", [x], [ca.jacobian(expression, x), expression])
        gradient, offset = (np.asarray(v, dtype=float) for v in function(np.zeros(nx)))
        block = np.zeros((gradient.shape[0], program.num_variables))
        block[:, node * nx: (node + 1) * nx] = gradient
        blocks.append(block)
        values.append(-offset.ravel())
    return (sp.coo_matrix(np.vstack(blocks)), np.concatenate(values)) if blocks else None


def nonlinear_equalities(program: Transcription, X: ca.SX, tf) -> tuple[ca.SX, list[tuple[str, str, float]]]:
    """The nonlinear boundary constraints on the first or last node's states (``X``) and the final time, each row
    divided by its magnitude: the change of its value when every state moves by its own scale, at the user's guess
    when there is one, else (or where it gives no finite positive magnitude) at the straight-line guess, else 1 (its
    feasibility is then judged in that magnitude, as the defects are in the states' scales); and ``(name, at,
    magnitude)`` of each row. The straight line alone is not enough: the last phase of the Delta III launch states
    no final position, its straight line sits at the Earth's centre, where the orbital elements are not numbers,
    and its semi-major axis row was left in metres (every subproblem then failed) though the user's guess reached
    the target orbit."""
    p = program.problem
    x = p.state_vector()
    guesses = [program.states(program.initial_guess_straight())]
    if p.guess_nodes is not None:
        guesses.insert(0, program.states(program.initial_guess()))
    time_guess = p.tf if p.tf is not None else p.tf_guess
    rows, described = [], []
    for name, expression, at in p.boundary_constraints:
        if p.boundary_is_affine(expression):
            continue
        node, time = (0, 0.0) if at == "initial" else (program.N, time_guess)
        reach = ca.Function("reach", [x, p.time], [ca.mtimes(ca.fabs(ca.jacobian(expression, x)),
                                                             ca.DM(program.state_scales))])
        magnitudes = np.full(expression.numel(), np.nan)
        for guess in guesses:
            found = np.asarray(reach(guess[node], time), dtype=float).ravel()
            magnitudes = np.where(np.isnan(magnitudes) & np.isfinite(found) & (found > 0), found, magnitudes)
        magnitudes = np.where(np.isnan(magnitudes), 1.0, magnitudes)
        value = ca.substitute(expression, ca.vertcat(x, p.time), ca.vertcat(X[:, node], 0.0 if node == 0 else tf))
        rows.append(value / ca.DM(magnitudes))
        described += [(name, at, float(m)) for m in magnitudes]
    return (ca.vertcat(*rows) if rows else ca.SX(0, 1)), described


def boundary_errors(program: Transcription, states: np.ndarray, final_time: float) -> dict[str, float]:
    """Each nonlinear boundary constraint on the re-propagated first and last ``states`` (rows ``[0]``, ``[-1]``),
    in its magnitude, by ``"<at>_<name>_error"`` (as the final-state errors are judged)."""
    p, errors = program.problem, {}
    magnitudes = iter(m for _, _, m in program.boundary_equality_rows)
    for name, expression, at in p.boundary_constraints:
        if p.boundary_is_affine(expression):
            continue
        function = ca.Function("boundary", [p.state_vector(), p.time], [expression])
        state, time = (states[0], 0.0) if at == "initial" else (states[-1], final_time)
        values = np.abs(np.asarray(function(state, time), dtype=float).ravel())
        errors[f"{at}_{name}_error"] = float(max(v / next(magnitudes) for v in values))
    return errors
