"""The flat-attitude plan judged against IPOPT on the same NLP from several starts (the robustness benchmark's
reference, :mod:`convexguid.robustness`)."""

from __future__ import annotations

import numpy as np

from convexguid.families.flat_attitude.program import FlatAttitudeProgram, build_problem
from convexguid.families.flat_attitude.reference import solve_flat_attitude_ipopt
from convexguid.reference import IndependentOptimum, best_of_starts

BEND_RAD = 0.5
"""Amplitude of the bend added to the paper's start for the second and later starts, rad per Euler angle."""


def independent_optimum(spec, solution, starts: int = 4) -> IndependentOptimum:
    """The best energy IPOPT (exact Hessians) reaches on the spec's transcription, check points included.

    Start 0 is the paper's cubic Hermite guess (the SCP's own start); start ``k`` adds the bend
    :math:`b_k \\sin(\\pi\\tau)` with a seeded random :math:`b_k \\in [-0.5, 0.5]^3` rad, which keeps the
    boundary attitudes and rates and sends the path round the keep-out cones on other sides.
    """
    problem = build_problem(spec)
    x0 = FlatAttitudeProgram(problem).initial_guess().reshape(-1, 3)
    tau = (problem.node_times - problem.t0) / (problem.tf - problem.t0)
    rng = np.random.default_rng(2018)
    bends = [np.zeros(3)] + [rng.uniform(-BEND_RAD, BEND_RAD, 3) for _ in range(starts - 1)]

    def solve_from(k: int):
        start = x0 + np.sin(np.pi * tau)[:, None] * bends[k]
        return solve_flat_attitude_ipopt(problem, start.ravel())

    return best_of_starts(solve_from, starts, "IPOPT on the same NLP, exact Hessians")
