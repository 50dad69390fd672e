"""IPOPT (exact Hessian, through CasADi) on the same transcribed NLP the SCP solves: the independent answer a
user's problem is checked against (tests/test_ocp.py)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.ocp.transcription import Transcription


@dataclass(frozen=True)
class IpoptAnswer:
    """IPOPT's solution of the program: success, its objective (the program's), the point, IPOPT's status."""

    success: bool
    objective: float
    z: np.ndarray
    status: str
    setup_s: float = 0.0
    """CasADi's building of the NLP and of IPOPT's interface (its exact Hessian included), s."""
    solve_s: float = 0.0
    iterations: int = 0


def solve_with_ipopt(program: Transcription, z0: np.ndarray | None = None, tol: float = 1e-10) -> IpoptAnswer:
    """Minimise the program's objective (linear cost plus weighted squared residuals) subject to its defects, path
    constraints (with their margins), cones, objective epigraph and linear constraints, from ``z0``
    (default: its guess)."""
    started = time.perf_counter()
    nlp = program.symbolic_nlp()
    z, objective = nlp.z, nlp.objective
    blocks = [(expression, lower, upper) for _, expression, lower, upper in nlp.blocks]
    cones = program.evaluate(np.zeros(program.num_variables)).cones
    for cone in cones:
        # ||v_1:|| <= v_0 as v_1:.v_1: - v_0^2 <= 0 and v_0 >= 0, smooth for IPOPT (its feasibility tolerance then
        # lets a vector near zero, a coasting thrust, through by the square root of that tolerance)
        values = ca.DM(sp.csr_matrix(cone.jacobian).toarray()) @ z + ca.DM(cone.values)
        start = 0
        for size in cone.sizes:
            head, rest = values[start], values[start + 1: start + size]
            blocks += [(ca.dot(rest, rest) - head**2, -np.inf, 0.0), (-head, -np.inf, 0.0)]
            start += size
    g = ca.vertcat(*(b[0] for b in blocks))
    lbg = np.concatenate([np.full(b[0].shape[0], b[1]) for b in blocks])
    ubg = np.concatenate([np.full(b[0].shape[0], b[2]) for b in blocks])
    solver = ca.nlpsol("ipopt", "ipopt", {"x": z, "f": objective, "g": g},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.tol": tol,
                        "ipopt.constr_viol_tol": 1e-9})
    setup_s = time.perf_counter() - started
    started = time.perf_counter()
    result = solver(x0=program.initial_guess() if z0 is None else z0, lbg=lbg, ubg=ubg)
    solve_s = time.perf_counter() - started
    stats = solver.stats()
    return IpoptAnswer(bool(stats["success"]), float(result["f"]), np.asarray(result["x"]).ravel(),
                       str(stats["return_status"]), setup_s, solve_s, int(stats.get("iter_count", 0)))
