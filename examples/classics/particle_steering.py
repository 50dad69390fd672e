"""COPS particle steering: the minimum time to bring a particle driven by a thrust of fixed magnitude onto a line.

E. D. Dolan, J. J. More, T. S. Munson, "Benchmarking optimization software with COPS 3.0", Argonne ANL/MCS-TM-273
(2004), problem "Particle steering" (after Bryson & Ho, Applied Optimal Control, 1975, Sec. 2.4). Positions y1, y2,
velocities y3, y4 and the thrust angle u, with the acceleration a = 100:

    y1' = y3,  y2' = y4,  y3' = a cos(u),  y4' = a sin(u),
    y(0) = 0;  y2(tf) = 5, y3(tf) = 45, y4(tf) = 0 (y1(tf) free),  minimise tf.

Published: tf = 0.554570879 (COPS, 400 intervals). The angle is bounded to (-pi/2, pi/2), where the linear tangent
law of the optimum lies.
Run: python examples/classics/particle_steering.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

ACCELERATION = 100.0
PUBLISHED = 0.554570879
SOURCE = "COPS 3.0 (Dolan, More, Munson 2004), particle steering"
FIGURE = "final time tf [s]"


def build(intervals: int = 50) -> Problem:
    p = Problem("particle-steering")
    y1, y2 = p.state("y1", initial=0.0), p.state("y2", initial=0.0, final=5.0)
    y3, y4 = p.state("y3", initial=0.0, final=45.0), p.state("y4", initial=0.0, final=0.0)
    u = p.control("u", bounds=(-math.pi / 2, math.pi / 2), unit="rad")
    p.dynamics({y1: y3, y2: y4, y3: ACCELERATION * ca.cos(u), y4: ACCELERATION * ca.sin(u)})
    p.final_time(bounds=(0.1, 2.0), guess=1.0)
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
