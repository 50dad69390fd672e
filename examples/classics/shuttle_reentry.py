"""The Space Shuttle's reentry at maximum crossrange (no heating limit): the most final latitude from an equatorial
entry heading east.

J. T. Betts, Practical Methods for Optimal Control and Estimation Using Nonlinear Programming, 2nd ed., SIAM 2010,
Example 6.1 (pp. 247-251), the case without the heating constraint.

States: altitude h, longitude phi, latitude theta, speed v, flight path angle gamma, azimuth psi; controls: angle of
attack alpha and bank angle beta. With r = R_e + h, g = mu / r^2, rho = rho_0 exp(-h / h_r), lift and drag
L, D = 1/2 (c_L, c_D) S rho v^2, c_L = a_0 + a_1 alpha_deg, c_D = b_0 + b_1 alpha_deg + b_2 alpha_deg^2 and
m = w / g_0:

    h' = v sin gamma,                    phi' = v cos gamma sin psi / (r cos theta),
    theta' = v cos gamma cos psi / r,    v' = -D / m - g sin gamma,
    gamma' = L cos beta / (m v) + cos gamma (v / r - g / v),
    psi' = L sin beta / (m v cos gamma) + v cos gamma sin psi sin theta / (r cos theta),

from h = 260000 ft, phi = theta = 0, v = 25600 ft/s, gamma = -1 deg, psi = 90 deg to h = 80000 ft, v = 2500 ft/s,
gamma = -5 deg (phi, theta, psi and tf free), with -90 <= alpha <= 90 deg, -90 <= beta <= 1 deg and
|theta|, |gamma| <= 89 deg; maximize theta(tf). Constants: w = 203000 lb, g_0 = 32.174 ft/s^2, S = 2690 ft^2,
rho_0 = 0.002378 slug/ft^3, h_r = 23800 ft, mu = 0.14076539e17 ft^3/s^2, R_e = 20902900 ft, a_0 = -0.20704,
a_1 = 0.029244, b_0 = 0.07854, b_1 = -0.61592e-2, b_2 = 0.621408e-3. Published: theta(tf) = 34.1412 deg
(tf = 2008.59 s).

Stated in scaled units so the numbers stay near 1: altitude in 1e5 ft, speed in 1e4 ft/s, angles in radians,
time in seconds. ``build(heating_limit=70)`` adds the example's heating constraint on the wing's leading edge
(shuttle_reentry_heating.py).
Run: python examples/classics/shuttle_reentry.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

PUBLISHED = 34.1412
SOURCE = "Betts, Practical Methods for Optimal Control..., 2nd ed., SIAM 2010, Example 6.1 (no heating limit)"
FIGURE = "final latitude theta(tf) [deg]"

FT, FPS = 1e5, 1e4  # the units of altitude [ft] and of speed [ft/s]
MASS = 203000.0 / 32.174  # slug
AREA, RHO_0, H_R = 2690.0, 0.002378, 23800.0  # ft^2, slug/ft^3, ft
MU, R_E = 0.14076539e17, 20902900.0  # ft^3/s^2, ft
A_0, A_1 = -0.20704, 0.029244
B_0, B_1, B_2 = 0.07854, -0.61592e-2, 0.621408e-3
DEG = math.pi / 180


def figure(final_state: dict[str, float], final_time: float) -> float:
    return math.degrees(final_state["theta"])


def heating_rate(altitude, speed, alpha_deg):
    """Betts' heating rate on the wing's leading edge, BTU/ft^2/s: q = q_a q_r, q_r = 17700 sqrt(rho) (1e-4 v)^3.07
    and q_a a cubic in the angle of attack in degrees (altitude in ft, speed in ft/s)."""
    q_r = 17700.0 * ca.sqrt(RHO_0 * ca.exp(-altitude / H_R)) * (1e-4 * speed) ** 3.07
    q_a = 1.0672181 - 0.19213774e-1 * alpha_deg + 0.21286289e-3 * alpha_deg**2 - 0.10117249e-5 * alpha_deg**3
    return q_a * q_r


def build(intervals: int = 50, control: str = "quadratic", heating_limit: float | None = None) -> Problem:
    p = Problem("betts-shuttle-reentry")
    h = p.state("h", bounds=(0.0, None), initial=260000 / FT, final=80000 / FT, unit="1e5 ft")
    phi = p.state("phi", initial=0.0, scale=1.0, unit="rad")
    theta = p.state("theta", bounds=(-89 * DEG, 89 * DEG), initial=0.0, unit="rad")
    v = p.state("v", bounds=(0.0, None), initial=25600 / FPS, final=2500 / FPS, unit="1e4 ft/s")
    gamma = p.state("gamma", bounds=(-89 * DEG, 89 * DEG), initial=-1 * DEG, final=-5 * DEG, unit="rad")
    psi = p.state("psi", initial=90 * DEG, unit="rad")
    alpha = p.control("alpha", bounds=(-90 * DEG, 90 * DEG), unit="rad")
    beta = p.control("beta", bounds=(-90 * DEG, 1 * DEG), unit="rad")
    altitude, speed = h * FT, v * FPS  # ft, ft/s
    r = R_E + altitude
    g = MU / r**2
    alpha_deg = alpha / DEG
    pressure_area = 0.5 * RHO_0 * ca.exp(-altitude / H_R) * speed**2 * AREA
    lift = (A_0 + A_1 * alpha_deg) * pressure_area
    drag = (B_0 + B_1 * alpha_deg + B_2 * alpha_deg**2) * pressure_area
    p.dynamics({
        h: speed * ca.sin(gamma) / FT,
        phi: speed * ca.cos(gamma) * ca.sin(psi) / (r * ca.cos(theta)),
        theta: speed * ca.cos(gamma) * ca.cos(psi) / r,
        v: (-drag / MASS - g * ca.sin(gamma)) / FPS,
        gamma: lift * ca.cos(beta) / (MASS * speed) + ca.cos(gamma) * (speed / r - g / speed),
        psi: (lift * ca.sin(beta) / (MASS * speed * ca.cos(gamma))
              + speed * ca.cos(gamma) * ca.sin(psi) * ca.sin(theta) / (r * ca.cos(theta))),
    })
    if heating_limit is not None:  # BTU/ft^2/s, held in its own unit
        p.path_constraint("heating", heating_rate(altitude, speed, alpha_deg) / heating_limit - 1.0)
    p.final_time(bounds=(100.0, 4000.0), guess=1000.0)
    p.minimize_terminal(-theta)
    p.transcription(intervals, control=control)  # Hermite-Simpson
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
