"""Minimum-fuel 3-DoF powered descent by lossless convexification (Acikmese & Ploen 2007; Blackmore, Acikmese &
Scharf 2010), and the same landing stated as the nonconvex problem it relaxes.

A lander 1.5 km up, 2 km downrange and 500 m crossrange on Mars (x up), descending at 75 m/s and closing at 100 m/s,
lands at the origin at rest 40 s later. Its net thrust T lies between rho_1 and rho_2 (a nonconvex annulus: it
cannot throttle to zero), its mass burns at alpha |T|, and it stays above a 4 deg glide-slope cone. The vehicle is
that of Acikmese & Ploen's Mars example: six 3.1 kN engines canted 27 deg (T_max = 6 x 3100 cos 27 deg N), throttle
0.3 to 0.8, Isp 225 s, wet mass 1905 kg, dry 1505 kg; the start and the flight time are this example's (the
minimum-fuel flight time from this start is near 35 s; at 40 s both throttle limits are met).

``build()`` states the lossless convexification: with sigma = Gamma/m, u = T/m and z = ln m the dynamics are
linear (v' = u + g, z' = -alpha sigma), the thrust magnitude relaxes to the cone ||u|| <= sigma (kept exact by the
engine), the annulus becomes rho_1 e^-z <= sigma <= rho_2 e^-z (the engine linearizes these), the glide slope is a
cone, and the objective is the final log-mass. At the optimum ||u|| = sigma (the relaxation is lossless): the test
checks it on the dense re-propagation. ``build_nonconvex()`` states the original problem (thrust, mass, the
annulus as ||T||^2 bounds) for IPOPT: tests/test_ocp_cones.py compares the two final masses.
Run: python examples/powered_descent.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

GRAVITY = 3.7114  # m/s^2, Mars
T_MAX = 6 * 3100.0 * math.cos(math.radians(27.0))  # N
RHO_1, RHO_2 = 0.3 * T_MAX, 0.8 * T_MAX  # N
ALPHA = 1.0 / (225.0 * 9.807 * math.cos(math.radians(27.0)))  # s/m
WET_MASS, DRY_MASS = 1905.0, 1505.0  # kg
START_POSITION, START_VELOCITY = (1500.0, 500.0, 2000.0), (-75.0, 0.0, -100.0)  # m, m/s (x up)
GLIDE_SLOPE = math.radians(4.0)  # smallest elevation above the landing site
FLIGHT_TIME = 40.0  # s


def _kinematics(p: Problem):
    position = [p.state(f"r{axis}", initial=start, final=0.0, scale=2000.0)
                for axis, start in zip("xyz", START_POSITION, strict=True)]
    velocity = [p.state(f"v{axis}", initial=start, final=0.0, scale=100.0)
                for axis, start in zip("xyz", START_VELOCITY, strict=True)]
    # the glide slope: the lander stays above the cone of half-angle 90 deg - GLIDE_SLOPE over the site
    p.cone_constraint("glide_slope", position[1:], position[0] / math.tan(GLIDE_SLOPE), "m")
    return position, velocity


def build(intervals: int = 30, method: str = "foh") -> Problem:
    """The lossless convexification (log-mass z, acceleration u, its magnitude bound sigma)."""
    p = Problem("powered-descent-lcvx")
    position, velocity = _kinematics(p)
    log_mass = p.state("z", bounds=(math.log(DRY_MASS), None), initial=math.log(WET_MASS), scale=0.25)
    u = [p.control(f"u{axis}", scale=5.0, guess=GRAVITY if axis == "x" else 0.0) for axis in "xyz"]
    sigma = p.control("sigma", bounds=(0.0, None), scale=5.0, guess=GRAVITY)
    gravity = (-GRAVITY, 0.0, 0.0)
    p.dynamics({**{r: v for r, v in zip(position, velocity, strict=True)},
                **{v: a + g for v, a, g in zip(velocity, u, gravity, strict=True)},
                log_mass: -ALPHA * sigma})
    p.cone_constraint("thrust_magnitude", u, sigma, "m/s^2")
    p.path_constraint("throttle_floor", RHO_1 * ca.exp(-log_mass) - sigma, "m/s^2")
    p.path_constraint("throttle_ceiling", sigma - RHO_2 * ca.exp(-log_mass), "m/s^2")
    p.final_time(fixed=FLIGHT_TIME)
    p.minimize_terminal(-log_mass)
    p.transcription(intervals, method)
    return p


def build_nonconvex(intervals: int = 30, method: str = "foh") -> Problem:
    """The original problem: thrust T in the annulus rho_1 <= ||T|| <= rho_2, mass m' = -alpha ||T||."""
    p = Problem("powered-descent-nonconvex")
    position, velocity = _kinematics(p)
    mass = p.state("m", bounds=(DRY_MASS, None), initial=WET_MASS, scale=400.0)
    thrust = [p.control(f"T{axis}", bounds=(-RHO_2, RHO_2), scale=RHO_2,
                        guess=0.5 * (RHO_1 + RHO_2) if axis == "x" else 0.0) for axis in "xyz"]
    magnitude_squared = sum(t**2 for t in thrust)
    gravity = (-GRAVITY, 0.0, 0.0)
    p.dynamics({**{r: v for r, v in zip(position, velocity, strict=True)},
                **{v: t / mass + g for v, t, g in zip(velocity, thrust, gravity, strict=True)},
                mass: -ALPHA * ca.sqrt(magnitude_squared)})
    p.path_constraint("thrust_floor", 1.0 - magnitude_squared / RHO_1**2)
    p.path_constraint("thrust_ceiling", magnitude_squared / RHO_2**2 - 1.0)
    p.final_time(fixed=FLIGHT_TIME)
    p.minimize_terminal(-mass)
    p.transcription(intervals, method)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations)
    final_mass = math.exp(-solution.objective)
    print(f"final mass {final_mass:.3f} kg (fuel {WET_MASS - final_mass:.3f} kg), wall {solution.wall_time_s:.3f} s")
