"""The Rayleigh problem with a mixed control-state constraint: an electric oscillator's current driven to rest.

After H. Maurer and D. Augustin, "Sensitivity analysis and real-time control of parametric optimal control problems
using boundary value methods", Online Optimization of Large Scale Systems (Springer, 2001), as stated by J. T. Betts,
Practical Methods for Optimal Control Using Nonlinear Programming, 3rd ed. (SIAM, 2020), ex. 10.113. Two states
and the cost J (the integral of its rate):

    x1' = x2,  x2' = -x1 + x2 (1.4 - 0.14 x2^2) + 4 u,  J' = u^2 + x1^2,  u + x1 / 6 <= 0,
    from x1 = x2 = -5 over 4.5 s (free final state);  minimise J(4.5).

The constraint holds on a boundary arc near the end, where the control follows the state (u = -x1 / 6): between
nodes a quadratic control cannot follow it exactly, and the dense check sees the difference.
Run: python examples/classics/rayleigh_mixed.py
"""

from convexguid.ocp import Problem

DURATION = 4.5
PUBLISHED = 44.8044433
SOURCE = "Maurer & Augustin 2001; Betts, Practical Methods for Optimal Control, 3rd ed. (2020), ex. 10.113"
FIGURE = "cost J(tf)"


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["J"]


def build(intervals: int = 100) -> Problem:
    p = Problem("rayleigh-mixed")
    x1 = p.state("x1", initial=-5.0)
    x2 = p.state("x2", initial=-5.0)
    cost = p.state("J", initial=0.0)
    u = p.control("u")
    p.dynamics({x1: x2, x2: -x1 + x2 * (1.4 - 0.14 * x2**2) + 4.0 * u, cost: u**2 + x1**2})
    p.path_constraint("mixed", u + x1 / 6.0)
    p.final_time(fixed=DURATION)
    p.minimize_terminal(cost)
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
