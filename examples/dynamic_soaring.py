"""Dynamic soaring: the weakest wind shear in which a glider can fly a closed loop without losing energy.

Y. J. Zhao, Optimal patterns of glider dynamic soaring, Optimal Control Applications and Methods 25(2), 2004,
67-89, as GPOPS-II states it (Patterson & Rao, ACM TOMS 41(1), 2014, its dynamic soaring example). A point-mass
glider (5.6 slug, 45.09703 ft^2, C_D = 0.00873 + 0.045 C_L^2, sea-level air) in a horizontal wind that grows
linearly with height, W = beta h. Its states: position x, y, h [ft], airspeed v [ft/s], path angle gamma and
heading psi [rad]; its controls: lift coefficient C_L in [0, 1.5] and bank angle phi within 75 deg; beta is a
parameter, the objective. With W' = beta h':

    x' = v cos(gamma) sin(psi) + beta h,     y' = v cos(gamma) cos(psi),     h' = v sin(gamma),
    m v' = -D - m g sin(gamma) - m W' cos(gamma) sin(psi),
    m v gamma' = L cos(phi) - m g cos(gamma) + m W' sin(gamma) sin(psi),
    m v cos(gamma) psi' = L sin(phi) - m W' cos(psi),

the load factor L / (m g) within [-2, 5], the loop from and back to the origin on the ground (h >= 0), the speed and
path angle periodic and the heading one turn less at the end: one phase whose periodic conditions are links on its
own ends (:class:`~convexguid.ocp.Phases`).

The glider takes off from and lands on its bound h = 0: the collocation's first plan lands climbing and crosses the
ground between its last two nodes, which the repair mends by holding the landing's rate into the bounds
(docs/ocp.md, "What the engine does with it"). Measured on this machine from the straight-line guess, 40
intervals (python -m convexguid.benches.ocp_examples): the first solve reaches beta = 0.063736 1/s (0.063641,
the optimum IPOPT finds from GPOPS-II's circular guess, before the airspeed and height bounds were held between
the nodes too); IPOPT from the straight line stops at another local optimum, 0.063692. After seven repair rounds
(57 intervals, the landing's rate conditions, margins on the load factor) the verified plan needs 0.063735, after
297 SCP iterations (253 to 257 with earlier end-game rules). With the glider's constants moved by 1e-12 it
ended at the same beta to 1e-11 (446 to 582 SCP iterations against 401, measured before the penalty's steering of
docs/engine.md). The value 0.0797 often quoted for this problem was not reproduced here, by either solver.
Run: python examples/dynamic_soaring.py
"""

import math

import casadi as ca

from convexguid.ocp import Phases, Problem

DENSITY, CD0, INDUCED, GRAVITY, MASS, AREA = 0.002378, 0.00873, 0.045, 32.2, 5.6, 45.09703
MAX_ANGLE = math.radians(75.0)


def build(intervals: int = 40) -> Phases:
    p = Problem("soaring")
    x = p.state("x", bounds=(-1000.0, 1000.0), initial=0.0, final=0.0, unit="ft")
    y = p.state("y", bounds=(-1000.0, 1000.0), initial=0.0, final=0.0, unit="ft")
    h = p.state("h", bounds=(0.0, 1000.0), initial=0.0, final=0.0, unit="ft")
    v = p.state("v", bounds=(10.0, 350.0), unit="ft/s")
    gamma = p.state("gamma", bounds=(-MAX_ANGLE, MAX_ANGLE), unit="rad")
    psi = p.state("psi", bounds=(-3 * math.pi, math.pi / 2), unit="rad")
    beta = p.parameter("beta", bounds=(0.005, 0.15), guess=0.1)
    lift_coefficient = p.control("CL", bounds=(0.0, 1.5))
    bank = p.control("phi", bounds=(-MAX_ANGLE, MAX_ANGLE), unit="rad")

    dynamic_pressure = 0.5 * DENSITY * v**2
    lift = dynamic_pressure * AREA * lift_coefficient
    drag = dynamic_pressure * AREA * (CD0 + INDUCED * lift_coefficient**2)
    climb = v * ca.sin(gamma)
    wind_rate = beta * climb
    p.dynamics({
        x: v * ca.cos(gamma) * ca.sin(psi) + beta * h,
        y: v * ca.cos(gamma) * ca.cos(psi),
        h: climb,
        v: -drag / MASS - GRAVITY * ca.sin(gamma) - wind_rate * ca.cos(gamma) * ca.sin(psi),
        gamma: (lift * ca.cos(bank) - MASS * GRAVITY * ca.cos(gamma)
                + MASS * wind_rate * ca.sin(gamma) * ca.sin(psi)) / (MASS * v),
        psi: (lift * ca.sin(bank) - MASS * wind_rate * ca.cos(psi)) / (MASS * v * ca.cos(gamma)),
    })
    load_factor = lift / (MASS * GRAVITY)
    p.path_constraint("load_factor_max", load_factor - 5.0)
    p.path_constraint("load_factor_min", -2.0 - load_factor)
    p.final_time(bounds=(10.0, 30.0), guess=24.0)
    p.minimize_terminal(beta)
    p.transcription(intervals)

    loop = Phases("dynamic-soaring", [p])
    loop.link("speed_periodic", p.end(v) - p.start(v))
    loop.link("path_angle_periodic", p.end(gamma) - p.start(gamma))
    loop.link("one_turn", p.end(psi) - p.start(psi) + 2 * math.pi)
    return loop


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.figures.parameters["beta"])
