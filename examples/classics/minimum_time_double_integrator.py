"""The time-optimal double integrator: a bang-bang control with one switch, the textbook case of the maximum principle.

L. S. Pontryagin, V. G. Boltyanskii, R. V. Gamkrelidze, E. F. Mishchenko, The Mathematical Theory of Optimal
Processes, Interscience 1962, Ch. 1 (the time-optimal control of x'' = u):

    x' = v,  v' = u,  |u| <= 1,  x(0) = 1, v(0) = 0,  x(tf) = 0, v(tf) = 0,  minimise tf.

The control is -1 until the state meets the switching curve x = -v |v| / 2, then +1: here it switches at t = 1, where
x = 1/2 and v = -1, and the rest is reached at tf = 2 exactly. The control jumps from one bound to the other, which
Hermite-Simpson's control, continuous from node to midpoint to node, cannot follow: its final time is above 2 by
the transcription's error (1.8e-4 of it on 40 intervals, IPOPT's the same).
Run: python examples/classics/minimum_time_double_integrator.py
"""

from convexguid.ocp import Problem

PUBLISHED = 2.0
SOURCE = "Pontryagin et al., The Mathematical Theory of Optimal Processes (1962), Ch. 1"
FIGURE = "final time tf"


def build(intervals: int = 40) -> Problem:
    p = Problem("minimum-time-double-integrator")
    x = p.state("x", initial=1.0, final=0.0)
    v = p.state("v", initial=0.0, final=0.0)
    u = p.control("u", bounds=(-1.0, 1.0))
    p.dynamics({x: v, v: u})
    p.final_time(bounds=(0.1, 10.0))
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.figures.final_time_s)
