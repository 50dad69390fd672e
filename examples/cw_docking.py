"""A Clohessy-Wiltshire proximity operation: a chaser 100 m behind a docking port flies into it inside a
line-of-sight approach cone, with a per-axis thrust box and a speed limit, at minimum fuel with a free final time.

Hill frame at the port: x radial, y along-track, z cross-track; the port looks along -y, so the chaser comes in
from y < 0 and must stay in the cone sqrt(x^2 + z^2) <= tan(20 deg) (-y), written squared (smooth; the nappe on
the y > 0 side is out of reach, since the path could only get there through the port itself). Fuel is the integral of
|a_x| + |a_y| + |a_z| (one thruster pair per axis), in m/s. The shape of OpenSCvx's examples/spacecraft/proxops_cw.py;
the numbers are this example's own.
Run: python examples/cw_docking.py
"""

import math

from convexguid.ocp import Problem

MEAN_MOTION = 0.0011  # rad/s, a low Earth orbit
CONE_HALF_ANGLE = math.radians(20.0)
THRUST_MAX = 0.02  # m/s^2 per axis
SPEED_MAX = 0.5  # m/s


def build(intervals: int = 40, start_y: float = -100.0) -> Problem:
    n = MEAN_MOTION
    p = Problem("cw-docking")
    x = p.state("x", initial=5.0, final=0.0, scale=10.0)
    y = p.state("y", initial=start_y, final=0.0)
    z = p.state("z", initial=-5.0, final=0.0, scale=10.0)
    vx = p.state("vx", initial=0.0, final=0.0, scale=SPEED_MAX)
    vy = p.state("vy", initial=0.0, final=0.0, scale=SPEED_MAX)
    vz = p.state("vz", initial=0.0, final=0.0, scale=SPEED_MAX)
    ax, ay, az = (p.control(f"a{axis}", bounds=(-THRUST_MAX, THRUST_MAX)) for axis in "xyz")
    p.dynamics({x: vx, y: vy, z: vz,
                vx: 3 * n**2 * x + 2 * n * vy + ax, vy: -2 * n * vx + ay, vz: -(n**2) * z + az})
    p.path_constraint("approach_cone", x**2 + z**2 - math.tan(CONE_HALF_ANGLE) ** 2 * y**2, "m^2")
    p.path_constraint("speed", vx**2 + vy**2 + vz**2 - SPEED_MAX**2, "m^2/s^2")
    p.final_time(bounds=(100.0, 600.0), guess=300.0)
    p.minimize_fuel()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations)
    print(f"fuel {solution.objective:.6f} m/s, final time {solution.figures.final_time_s:.2f} s")
