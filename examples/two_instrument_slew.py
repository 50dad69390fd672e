"""An attitude slew with two body-fixed instruments: the star tracker must not look near the Sun (keep-out), the
antenna must keep looking near the Earth (keep-in).

A small satellite (inertia diag(20, 22, 18) kg m^2, torques within +-0.05 N m per axis) turns 120 deg about its
body z axis, rest to rest, in 60 s at minimum control energy. Its star tracker looks along body x; the Sun is in the
plane that boresight sweeps, 60 deg from where it starts, so the eigenaxis turn would look straight into it: the
tracker must stay 25 deg away, by lifting out of that plane, above it or below. The antenna looks along body z and
must stay within 18.5 deg of the Earth, 8 deg from inertial z towards +y: lifting the tracker tilts the antenna, and
the Earth cone allows only one side, and that one only just. Both cones are nonconvex in the attitude; the engine
linearizes them and the dense check judges them between the nodes. tests/test_ocp.py compares the energy
with IPOPT's on the same NLP.
Run: python examples/two_instrument_slew.py
"""

import math

import casadi as ca
import numpy as np

from convexguid.ocp import Problem
from convexguid.ocp.attitude import inertial_direction, rigid_body_dynamics

INERTIA = (20.0, 22.0, 18.0)  # kg m^2
TORQUE_MAX = 0.05  # N m
ANGLE = math.radians(120.0)
SUN = (math.cos(math.radians(60.0)), math.sin(math.radians(60.0)), 0.0)  # inertial
EARTH = (0.0, math.sin(math.radians(8.0)), math.cos(math.radians(8.0)))  # inertial
TRACKER, ANTENNA = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)  # body
SUN_EXCLUSION = math.radians(25.0)
EARTH_INCLUSION = math.radians(18.5)


def build(intervals: int = 40, duration: float = 60.0) -> Problem:
    p = Problem("two-instrument-slew")
    final_q = (0.0, 0.0, math.sin(ANGLE / 2), math.cos(ANGLE / 2))
    q = [p.state(f"q{i + 1}", bounds=(-1.0, 1.0), initial=(0.0, 0.0, 0.0, 1.0)[i], final=final_q[i])
         for i in range(4)]
    w = [p.state(f"w{i + 1}", initial=0.0, final=0.0, scale=0.05) for i in range(3)]
    u = [p.control(f"u{i + 1}", bounds=(-TORQUE_MAX, TORQUE_MAX)) for i in range(3)]
    p.dynamics(rigid_body_dynamics(q, w, u, np.diag(INERTIA)))
    tracker, antenna = inertial_direction(q, TRACKER), inertial_direction(q, ANTENNA)
    p.path_constraint("tracker_sun_exclusion", ca.dot(tracker, ca.DM(SUN)) - math.cos(SUN_EXCLUSION))
    p.path_constraint("antenna_earth_inclusion", math.cos(EARTH_INCLUSION) - ca.dot(antenna, ca.DM(EARTH)))
    p.final_time(fixed=duration)
    p.minimize_energy()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations)
    print(f"energy {solution.objective:.6g} N^2 m^2 s, wall {solution.wall_time_s:.3f} s")
