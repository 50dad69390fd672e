"""The brachistochrone: the fastest frictionless slide from rest at the origin to (2, -2) m under gravity.

The answer is a cycloid (Johann Bernoulli, 1696); tests/test_ocp.py compares the planned time with it.
Run: python examples/brachistochrone.py
"""

import casadi as ca

from convexguid.ocp import Problem

G = 9.81
PUBLISHED = 0.8243387
SOURCE = "Bernoulli 1696: the cycloid through (2, -2) m, g = 9.81 m/s^2"
FIGURE = "final time tf [s]"


def build(intervals: int = 30) -> Problem:
    p = Problem("brachistochrone")
    x = p.state("x", initial=0.0, final=2.0, unit="m")
    y = p.state("y", initial=0.0, final=-2.0, unit="m")
    v = p.state("v", bounds=(0.0, None), initial=0.0, scale=6.0, unit="m/s")
    theta = p.control("theta", bounds=(-1.5708, 3.1416), guess=1.0, unit="rad")  # from the downward vertical
    p.dynamics({x: v * ca.sin(theta), y: -v * ca.cos(theta), v: G * ca.cos(theta)})
    p.final_time(bounds=(0.1, 5.0), guess=1.0)
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message)
    print(f"final time {solution.figures.final_time_s:.6f} s")
