"""Dymos' two-phase cannonball: the ball's size and launch that carry it farthest through the air, an ascent to
its apex and a descent to the ground.

OpenMDAO Dymos, examples/cannonball (the multi-phase cannonball notebook and its test of connected initial states):
a solid iron ball (7870 kg/m^3, drag coefficient 0.5) of radius R in [0.01, 0.1] m, a design parameter, fired from
the ground with at most 400 kJ of muzzle energy, flat Earth (g = 9.80665 m/s^2):

    v' = -D/m - g sin(gam),  gam' = -g cos(gam) / v,  h' = v sin(gam),  r' = v cos(gam),
    D = rho(h) v^2 (pi R^2) C_D / 2,  m = 4/3 pi R^3 rho_iron,

the ascent ending where the path is level (gam = 0), the descent where h = 0, every state and R continuous between
them; each phase lasts 1 to 100 s. Maximize the range r at impact. Dymos' test asserts 3183.25 m (within 1%).

Dymos reads the air density from a table of the 1976 standard atmosphere; the ball stays below 1 km, where that
table is the troposphere's closed form used here, rho = 1.225 (1 - h / 44330.8)^4.2559 kg/m^3.

The guess is Dymos' own, a straight line in each phase (ascent: r and h from 0 to 100 m, v from 200 to 150 m/s,
gam from 25 deg to 0; descent: r from 100 to 200 m, h from 100 m to 0, v from 150 to 200 m/s, gam from 0 to
-45 deg; R = 0.05 m). The straight line between the stated ends puts the speed at 0, where gam' is not a number,
and the engine then stops at once saying so.
Run: python examples/phases/cannonball.py
"""

import math

import casadi as ca
import numpy as np

from convexguid.ocp import Phases, Problem

PUBLISHED = 3183.25
SOURCE = "OpenMDAO Dymos, examples/cannonball, two-phase cannonball (test of connected initial states)"
FIGURE = "range at impact r(tf) [m]"

GRAVITY, DRAG_COEFFICIENT, IRON_DENSITY, MUZZLE_ENERGY = 9.80665, 0.5, 7870.0, 400e3


def air_density(h):
    """The 1976 standard atmosphere's troposphere, kg/m^3 (h in m)."""
    return 1.225 * (1.0 - h / 44330.8) ** 4.2559


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["r"]


def flight_phase(name: str, intervals: int, start: tuple, end: tuple, initial=None, final=None):
    """One phase of the flight, its range, its speed and the ball's mass; ``start`` and ``end`` the guessed
    (r, h, v, gam) at its ends, ``initial`` and ``final`` the values it states there."""
    initial, final = initial or {}, final or {}
    p = Problem(name)
    r = p.state("r", initial=initial.get("r"), unit="m")
    h = p.state("h", initial=initial.get("h"), final=final.get("h"), unit="m")
    v = p.state("v", unit="m/s")
    gam = p.state("gam", final=final.get("gam"), unit="rad")
    radius = p.parameter("radius", bounds=(0.01, 0.1), guess=0.05)
    mass = 4.0 / 3.0 * math.pi * radius**3 * IRON_DENSITY
    drag = 0.5 * air_density(h) * v**2 * math.pi * radius**2 * DRAG_COEFFICIENT
    p.dynamics({r: v * ca.cos(gam), h: v * ca.sin(gam), v: -drag / mass - GRAVITY * ca.sin(gam),
                gam: -GRAVITY * ca.cos(gam) / v})
    p.final_time(bounds=(1.0, 100.0), guess=10.0)
    p.transcription(intervals)
    share = np.linspace(0.0, 1.0, intervals + 1)[:, None]
    ends = np.array(start + (0.05,)), np.array(end + (0.05,))
    p.initial_guess(ends[0] + share * (ends[1] - ends[0]), np.zeros((intervals + 1, 0)))
    return p, r, v, mass


def build(intervals: int = 25) -> Phases:
    """``intervals`` Hermite-Simpson intervals per phase."""
    level, dive = 0.0, math.radians(-45.0)
    ascent, _, v, mass = flight_phase("ascent", intervals, (0.0, 0.0, 200.0, math.radians(25.0)),
                                      (100.0, 100.0, 150.0, level), initial={"r": 0.0, "h": 0.0},
                                      final={"gam": level})
    descent, r, _, _ = flight_phase("descent", intervals, (100.0, 100.0, 150.0, level), (200.0, 0.0, 200.0, dive),
                                    final={"h": 0.0})
    ascent.point_constraint("muzzle_energy", (0.5 * mass * v**2 - MUZZLE_ENERGY) / MUZZLE_ENERGY, at=0.0)
    descent.minimize_terminal(-r)
    flight = Phases("cannonball", [ascent, descent])
    flight.connect(ascent, descent)  # r, h, v, gam and the radius
    return flight


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, f"range {-solution.objective:.3f} m")
