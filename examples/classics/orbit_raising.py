"""The maximum-radius orbit transfer in a given time: Moyer & Pinkham's low-thrust Earth-to-Mars-orbit raising.

A. E. Bryson, Y.-C. Ho, Applied Optimal Control, Hemisphere 1975, Sec. 2.5 (after H. G. Moyer, G. Pinkham, 1964).
In units where mu = 1 and the initial orbit radius r0 = 1, with r the radius, u and v the radial and tangential
velocities and phi the thrust direction from the local horizontal:

    r' = u,  u' = v^2 / r - mu / r^2 + T sin(phi) / m(t),  v' = -u v / r + T cos(phi) / m(t),
    m(t) = 1 - 0.0749 t,  T = 0.1405,  tf = 3.32,
    r(0) = 1, u(0) = 0, v(0) = 1 (a circular orbit);  u(tf) = 0, v(tf) = sqrt(mu / r(tf)) (circular again),
    maximise r(tf).

The published final radius is 1.525 (PUBLISHED = 1.5252, the figure collocation codes reproduce for these data).
Bryson & Ho's transfer takes 193 days, 3.32 time units of 58.13 days (with tf = 3.3155 the optimum is 1.52368).
The thrust direction turns through about 290 degrees (from 25 to 312): it is an unbounded angle with period 2 pi,
so that the plan's values are unwrapped before they are flown (a bounded window would cut the optimal arc).
Run: python examples/classics/orbit_raising.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

MU = 1.0
THRUST = 0.1405
MASS_FLOW = 0.0749
FINAL_TIME = 3.32
PUBLISHED = 1.5252
SOURCE = "Bryson & Ho, Applied Optimal Control (1975), Sec. 2.5"
FIGURE = "final radius r(tf) / r0"


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["r"]


def build(intervals: int = 40) -> Problem:
    p = Problem("orbit-raising")
    r = p.state("r", initial=1.0)
    u = p.state("u", initial=0.0, final=0.0)
    v = p.state("v", initial=1.0)
    phi = p.control("phi", unit="rad", period=2 * math.pi)
    mass = 1.0 - MASS_FLOW * p.time
    p.dynamics({r: u,
                u: v**2 / r - MU / r**2 + THRUST * ca.sin(phi) / mass,
                v: -u * v / r + THRUST * ca.cos(phi) / mass})
    p.boundary_constraint("circular_speed", v - ca.sqrt(MU / r), at="final")
    p.final_time(fixed=FINAL_TIME)
    p.minimize_terminal(-r)
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
