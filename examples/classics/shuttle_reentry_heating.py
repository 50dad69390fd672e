"""The Space Shuttle's reentry at maximum crossrange with the heating on the wing's leading edge at most
70 BTU/ft^2/s.

J. T. Betts, Practical Methods for Optimal Control and Estimation Using Nonlinear Programming, 2nd ed., SIAM 2010,
Example 6.1, the heat-limited case: theta(tf) = 30.6255 deg (tf = 2198.67 s), the figures Dymos' shuttle test
asserts too. The dynamics, bounds and boundary values are those of shuttle_reentry.py; the constraint is
q = q_a q_r <= 70 with q_r = 17700 sqrt(rho) (1e-4 v)^3.07 and
q_a = 1.0672181 - 0.19213774e-1 alpha + 0.21286289e-3 alpha^2 - 0.10117249e-5 alpha^3 (alpha in degrees),
held at every node and midpoint.

Run: python examples/classics/shuttle_reentry_heating.py
"""

import importlib.util
from pathlib import Path

from convexguid.ocp import Problem

_SPEC = importlib.util.spec_from_file_location("shuttle_reentry", Path(__file__).with_name("shuttle_reentry.py"))
shuttle = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(shuttle)

PUBLISHED = 30.6255
SOURCE = "Betts, Practical Methods for Optimal Control..., 2nd ed., SIAM 2010, Example 6.1 (heating at most 70)"
FIGURE = "final latitude theta(tf) [deg]"
figure = shuttle.figure


def build(intervals: int = 50) -> Problem:
    return shuttle.build(intervals, heating_limit=70.0)


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
