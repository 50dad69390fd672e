"""Goddard's rocket in three phases, the middle one a singular arc: full thrust, a thrust that follows the drag,
then a coast, each a phase of its own and the three joined at their ends.

J. T. Betts, Practical Methods for Optimal Control and Estimation Using Nonlinear Programming, 2nd ed., SIAM
2010, Sec. 4.14 (the Goddard rocket): maximum final altitude h(tf) = 18550.872 ft.

A sounding rocket climbs vertically from rest at sea level against drag D = sigma v^2 exp(-h / h_0) and constant
gravity, burning from 3 to 1 slug of mass:

    h' = v,  v' = (T - D) / m - g,  m' = -T / c.

The optimal thrust is bang-singular-bang. Phase ``boost``: T = T_m; phase ``singular``: T between 1% and 99% of
T_m with the singular-arc condition m g - (1 + v / c) D = 0 along it (a path equality); phase ``coast``: T = 0,
ending with all the propellant burnt (m = 1 slug). Every duration is free, and h, v, m are continuous where the
phases meet. Constants: T_m = 193.044 lbf, g = 32.174 ft/s^2, sigma = 5.4915348e-5 slug/ft, c = 1580.9425 ft/s,
h_0 = 23800 ft. Boost and coast have no control: their thrust is a constant of the dynamics.
Run: python examples/phases/goddard_three_phase.py
"""

import casadi as ca
import numpy as np

from convexguid.ocp import Phases, Problem

PUBLISHED = 18550.872
SOURCE = "Betts, Practical Methods for Optimal Control..., 2nd ed. (2010), Sec. 4.14, Goddard rocket in three phases"
FIGURE = "final altitude h(tf) [ft]"

T_M, G, SIGMA, C, H_0 = 193.044, 32.174, 5.49153484923381010e-05, 1580.9425279876559, 23800.0
M_0, M_F = 3.0, 1.0


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["h"]


def drag(h, v):
    return SIGMA * v**2 * ca.exp(-h / H_0)


def phase(name: str, thrust: tuple[float, float], intervals: int, initial: dict | None = None,
          final: dict | None = None):
    """One arc: its states (the same in all three, with the ``initial`` and ``final`` values it fixes), its thrust
    (a control between the two bounds of ``thrust``, or their value when they agree) and the dynamics."""
    initial, final = initial or {}, final or {}
    p = Problem(name)
    h = p.state("h", bounds=(0.0, 20000.0), initial=initial.get("h"), final=final.get("h"), unit="ft")
    v = p.state("v", bounds=(0.0, 10000.0), initial=initial.get("v"), final=final.get("v"), unit="ft/s")
    m = p.state("m", bounds=(M_F, M_0), initial=initial.get("m"), final=final.get("m"), unit="slug")
    low, high = thrust
    force = p.control("T", bounds=(low, high), unit="lbf") if low < high else low
    p.dynamics({h: v, v: (force - drag(h, v)) / m - G, m: -force / C})
    p.final_time(bounds=(0.1, 60.0), guess=15.0)
    # the thrust linear between node values: a quadratic one chatters along the singular arc, whose state equality
    # leaves the midpoint values free
    p.transcription(intervals, control="linear")
    return p, (h, v, m)


def build(intervals: int = 20) -> Phases:
    boost, _ = phase("boost", (T_M, T_M), intervals, initial={"h": 0.0, "v": 0.0, "m": M_0})
    singular, (h, v, m) = phase("singular", (0.01 * T_M, 0.99 * T_M), intervals)
    coast, (h_end, _, _) = phase("coast", (0.0, 0.0), intervals, final={"m": M_F})
    singular.path_equality("singular_arc", m * G - (1 + v / C) * drag(h, v), unit="lbf")
    coast.minimize_terminal(-h_end)
    for k, p in enumerate((boost, singular, coast)):
        # a guess as the published solutions start (every phase 15 s, 6000 ft a phase, mass burnt evenly): the
        # straight line knows no altitude beyond h(0) = 0
        share = np.linspace(0.0, 1.0, intervals + 1)[:, None]
        h, m = 6000.0 * (k + share), M_0 - 2 / 3 * (k + share)
        p.initial_guess(np.hstack([h, np.full_like(h, 500.0), m]),
                        np.full((intervals + 1, len(p.controls)), T_M * (2 - k) / 2))
    flight = Phases("goddard-three-phase", [boost, singular, coast])
    flight.connect(boost, singular)
    flight.connect(singular, coast)
    return flight


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, -solution.objective)
