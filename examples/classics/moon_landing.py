"""A soft landing with the least propellant: vertical descent under constant gravity, thrust acceleration bounded.

After J. S. Meditch, "On the problem of optimal thrust programming for a lunar soft landing", IEEE Transactions on
Automatic Control 9(4), 1964, with the mass held constant so that the optimum has a closed form. Height h, speed v,
the propellant used J (the integral of the thrust acceleration u):

    h' = v,  v' = -g + u,  J' = u,  0 <= u <= u_max,  h >= 0,
    from h = 10, v = -2 to h = 0, v = 0, free final time;  minimise J(tf),   g = 1.5, u_max = 3.

The optimum falls freely, then brakes at full thrust (net deceleration u_max - g) to touch down at rest. The switch
is where the free fall's speed, v^2 = v0^2 + 2 g (h0 - h), meets the braking parabola, v^2 = 2 (u_max - g) h: there
h = 17/3 and |v| = sqrt(17), and the burn lasts sqrt(17) / 1.5, so J = u_max sqrt(17) / 1.5 = 2 sqrt(17) = 8.246211.
Run: python examples/classics/moon_landing.py
"""

import math

from convexguid.ocp import Problem

GRAVITY, MAX_THRUST = 1.5, 3.0
H_0, V_0 = 10.0, -2.0
BRAKING = MAX_THRUST - GRAVITY
SWITCH_HEIGHT = (V_0**2 + 2 * GRAVITY * H_0) / (2 * BRAKING + 2 * GRAVITY)
PUBLISHED = MAX_THRUST * math.sqrt(2 * BRAKING * SWITCH_HEIGHT) / BRAKING  # = 2 sqrt(17)
SOURCE = "Meditch, IEEE Trans. Automatic Control 9(4), 1964 (constant mass): closed form 2 sqrt(17)"
FIGURE = "propellant J(tf) (velocity change)"


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["J"]


def build(intervals: int = 50) -> Problem:
    p = Problem("moon-landing")
    h = p.state("h", bounds=(0.0, None), initial=H_0, final=0.0)
    v = p.state("v", initial=V_0, final=0.0)
    used = p.state("J", initial=0.0)
    u = p.control("u", bounds=(0.0, MAX_THRUST))
    p.dynamics({h: v, v: -GRAVITY + u, used: u})
    p.final_time(bounds=(0.1, 20.0), guess=5.0)
    p.minimize_terminal(used)
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
