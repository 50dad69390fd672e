"""OpenSCvx's proximity-operations example (examples/spacecraft/proxops_cw.py of OpenSCvx 0.5.2) stated in
convexguid: the same Clohessy-Wiltshire chaser, bounds, boundary values, approach cone and cone entrance.

A chaser 100 m behind the target on the V-bar (y = -100 m, drifting at 2 m/s along y) docks at the origin at rest.
Every position component within +-100 m, every velocity within +-2 m/s, every acceleration within +-0.1 m/s^2.
Over the second half of the maneuver it stays in an R-bar approach cone of 20 deg about -x (sqrt(y^2 + z^2) <=
tan(20 deg) (-x), written squared), entered at least 20 m below the target at half time. The final time is free,
at most 180 s. OpenSCvx's file minimizes nothing (its cost is zero: any feasible plan); this one minimizes fuel,
the integral of |a_x| + |a_y| + |a_z|, with the acceleration linear between nodes (a first-order hold: the
Clohessy-Wiltshire flow across each interval is exact, so the dense re-propagation lands where the plan does).
validation/BENCHMARKS_ocp.md sets the two side by side (python -m convexguid.benches.openscvx).
Run: python examples/proxops_openscvx.py
"""

import math

from convexguid.ocp import Problem

MU = 3.986004418e14  # m^3/s^2
SEMI_MAJOR_AXIS = 6.778e6  # m, about 400 km up
MEAN_MOTION = math.sqrt(MU / SEMI_MAJOR_AXIS**3)
CONE_HALF_ANGLE = math.radians(20.0)
A_MAX, V_MAX, P_MAX = 0.1, 2.0, 100.0


def build(intervals: int = 20, method: str = "foh", entrance_depth: float = 20.0) -> Problem:
    """The problem on ``intervals`` intervals of ``method``, the cone entered ``entrance_depth`` m below the target."""
    n = MEAN_MOTION
    p = Problem("proxops-cw")
    x, y, z = (p.state(axis, bounds=(-P_MAX, P_MAX), initial=start, final=0.0)
               for axis, start in zip("xyz", (0.0, -100.0, 0.0), strict=True))
    vx, vy, vz = (p.state(f"v{axis}", bounds=(-V_MAX, V_MAX), initial=start, final=0.0)
                  for axis, start in zip("xyz", (0.0, 2.0, 0.0), strict=True))
    ax, ay, az = (p.control(f"a{axis}", bounds=(-A_MAX, A_MAX)) for axis in "xyz")
    p.dynamics({x: vx, y: vy, z: vz,
                vx: 3 * n**2 * x + 2 * n * vy + ax, vy: -2 * n * vx + ay, vz: -(n**2) * z + az})
    p.path_constraint("approach_cone", y**2 + z**2 - math.tan(CONE_HALF_ANGLE) ** 2 * x**2, "m^2",
                      during=(0.5, 1.0))
    p.point_constraint("cone_entrance", entrance_depth + x, at=0.5, unit="m")
    p.final_time(bounds=(10.0, 180.0), guess=120.0)
    p.minimize_fuel()
    p.transcription(intervals, method)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations)
    print(f"fuel {solution.objective:.6f} m/s, final time {solution.figures.final_time_s:.3f} s, "
          f"wall {solution.wall_time_s:.3f} s")
