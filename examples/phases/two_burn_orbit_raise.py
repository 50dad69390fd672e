"""A two-burn orbit raise: burn, coast, burn from a circular orbit of radius 1 to one of radius 3, least delta-v.

Dymos' finite-burn orbit raise (OpenMDAO/dymos, ``examples/finite_burn_orbit_raise``; after J. M. Longuski's
and P. J. Enright and B. A. Conway's finite-thrust transfers), in canonical units (mu = 1): its documented
delta-v is 0.3995 (within 2e-3 in its tests). The impulsive Hohmann transfer needs 0.3938; the finite burns
lose a little to gravity.

Polar states r, theta, v_r, v_t; the thrust acceleration a grows as mass burns (a' = a^2 / c, exhaust speed
c = 1.5, a = 0.1 at the start) and the delta-v is its integral. The thrust points at the angle u above the local
horizontal:

    r' = v_r,  theta' = v_t / r,  v_r' = v_t^2 / r - 1 / r^2 + a sin u,  v_t' = -v_r v_t / r + a cos u.

Phase ``burn1`` (|u| <= 30 deg, 0.5 to 10 time units) from (1, 0, 0, 1); phase ``coast`` (no thrust, no control,
0.5 to 50 units); phase ``burn2`` (u free: a periodic control, 0.5 to 10 units) to r = 3 on a circular orbit
(v_r = 0, v_t = sqrt(1/3)). The position and velocity are continuous through the three phases; the engine's
acceleration and the delta-v carry from the first burn to the second (the coast does not have them).
Run: python examples/phases/two_burn_orbit_raise.py
"""

import math

import casadi as ca

from convexguid.ocp import Phases, Problem

PUBLISHED = 0.3995
SOURCE = "OpenMDAO/dymos, examples/finite_burn_orbit_raise (two-burn orbit raise), delta-v 0.3995"
FIGURE = "delta-v [DU/TU]"

EXHAUST_SPEED = 1.5
R_TARGET = 3.0


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["deltav"]


def orbit(p: Problem, initial: dict | None = None, final: dict | None = None):
    """The polar states of ``p`` (with the ``initial`` and ``final`` values it fixes) and their gravity-only rates."""
    initial, final = initial or {}, final or {}
    r = p.state("r", bounds=(0.5, 5.0), initial=initial.get("r"), final=final.get("r"), unit="DU")
    theta = p.state("theta", bounds=(0.0, 4 * math.pi), initial=initial.get("theta"), unit="rad")
    vr = p.state("vr", bounds=(-2.0, 2.0), initial=initial.get("vr"), final=final.get("vr"), unit="DU/TU")
    vt = p.state("vt", bounds=(0.0, 2.0), initial=initial.get("vt"), final=final.get("vt"), unit="DU/TU")
    rates = {r: vr, theta: vt / r, vr: vt**2 / r - 1 / r**2, vt: -vr * vt / r}
    return (r, theta, vr, vt), rates


def burn(name: str, angle_bounds, intervals: int, exhaust_speed: float, initial: dict | None = None,
         final: dict | None = None):
    """A burn arc: the orbit, the thrust acceleration and delta-v as states, the thrust angle as the control."""
    p = Problem(name)
    (r, theta, vr, vt), rates = orbit(p, initial, final)
    initial = initial or {}
    accel = p.state("accel", bounds=(0.0, 1.0), initial=initial.get("accel"), unit="DU/TU^2")
    deltav = p.state("deltav", bounds=(0.0, 2.0), initial=initial.get("deltav"), unit="DU/TU")
    u = (p.control("u", bounds=angle_bounds, unit="rad") if angle_bounds is not None
         else p.control("u", period=2 * math.pi, unit="rad"))
    rates[vr] += accel * ca.sin(u)
    rates[vt] += accel * ca.cos(u)
    p.dynamics({**rates, accel: accel**2 / exhaust_speed, deltav: accel})
    p.final_time(bounds=(0.5, 10.0), guess=2.0)
    p.transcription(intervals)
    return p, deltav


def build(intervals: int = 20, r_target: float = R_TARGET, exhaust_speed: float = EXHAUST_SPEED) -> Phases:
    """The transfer to a circular orbit of radius ``r_target`` with the engine's ``exhaust_speed`` (the published
    case: 3 and 1.5)."""
    limit = math.radians(30.0)
    burn1, _ = burn("burn1", (-limit, limit), intervals, exhaust_speed,
                    initial={"r": 1.0, "theta": 0.0, "vr": 0.0, "vt": 1.0, "accel": 0.1, "deltav": 0.0})
    coast = Problem("coast")
    _, rates = orbit(coast)
    coast.dynamics(rates)
    coast.final_time(bounds=(0.5, 50.0), guess=3.0)
    coast.transcription(intervals)
    burn2, deltav = burn("burn2", None, intervals, exhaust_speed,
                         final={"r": r_target, "vr": 0.0, "vt": math.sqrt(1 / r_target)})
    burn2.minimize_terminal(deltav)
    transfer = Phases("two-burn-orbit-raise", [burn1, coast, burn2])
    transfer.connect(burn1, coast)
    transfer.connect(coast, burn2)
    transfer.connect(burn1, burn2, ["accel", "deltav"])
    return transfer


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
