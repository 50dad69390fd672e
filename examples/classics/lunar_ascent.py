"""A single-stage ascent from the Moon's surface to a circular-orbit insertion point in the least time: a flat Moon, no
atmosphere, constant thrust, the pitch angle theta the control.

Bryson & Ho, Applied Optimal Control (1975), Sec. 2.7 (launch into orbit over a flat planet), with the constants of
OpenMDAO Dymos' lunar ascent examples (ssto_moon_linear_tangent): g = 1.61544 m/s^2, thrust F = 3 g m0 with
m0 = 50000 kg, Isp = 1e6 s (the mass barely changes). Positions x, y [m], velocities vx, vy [m/s], mass m [kg]:

    x' = vx,  y' = vy,  vx' = F cos(theta) / m,  vy' = F sin(theta) / m - g,  m' = -F / (g Isp),

from rest at the origin to y = 185 km, vx = 1627 m/s, vy = 0 (x free); x, y, vx >= 0; minimize tf.
In a uniform field the optimal pitch follows the linear tangent law, tan(theta) = tan(theta0) - c t, whatever
the thrust history (Bryson & Ho, Sec. 2.7). Its two constants and tf are found here by shooting (SciPy's DOP853 at
rtol 1e-12 and a root finder on the three final conditions): that continuous optimum is the reference, computed
independently of any transcription. Dymos' notebooks check 481 s within 1%.
Run: python examples/classics/lunar_ascent.py
"""

import math

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from convexguid.ocp import Problem

GRAVITY, MASS_0, ISP = 1.61544, 50000.0, 1.0e6
THRUST = 3.0 * MASS_0 * GRAVITY
ALTITUDE, ORBITAL_SPEED = 1.85e5, 1627.0


def linear_tangent_optimum() -> float:
    """The minimum time by the linear tangent law: tan(theta0), c and tf that reach the three final conditions."""
    def rates(t, s, tan0, c):
        theta = math.atan(tan0 - c * t)
        acceleration = THRUST / s[4]
        return [s[2], s[3], acceleration * math.cos(theta), acceleration * math.sin(theta) - GRAVITY,
                -THRUST / (GRAVITY * ISP)]

    def misses(unknowns):
        tan0, c, tf = unknowns
        end = solve_ivp(rates, (0.0, tf), [0.0, 0.0, 0.0, 0.0, MASS_0], args=(tan0, c), method="DOP853",
                        rtol=1e-12, atol=1e-9).y[:, -1]
        return [(end[1] - ALTITUDE) / ALTITUDE, (end[2] - ORBITAL_SPEED) / ORBITAL_SPEED, end[3] / ORBITAL_SPEED]

    unknowns, _, found, message = fsolve(misses, [1.5, 0.005, 480.0], xtol=1e-13, full_output=True)
    if found != 1 or np.max(np.abs(misses(unknowns))) > 1e-10:
        raise RuntimeError(f"the linear tangent law's shooting did not converge: {message}")
    return float(unknowns[2])


PUBLISHED = linear_tangent_optimum()  # 481.7168 s
SOURCE = ("Bryson & Ho, Applied Optimal Control (1975), Sec. 2.7, with Dymos' lunar ascent constants: the linear "
          "tangent law solved by shooting")
FIGURE = "final time tf [s]"


def build(intervals: int = 50) -> Problem:
    p = Problem("lunar-ascent")
    x = p.state("x", bounds=(0.0, None), initial=0.0, unit="m")
    y = p.state("y", bounds=(0.0, None), initial=0.0, final=ALTITUDE, unit="m")
    vx = p.state("vx", bounds=(0.0, None), initial=0.0, final=ORBITAL_SPEED, unit="m/s")
    vy = p.state("vy", initial=0.0, final=0.0, unit="m/s")
    m = p.state("m", initial=MASS_0, unit="kg")
    theta = p.control("theta", unit="rad")
    p.dynamics({x: vx, y: vy, vx: THRUST * ca.cos(theta) / m, vy: THRUST * ca.sin(theta) / m - GRAVITY,
                m: -THRUST / (GRAVITY * ISP)})
    p.final_time(bounds=(10.0, 1000.0), guess=500.0)
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.figures.final_time_s, PUBLISHED)
