"""The unit each path constraint's rows are judged in: its magnitude, brought near the defects' own.

A constraint enters the engine, and the dense check, in the unit it is written in, while the defects are in the
states' scales and the cones and nonlinear boundary conditions in their magnitudes. Betts' space station writes its
momentum limit as :math:`h \\cdot h - 10^8 \\le 0` in (ft lbf s)^2: a violation of 1e4 of that unit outweighed
everything else in the :math:`\\ell_1` merit, the step ratios came out near -1e10, and the badly scaled subproblems
failed (``solver_error``); a limit written in millionths of its unit was met by anything under the feasibility
tolerance. So each path inequality, path equality and point constraint is divided by :func:`constraint_divisors`
(docs/ocp.md, 'Units of a constraint').
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:
    from convexguid.ocp.problem import Problem

MAGNITUDE_SAMPLES = 21
"""Instants of the straight-line guess a constraint's magnitude is estimated over: evenly spaced, the same on every
grid, so a refined program judges it in the same unit."""

STRICTEST = 10.0
"""How many times stricter than its magnitude a constraint's rows may be judged. Measured on Betts' space station (a
momentum limit of magnitude 1.1e9): divided down to 1, 39 iterations; to 10, 54; to 100, 113. Down to 1, the PROPT
obstacle avoidance (magnitude 16, a path of fixed length threading two circles) ended unverified on 5 of 8 grids and
perturbations; at 10, 1 of 8, as in its own unit. No one value suits every statement: at 10 the docking cone of
examples/cw_docking.py, in m^2 (magnitude 4374), takes 22 iterations where its stated unit took 14."""


def constraint_divisors(problem: Problem, x: ca.SX, u: ca.SX, t: ca.SX, scales: np.ndarray, tf: float) -> np.ndarray:
    """What each of ``problem.constraints`` is divided by (1 for a cone, divided by its own magnitude elsewhere),
    from its magnitude :math:`m`: the stated ``scale``, else the largest change of its value when every state and
    control (symbols ``x``, ``u``; time ``t``) moves by its own scale (``scales``, states then controls), to second
    order (:math:`|\\nabla g|^T \\sigma + \\tfrac12 \\sigma^T |\\nabla^2 g| \\sigma`: a speed limit
    :math:`v^2 - v_{max}^2` has one where the straight line is at rest), over :data:`MAGNITUDE_SAMPLES` instants of the
    straight-line guess over the horizon ``tf`` (1 where nothing moves it). The divisor
    :math:`\\max(\\min(m, 1), m / S)`, :math:`S` = :data:`STRICTEST`, judges the rows in the stricter of their stated
    unit and their magnitude, never more than :math:`S` times stricter than the magnitude: a limit in tiny units is
    not lost under the feasibility tolerance, one in huge units does not drown the merit, and a well-scaled one is
    left as stated."""
    constraints = problem.constraints
    magnitudes = np.array([c.scale or 1.0 for c in constraints])
    estimated = [j for j, c in enumerate(constraints) if c.cone is None and c.scale is None]
    if estimated:
        variables, sigma = ca.vertcat(x, u), ca.DM(scales)
        changes = [ca.dot(ca.fabs(ca.gradient(g, variables)), sigma)
                   + 0.5 * ca.dot(sigma, ca.mtimes(ca.fabs(ca.hessian(g, variables)[0]), sigma))
                   for g in (constraints[j].expression for j in estimated)]
        reach = ca.Function("reach", [x, u, t], [ca.vertcat(*changes)])
        start, end, control = problem.straight_line()
        values = np.array([np.asarray(reach(start + s * (end - start), control, s * tf), dtype=float).ravel()
                           for s in np.linspace(0.0, 1.0, MAGNITUDE_SAMPLES)])
        largest = np.max(np.where(np.isfinite(values), values, 0.0), axis=0)
        magnitudes[estimated] = np.where(largest > 0, largest, 1.0)
    # a cone's magnitude stays 1 here (its own division is the cone block's): so does its divisor
    return np.maximum(np.minimum(magnitudes, 1.0), magnitudes / STRICTEST)
