"""The hard linear rows of a transcription, :math:`Az = b` and :math:`Gz \\le h`, that every convex subproblem keeps.

Equalities: the stated boundary values (the states at the first and the last node) and the boundary constraints
affine in the states (:func:`~convexguid.ocp.boundary.affine_rows`). Inequalities, in this order: the variables'
upper bounds, their lower bounds (a state bound a dense-check repair tightened less its margin,
:class:`~convexguid.ocp.parts.Margins`), a bounded control's interpolant held within its bounds at the
transcription's ``INTERPOLATION_SAMPLES`` of every interval, and for the 1-norm fuel the slack rows
:math:`\\pm v - s \\le 0`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from convexguid.ocp.boundary import affine_rows
from convexguid.scp.problem import LinearConstraints

if TYPE_CHECKING:
    from convexguid.ocp.transcription import Transcription


def linear_constraints(t: Transcription) -> LinearConstraints:
    """The transcription's rows ``A z = b`` and ``G z <= h`` (the module docstring lists them)."""
    p, N, nx, n = t.problem, t.N, t.nx, t.num_variables
    columns, values = [], []
    for i, v in enumerate(p.states):
        for node, value in ((0, v.initial), (N, v.final)):
            if value is not None:
                columns.append(node * nx + i)
                values.append(value)
    A = selection(np.array(columns, dtype=int), 1.0, n)
    boundary = affine_rows(t)
    if boundary is not None:
        A = sp.vstack([A, boundary[0]]).tocoo()
        values += list(boundary[1])
    low, high = variable_bounds(t)
    upper, lower = np.flatnonzero(np.isfinite(high)), np.flatnonzero(np.isfinite(low))
    blocks = [selection(upper, 1.0, n), selection(lower, -1.0, n), interpolant_rows(t)]
    if t.fuel_norm == 1:
        # -s <= v <= s for every control value: v - s <= 0 and -v - s <= 0
        controls = np.arange(t.control_start, t.slack_start)
        slacks = np.arange(t.slack_start, t.slack_start + t.num_slacks)
        rows = np.arange(controls.size)
        for sign in (1.0, -1.0):
            blocks.append(sp.coo_matrix((np.concatenate([np.full(rows.size, sign), -np.ones(rows.size)]),
                                         (np.concatenate([rows, rows]), np.concatenate([controls, slacks]))),
                                        shape=(rows.size, n)))
    # a repaired state bound holds with its margin at the nodes next to where the dense check saw it broken
    tightened = np.concatenate([t.margins.bounds, np.zeros(n - t.margins.bounds.size)])
    h = np.concatenate([high[upper] - tightened[upper], -low[lower] - tightened[lower], interpolant_limits(t),
                        np.zeros(2 * t.num_slacks if t.fuel_norm == 1 else 0)])
    return LinearConstraints(A.tocoo(), np.array(values, dtype=float), sp.vstack(blocks).tocoo(), h)


def selection(columns: np.ndarray, sign: float, n: int) -> sp.coo_matrix:
    """One row per entry of ``columns``: ``sign`` times that variable."""
    return sp.coo_matrix((np.full(columns.size, sign), (np.arange(columns.size), columns)), shape=(columns.size, n))


def variable_bounds(t: Transcription) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of every variable of ``z`` (infinite where there is none)."""
    p, N = t.problem, t.N
    xl, xh = p.bounds_array(p.states)
    ul, uh = p.bounds_array(p.controls)
    per_axis = t.control_values_per_axis()
    low = [np.tile(xl, N + 1), np.tile(ul, per_axis), np.zeros(t.num_slacks), np.full(int(t.epigraph), -np.inf)]
    high = [np.tile(xh, N + 1), np.tile(uh, per_axis), np.full(t.num_slacks, np.inf), np.full(int(t.epigraph), np.inf)]
    if t.free_time:
        low.append([p.tf_bounds[0]])
        high.append([p.tf_bounds[1]])
    return np.concatenate(low), np.concatenate(high)


def bounded_controls(t: Transcription, upper: bool) -> list[int]:
    return [j for j, v in enumerate(t.problem.controls) if (v.upper if upper else v.lower) is not None]


def interpolant_rows(t: Transcription) -> sp.coo_matrix:
    """Rows ``+-(sum_i a_i v_i)``: the control's interpolant at the transcription's ``INTERPOLATION_SAMPLES`` for
    every bounded control on every interval (upper bounds, then lower; :func:`interpolant_limits` gives their
    right-hand sides)."""
    rows, cols, vals, count = [], [], [], 0
    for sign, upper in ((1.0, True), (-1.0, False)):
        for k in range(t.N):
            for j in bounded_controls(t, upper):
                for s in t.INTERPOLATION_SAMPLES:
                    for column, weight in zip(t.interval_control_columns(k, j), t.interval_weights(s), strict=True):
                        rows.append(count)
                        cols.append(column)
                        vals.append(sign * weight)
                    count += 1
    return sp.coo_matrix((vals, (rows, cols)), shape=(count, t.num_variables))


def interpolant_limits(t: Transcription) -> np.ndarray:
    controls, samples = t.problem.controls, len(t.INTERPOLATION_SAMPLES)
    upper = [controls[j].upper for _ in range(t.N) for j in bounded_controls(t, True)]
    lower = [-controls[j].lower for _ in range(t.N) for j in bounded_controls(t, False)]
    return np.repeat(np.array(upper + lower, dtype=float), samples)
