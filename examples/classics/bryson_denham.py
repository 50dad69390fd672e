"""Bryson & Denham's state-constrained double integrator: the least control effort with a bounded position.

A. E. Bryson, Y.-C. Ho, Applied Optimal Control, Hemisphere 1975, Sec. 3.11 (Bryson, Denham, Dreyfus, AIAA J. 1963):

    x' = v,  v' = u,  x(0) = 0, v(0) = 1,  x(1) = 0, v(1) = -1,  x(t) <= l = 1/9,
    minimise J = (1/2) integral_0^1 u^2 dt.

For l <= 1/6 the bound is met along an arc 3l <= t <= 1 - 3l and J = 4 / (9 l) = 4 exactly for l = 1/9.
The objective is minimize_energy (the integral of u^2, kept exact as a convex quadratic in every subproblem, so
the program's objective is 2 J); the state J with rate u^2 / 2 only reports the figure (Hermite-Simpson integrates
it with the same Simpson weights as the energy, so J(1) is half the program's objective).
Run: python examples/classics/bryson_denham.py
"""

from convexguid.ocp import Problem

LIMIT = 1.0 / 9.0
PUBLISHED = 4.0 / (9.0 * LIMIT)
SOURCE = "Bryson & Ho, Applied Optimal Control (1975), Sec. 3.11"
FIGURE = "J = (1/2) integral of u^2"


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["J"]


def build(intervals: int = 30) -> Problem:
    p = Problem("bryson-denham")
    x = p.state("x", bounds=(None, LIMIT), initial=0.0, final=0.0)
    v = p.state("v", initial=1.0, final=-1.0)
    cost = p.state("J", initial=0.0)
    u = p.control("u")
    p.dynamics({x: v, v: u, cost: u**2 / 2})
    p.final_time(fixed=1.0)
    p.minimize_energy()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
