"""The quaternion-attitude plan judged against IPOPT on the same Hermite-Simpson NLP from several starts (the
robustness benchmark's reference, :mod:`convexguid.robustness`)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from convexguid.families.quaternion_attitude.program import eigenaxis_guess, eigenaxis_start
from convexguid.families.quaternion_attitude.reference import solve_quaternion_attitude_ipopt
from convexguid.families.quaternion_attitude.solve import build_case
from convexguid.reference import IndependentOptimum, best_of_starts

STRETCH = (1.0, 1.5, 0.75, 2.0)
"""Final-time guesses of the starts as multiples of the eigenaxis one (minimum time; cycled)."""
JITTER = 0.1
"""Relative size of the seeded noise on the rates and torques of the second and later starts."""


def independent_optimum(spec, solution, starts: int = 4) -> IndependentOptimum:
    """The best objective IPOPT (exact Hessians) reaches on the spec's NLP (its intervals, cones and margins).

    Taken from ``solution``, so that both solve one NLP: the final time it flew, for a minimum-energy slew whose
    final time is a multiple of the minimum time, and the node margin its dense check's repairs left on the
    cones and forbidden attitudes.

    Start 0 is the SCP's eigenaxis start; start ``k`` stretches the eigenaxis slew's duration by
    ``STRETCH[k]`` (minimum time) and adds seeded noise of ``JITTER`` times the largest rate and torque of the
    guess to every node's rate and torque.
    """
    case = build_case(spec)
    if case.tf is None and spec.objective == "energy":
        case = replace(case, tf=solution.figures.maneuver_time_s)
    K = spec.discretization.intervals
    margin = float(np.radians(solution.figures.node_constraint_margin_deg or 0.0))
    guess, tf_guess = eigenaxis_start(case, K)
    rng = np.random.default_rng(2003)

    def solve_from(k: int):
        tf = tf_guess * (STRETCH[k % len(STRETCH)] if case.tf is None else 1.0)
        start = eigenaxis_guess(case, case.t0 + np.linspace(0.0, tf, K + 1)) if k else guess
        if k:
            start = start.copy()
            for part in (slice(4, 7), slice(7, 10)):
                size = max(float(np.abs(start[:, part]).max()), 1e-9)
                start[1:-1, part] += JITTER * size * rng.standard_normal(start[1:-1, part].shape)
        return solve_quaternion_attitude_ipopt(case, K, start, tf, margin=margin)

    return best_of_starts(solve_from, starts, "IPOPT on the same NLP, exact Hessians")
