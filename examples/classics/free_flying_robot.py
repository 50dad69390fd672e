"""A free-flying space robot moved to rest at the origin with the least thruster use: two pairs of opposed thrusters.

After Y. Sakawa, "Trajectory planning of a free-flying robot by using the optimal control", Optimal Control
Applications and Methods 20, 1999, as stated by J. T. Betts, Practical Methods for Optimal Control Using Nonlinear
Programming (SIAM; 2nd ed. 2010, Sec. 6.13; 3rd ed. 2020, ex. 10.43). Position (x, y), attitude theta, their rates,
and the thrust used J. The thrusters u1..u4 in [0, 1] act in opposed pairs, each pair at most 1 in all:

    x'' = (u1 - u2 + u3 - u4) cos(theta),  y'' = (u1 - u2 + u3 - u4) sin(theta),
    theta'' = alpha (u1 - u2) - beta (u3 - u4),  J' = u1 + u2 + u3 + u4,  u1 + u2 <= 1,  u3 + u4 <= 1,
    from (-10, -10, pi/2) at rest to (0, 0, 0) at rest in 12 s;  minimise J(12),   alpha = beta = 0.2.

The optimum is bang-off-bang in every thruster, so the default grid is 100 intervals: on 40, IPOPT on the same
collocation stops 0.3% above the published figure.
Run: python examples/classics/free_flying_robot.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

ALPHA = BETA = 0.2
DURATION = 12.0
PUBLISHED = 7.91055654
SOURCE = "Sakawa, OCAM 20, 1999; Betts, Practical Methods for Optimal Control, 3rd ed. (2020), ex. 10.43"
FIGURE = "thrust used J(tf)"


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["J"]


def build(intervals: int = 100) -> Problem:
    p = Problem("free-flying-robot")
    x = p.state("x", initial=-10.0, final=0.0)
    y = p.state("y", initial=-10.0, final=0.0)
    theta = p.state("theta", initial=math.pi / 2, final=0.0)
    vx = p.state("vx", initial=0.0, final=0.0)
    vy = p.state("vy", initial=0.0, final=0.0)
    omega = p.state("omega", initial=0.0, final=0.0)
    used = p.state("J", initial=0.0)
    u1, u2, u3, u4 = (p.control(f"u{i}", bounds=(0.0, 1.0)) for i in range(1, 5))
    thrust = u1 - u2 + u3 - u4
    p.dynamics({x: vx, y: vy, theta: omega, vx: thrust * ca.cos(theta), vy: thrust * ca.sin(theta),
                omega: ALPHA * (u1 - u2) - BETA * (u3 - u4), used: u1 + u2 + u3 + u4})
    p.path_constraint("first_pair", u1 + u2 - 1.0)
    p.path_constraint("second_pair", u3 + u4 - 1.0)
    p.final_time(fixed=DURATION)
    p.minimize_terminal(used)
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
