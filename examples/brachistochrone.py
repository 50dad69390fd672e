"""The brachistochrone: the fastest frictionless slide from rest at the origin to (2, -2) m under gravity.

The answer is a cycloid (Johann Bernoulli, 1696); tests/test_ocp.py compares the planned time with it.
Run: python examples/brachistochrone.py
"""

import casadi as ca

from convexguid.ocp import Problem

G = 9.81


def build(intervals: int = 30) -> Problem:
    p = Problem("brachistochrone")
    p.state("x", initial=0.0, final=2.0)
    p.state("y", initial=0.0, final=-2.0)
    v = p.state("v", bounds=(0.0, None), initial=0.0, scale=6.0)
    theta = p.control("theta", bounds=(0.0, 3.14159), guess=1.0)
    x_dot, y_dot, v_dot = v * ca.sin(theta), -v * ca.cos(theta), G * ca.cos(theta)
    p.dynamics({p.states[0].symbol: x_dot, p.states[1].symbol: y_dot, v: v_dot})
    p.final_time(bounds=(0.1, 5.0), guess=1.0)
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message)
    print(f"final time {solution.figures.final_time_s:.6f} s")
