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
    g, lbg, ubg, lbx, ubx = variable_bounds(z, g, lbg, ubg)
    solver = ca.nlpsol("ipopt", "ipopt", {"x": z, "f": objective, "g": g},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.tol": tol,
                        "ipopt.constr_viol_tol": 1e-9})
    setup_s = time.perf_counter() - started
    started = time.perf_counter()
    result = solver(x0=program.initial_guess() if z0 is None else z0, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx)
    solve_s = time.perf_counter() - started
    stats = solver.stats()
    return IpoptAnswer(bool(stats["success"]), float(result["f"]), np.asarray(result["x"]).ravel(),
                       str(stats["return_status"]), setup_s, solve_s, int(stats.get("iter_count", 0)))


def variable_bounds(z: ca.SX, g: ca.SX, lbg: np.ndarray, ubg: np.ndarray):
    """``(g, lbg, ubg, lbx, ubx)``: the rows of ``lbg <= g(z) <= ubg`` that are a constant times one variable plus a
    constant (a state's bounds, its stated boundary values) taken out as bounds on that variable, which IPOPT keeps
    its iterates within (it may leave a constraint row's bounds until it converges, and the dynamics then meet
    states the statement excludes: a negative radius, a speed of zero)."""
    n = z.shape[0]
    jacobian = ca.jacobian(g, z)
    rows, cols = (np.asarray(a, dtype=int) for a in jacobian.sparsity().get_triplet())
    single = np.bincount(rows, minlength=g.shape[0]) == 1
    slope_at = ca.Function("slope", [z], [jacobian])(np.zeros(n)).sparse()
    offset = np.asarray(ca.Function("offset", [z], [g])(np.zeros(n)), dtype=float).ravel()
    lbx, ubx = np.full(n, -np.inf), np.full(n, np.inf)
    taken = np.zeros(g.shape[0], dtype=bool)
    for row, col in zip(rows, cols, strict=True):
        if not single[row] or ca.depends_on(jacobian[int(row), int(col)], z):
            continue
        slope = float(slope_at[row, col])
        if slope == 0.0:
            continue
        low, high = sorted(((lbg[row] - offset[row]) / slope, (ubg[row] - offset[row]) / slope))
        lbx[col], ubx[col] = max(lbx[col], low), min(ubx[col], high)
        taken[row] = True
    kept = np.flatnonzero(~taken)
    return g[kept.tolist()], lbg[kept], ubg[kept], lbx, ubx
