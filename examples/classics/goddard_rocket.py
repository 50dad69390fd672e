"""Goddard's rocket as COPS 3.0 states it: the highest climb with a given propellant, drag and inverse-square
gravity, free final time.

E. D. Dolan, J. J. More, T. S. Munson, "Benchmarking optimization software with COPS 3.0", Argonne National
Laboratory, ANL/MCS-TM-273, 2004, problem "Goddard rocket" (nondimensional; after H. Seywald and E. M. Cliff, 1992).

States: altitude h, speed v, mass m; control: the thrust T in [0, T_max]. With drag
D(h, v) = D_c v^2 exp(-h_c (h - h_0) / h_0) and gravity g(h) = g_0 (h_0 / h)^2:

    h' = v,  v' = (T - D(h, v)) / m - g(h),  m' = -T / c,

from h(0) = h_0 = 1, v(0) = v_0 = 0, m(0) = m_0 = 1 to m(tf) = m_c m_0, with h >= h_0, v >= 0 and
m_c m_0 <= m <= m_0; maximize h(tf). Constants: g_0 = 1, T_c = 3.5, h_c = 500, v_c = 620, m_c = 0.6, and
c = 0.5 sqrt(g_0 h_0), D_c = 0.5 v_c m_0 / g_0, T_max = T_c g_0 m_0. Published: h(tf) = 1.01283 (COPS's
trapezoidal discretization at 100 to 400 intervals; tf near 0.199). The optimal thrust is full, then singular
(a thrust that follows the drag), then off; the control is linear between node values (``control="linear"``, the
way COPS holds it at the nodes): Hermite-Simpson's quadratic control chatters along the singular arc (on 50
intervals node values alternate between about 3.4 and 1.2), for the same h(tf) to 3e-6.
Run: python examples/classics/goddard_rocket.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

PUBLISHED = 1.01283
SOURCE = "Dolan, More & Munson, COPS 3.0 (ANL/MCS-TM-273, 2004), Goddard rocket"
FIGURE = "final altitude h(tf) [h_0]"

H_0, V_0, M_0, G_0 = 1.0, 0.0, 1.0, 1.0
T_C, H_C, V_C, M_C = 3.5, 500.0, 620.0, 0.6
C = 0.5 * math.sqrt(G_0 * H_0)  # exhaust speed
D_C = 0.5 * V_C * M_0 / G_0
T_MAX = T_C * G_0 * M_0


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["h"]


def build(intervals: int = 50, control: str = "linear") -> Problem:
    p = Problem("cops-goddard-rocket")
    h = p.state("h", bounds=(H_0, None), initial=H_0)
    v = p.state("v", bounds=(0.0, None), initial=V_0)
    m = p.state("m", bounds=(M_C * M_0, M_0), initial=M_0, final=M_C * M_0)
    thrust = p.control("T", bounds=(0.0, T_MAX))
    drag = D_C * v**2 * ca.exp(-H_C * (h - H_0) / H_0)
    p.dynamics({h: v, v: (thrust - drag) / m - G_0 * (H_0 / h) ** 2, m: -thrust / C})
    p.final_time(bounds=(0.01, 1.0), guess=1.0)  # COPS starts from tf = 1
    p.minimize_terminal(-h)
    p.transcription(intervals, control=control)  # Hermite-Simpson
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
