"""Betts' asymmetric minimum-time reorientation: 150 deg about body x, rest to rest, |u_i| <= 50 N m.

J. T. Betts, Practical Methods for Optimal Control and Estimation Using Nonlinear Programming, 2nd ed., SIAM 2010,
p. 299 (also Fleming, Sekhavat, Ross, AIAA 2008-7012): inertia diag(5621, 4547, 2364) kg m^2, optimal time
28.6304 s. The same slew as problems/betts_asymmetric_slew.yaml, stated in Python: quaternion (scalar last) and
body rates as states, the three torques as controls.
Run: python examples/betts_slew.py
"""

import math

import numpy as np

from convexguid.ocp import Problem
from convexguid.ocp.attitude import rigid_body_dynamics

INERTIA = (5621.0, 4547.0, 2364.0)
TORQUE_MAX = 50.0
ANGLE = math.radians(150.0)
PUBLISHED = 28.6304
SOURCE = "Betts, Practical Methods for Optimal Control, 2nd ed. (2010), p. 299"
FIGURE = "final time tf [s]"


def build(intervals: int = 100) -> Problem:
    p = Problem("betts-asymmetric-slew")
    final_q = (math.sin(ANGLE / 2), 0.0, 0.0, math.cos(ANGLE / 2))
    q = [p.state(f"q{i + 1}", bounds=(-1.0, 1.0), initial=(0.0, 0.0, 0.0, 1.0)[i], final=final_q[i])
         for i in range(4)]
    w = [p.state(f"w{i + 1}", initial=0.0, final=0.0, scale=0.15) for i in range(3)]
    u = [p.control(f"u{i + 1}", bounds=(-TORQUE_MAX, TORQUE_MAX)) for i in range(3)]
    p.dynamics(rigid_body_dynamics(q, w, u, np.diag(INERTIA)))
    p.final_time(bounds=(10.0, 60.0), guess=35.0)
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations)
    print(f"final time {solution.figures.final_time_s:.4f} s (Betts: 28.6304 s)")
