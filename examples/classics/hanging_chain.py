"""COPS hanging chain: the shape of least potential energy of a uniform chain of given length hung between two
points.

E. D. Dolan, J. J. More, T. S. Munson, "Benchmarking optimization software with COPS 3.0", Argonne ANL/MCS-TM-273
(2004), problem "Hanging chain". The chain's height x over the horizontal coordinate t in [0, 1], its slope u the
control; the potential energy E and the length s are integrals, carried as states:

    x' = u,  E' = x sqrt(1 + u^2),  s' = sqrt(1 + u^2),
    x(0) = a = 1, x(1) = b = 3;  E(0) = 0;  s(0) = 0, s(1) = L = 4;  minimise E(1).

Published: E = 5.06852 (COPS). Stated with the default Hermite-Simpson control, quadratic through node, midpoint
and node: the collocation then has a spurious optimum (IPOPT stops on it at E = 4.93, below the true minimum) whose
slope zigzags near the end where the chain is steep, and the length it integrates is not the flown one; the dense
check catches it and the repair holds the slope linear between node values (see docs/ocp.md, "Repairs").
Run: python examples/classics/hanging_chain.py
"""

import casadi as ca

from convexguid.ocp import Problem

PUBLISHED = 5.06852
SOURCE = "Dolan, More & Munson, COPS 3.0 (ANL/MCS-TM-273, 2004), hanging chain"
FIGURE = "potential energy E(1)"

A, B, LENGTH = 1.0, 3.0, 4.0


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["E"]


def build(intervals: int = 50) -> Problem:
    p = Problem("cops-hanging-chain")
    x = p.state("x", initial=A, final=B)
    energy = p.state("E", initial=0.0)
    length = p.state("s", initial=0.0, final=LENGTH)
    u = p.control("u")
    p.dynamics({x: u, energy: x * ca.sqrt(1 + u**2), length: ca.sqrt(1 + u**2)})
    p.final_time(fixed=1.0)
    p.minimize_terminal(energy)
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
