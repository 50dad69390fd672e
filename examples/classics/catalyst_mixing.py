"""COPS 3.0 catalyst mixing: the mix of two catalysts along a tubular plug-flow reactor that converts the most of A.

E. D. Dolan, J. J. More, T. S. Munson, Benchmarking Optimization Software with COPS 3.0, ANL/MCS-TM-273,
Argonne National Laboratory, 2004, problem "catmix" (after D. J. Gunn, W. J. Thomas, Chem. Eng. Sci. 20, 1965,
and O. von Stryk's statement). With u the share of the first catalyst, on 0 <= t <= 1:

    x1' = u (10 x2 - x1),    x2' = u (x1 - 10 x2) - (1 - u) x2,    x1(0) = 1, x2(0) = 0,    0 <= u <= 1,
    minimise -1 + x1(1) + x2(1)   (the conversion 1 - x1(1) - x2(1), negated).

COPS reports -4.8055e-2 (its smoothing weight alpha is 0: no control-rate term). The optimal u is
bang-singular-bang: 1 until t ~ 0.14, a singular arc at u ~ 0.227, then 0 from t ~ 0.73. On the singular arc
Hermite-Simpson's quadratic control chatters between node and midpoint values and beats the published value
(-0.048086 on 50 intervals, by IPOPT), so the control is held linear between the nodes instead: -0.0480552 on 50
intervals, -0.0480557 on 200.
Run: python examples/classics/catalyst_mixing.py
"""

from convexguid.ocp import Problem

PUBLISHED = -0.048055
SOURCE = "Dolan, More & Munson, COPS 3.0, ANL/MCS-TM-273 (2004), catalyst mixing"
FIGURE = "-1 + x1(tf) + x2(tf) (minus the conversion)"


def figure(final_state: dict[str, float], final_time: float) -> float:
    return -1.0 + final_state["x1"] + final_state["x2"]


def build(intervals: int = 50) -> Problem:
    p = Problem("cops-catalyst-mixing")
    x1 = p.state("x1", initial=1.0)
    x2 = p.state("x2", initial=0.0)
    u = p.control("u", bounds=(0.0, 1.0))
    p.dynamics({x1: u * (10 * x2 - x1), x2: u * (x1 - 10 * x2) - (1 - u) * x2})
    p.final_time(fixed=1.0)
    p.minimize_terminal(-1 + x1 + x2)
    p.transcription(intervals, control="linear")
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
