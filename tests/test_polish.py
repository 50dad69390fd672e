"""What happens when the SCP stalls short of the KKT tolerance: the curved subproblem and the fitted multipliers.

* the convexified Hessian is positive semidefinite and keeps the reduced Hessian on the working rows' null space;
* the fitted multipliers of a hand-solved problem are its multiplier, and the fit minimizes the largest residual;
* a random minimum-time slew whose linear model stalled short of the KKT tolerance (the robustness benchmark's
  slew #4, 30 iterations and ``unverified`` before) is polished by the curved subproblem to a KKT point.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as la
import scipy.sparse as sp
from scipy.optimize import linprog, lsq_linear
from test_scp_engine import ShiftedDisk

from convexguid.api import solve
from convexguid.backends.base import Cones, ConicProgram
from convexguid.backends.registry import make_backend
from convexguid.problem_files import parse_problem
from convexguid.robustness.instances import random_minimum_time_slews
from convexguid.scp.curved import convexified, with_low_rank
from convexguid.scp.engine import SCPAlgorithm
from convexguid.scp.optimality import fitted_multipliers, smallest_largest_residual
from convexguid.scp.policies import FunnelPolicy
from convexguid.scp.problem import SCPSettings

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def test_the_convexified_hessian_is_convex_and_keeps_the_reduced_hessian():
    rng = np.random.default_rng(3)
    n, m = 8, 3
    rows = rng.standard_normal((m, n))
    Z = la.null_space(rows)
    # indefinite overall, positive definite on the null space of the rows
    reduced = Z @ np.diag(rng.uniform(0.5, 2.0, n - m)) @ Z.T
    Y = la.orth(rows.T)
    coupling = rng.standard_normal((m, n - m))
    hessian = reduced - 3.0 * Y @ Y.T + Y @ coupling @ Z.T + Z @ coupling.T @ Y.T
    assert np.linalg.eigvalsh(hessian)[0] < 0
    convex, gamma, augmented, factor = convexified(hessian, rows)
    assert gamma > 0
    assert np.linalg.eigvalsh(convex)[0] >= -1e-10 * np.abs(convex).max()
    np.testing.assert_allclose(Z.T @ convex @ Z, Z.T @ hessian @ Z, atol=1e-9)
    # the sparse backend's form of the same matrix: the augmented Hessian plus one term per negative eigenvalue
    np.testing.assert_allclose(augmented + factor @ factor.T, convex, atol=1e-9 * np.abs(convex).max())


def test_the_low_rank_term_is_the_same_quadratic_program():
    """min 1/2 u'(H + F F')u + q'u over a box, solved with F F' in P and with w = F'u: the same step and value."""
    rng = np.random.default_rng(5)
    n, rank = 6, 2
    root = rng.standard_normal((n, n))
    sparse_part = np.diag(rng.uniform(0.1, 1.0, n))
    factor = root[:, :rank]
    q = rng.standard_normal(n)
    box = sp.vstack([sp.identity(n), -sp.identity(n)], format="csc")
    def program(hessian):
        return ConicProgram(sp.triu(sp.csc_matrix(hessian), format="csc"), q, box, np.full(2 * n, 0.5),
                            Cones(nonneg=2 * n))
    dense = make_backend("clarabel", program(sparse_part + factor @ factor.T), tolerance=1e-10).solve()
    lifted = make_backend("clarabel", with_low_rank(program(sparse_part), n, factor), tolerance=1e-10).solve()
    np.testing.assert_allclose(lifted.x[:n], dense.x, atol=1e-7)
    assert lifted.x[n:] == pytest.approx(factor.T @ lifted.x[:n], abs=1e-8)
    assert np.any(np.abs(dense.x) >= 0.5 - 1e-6)  # the box binds: the test is of a constrained QP
    assert lifted.objective == pytest.approx(dense.objective, rel=1e-7)


def test_fitted_multipliers_are_the_hand_multiplier():
    """min |z - 3|^2 s.t. |z|^2 <= 2 at its optimum (1, 1): 2 (z - 3) + 2 mu z = 0 gives mu = 2."""
    algo = SCPAlgorithm(ShiftedDisk(), SCPSettings(backend="clarabel"))
    state = algo.initialize(np.array([1.0, 1.0]))
    multipliers = fitted_multipliers(algo, state)
    assert multipliers.inequality == pytest.approx([2.0], rel=1e-9)


def test_a_stalled_minimum_time_slew_is_polished_to_a_kkt_point():
    # random slew #7 stalls short of the KKT tolerance on linear steps and is polished (#4 did before the funnel)
    slew = [t for t in random_minimum_time_slews(PROBLEMS, 12, 19)][7]
    sol = solve(parse_problem(slew.problem, slew.source))
    assert sol.status == "converged" and sol.summary()["kkt"]["met"], sol.message
    assert any(r.solver_status == "curved" for r in sol.history)
    assert sol.iterations <= 50


def test_a_curved_step_the_backend_calls_inaccurate_is_still_a_step(monkeypatch):
    """The curved QP's answer graded `optimal_inaccurate` is taken like any other usable answer (the ratio test judges
    the step, the KKT conditions are checked on the NLP); refused, random rendezvous #75 of the robustness benchmark
    polished on linear steps to `unverified`."""
    from dataclasses import replace

    from convexguid.scp.curved import CurvedSubproblem

    real = CurvedSubproblem.solve

    def inaccurate(self, state, ev, model):
        result, value = real(self, state, ev, model)
        return (replace(result, status="optimal_inaccurate") if result.status == "optimal" else result), value

    monkeypatch.setattr(CurvedSubproblem, "solve", inaccurate)
    slew = [t for t in random_minimum_time_slews(PROBLEMS, 12, 19)][7]
    sol = solve(parse_problem(slew.problem, slew.source))
    assert sol.status == "converged" and sol.summary()["kkt"]["met"], sol.message
    assert any(r.solver_status == "curved" for r in sol.history)


def test_the_multiplier_fit_minimizes_the_largest_residual_the_certificate_judges():
    """The certificate judges stationarity by its largest scaled component, and the fit minimizes exactly that (a linear
    program on Clarabel): its largest residual is HiGHS's optimum of the same program to 1e-8, well below what the
    2-norm's minimizer (BVLS, the fit before) leaves; where the minimizers form a face (more multipliers than
    stationarity rows) it reaches a zero residual."""
    rng = np.random.default_rng(11)
    matrix = sp.random(60, 25, density=0.3, random_state=rng, format="csc") + sp.eye(60, 25, format="csc")
    target = rng.standard_normal(60)
    lower = np.where(np.arange(25) < 15, 0.0, -np.inf)  # signed multipliers first, free ones after
    dense, ones = matrix.toarray(), np.ones((60, 1))
    rows = np.block([[dense, -ones], [-dense, -ones]])
    best = linprog(np.r_[np.zeros(25), 1.0], A_ub=rows, b_ub=np.r_[target, -target],
                   bounds=[(lo if np.isfinite(lo) else None, None) for lo in lower] + [(0, None)], method="highs")
    assert best.status == 0 and best.fun > 0.1 and np.any(best.x[:15] < 1e-9)  # some signs bind: a constrained fit
    fit = smallest_largest_residual(matrix, target, lower)
    assert np.max(np.abs(matrix @ fit - target)) <= best.fun * (1 + 1e-8)
    assert np.all(fit[:15] >= 0.0)
    two_norm = lsq_linear(dense, target, bounds=(lower, np.full(25, np.inf)), method="bvls").x
    assert np.max(np.abs(matrix @ two_norm - target)) > 1.2 * best.fun
    # a face of minimizers: 40 multipliers, 25 rows, a target the signed ones reach with a zero residual
    wide = sp.random(25, 40, density=0.3, random_state=rng, format="csc") + sp.eye(25, 40, format="csc")
    reachable = wide @ np.concatenate([rng.uniform(0.0, 1.0, 30), rng.standard_normal(10)])
    signed = np.where(np.arange(40) < 30, 0.0, -np.inf)
    y = smallest_largest_residual(wide, reachable, signed)
    assert np.all(y[:30] >= 0.0)
    assert np.max(np.abs(wide @ y - reachable)) <= 1e-8 * np.max(np.abs(reachable))


def test_a_warm_start_gets_a_funnel_without_the_cold_starts_floor():
    """A repair's re-solve starts from a nearly feasible plan: its funnel is ten times its violation, not 1."""
    policy = FunnelPolicy()
    assert policy.initial(2.6e-3).width == 1.0
    assert policy.initial(2.6e-3, warm=True).width == pytest.approx(2.6e-2)


def test_a_curved_step_clarabel_cannot_solve_in_its_low_rank_form_is_solved_with_the_clipped_matrix(monkeypatch):
    """The low-rank form's objective is convex only where ``w = F^T u`` holds; where Clarabel fails on it (Luus'
    singular problem failed every curved step so), the same QP with the clipped Hessian as it is gives the step. Here
    the low-rank form is made to fail (an equality ``0 = 1`` appended); slew #7 is still polished by curved steps."""
    import convexguid.scp.curved as curved_module

    def failing(program, n, factor):
        lifted = with_low_rank(program, n, factor)
        impossible = sp.csr_matrix((1, lifted.num_variables))
        return ConicProgram(lifted.P, lifted.q, sp.vstack([impossible, lifted.A], format="csc"),
                            np.concatenate([[1.0], lifted.b]), Cones(zero=lifted.cones.zero + 1,
                                                                      nonneg=lifted.cones.nonneg,
                                                                      soc=lifted.cones.soc), lifted.constant)

    monkeypatch.setattr(curved_module, "with_low_rank", failing)
    slew = [t for t in random_minimum_time_slews(PROBLEMS, 12, 19)][7]
    sol = solve(parse_problem(slew.problem, slew.source))
    assert sol.status == "converged" and sol.summary()["kkt"]["met"], sol.message
    assert any(r.solver_status == "curved" for r in sol.history)


def luus_singular(intervals: int):
    """Luus' singular problem as PSOPT's applications document states it (``singular5``; PSOPT: 0.1192613 on 100
    Legendre nodes): the integral of x1^2 + x2^2 + 5e-4 (x2 + 16 t - 8 - 0.1 x3 u^2)^2 over t in [0, 1], with
    x1' = x2, x2' = -x3 u + 16 t - 8, x3' = u, x(0) = (0, -1, -sqrt 5) and 0 <= u <= 10."""
    from convexguid.ocp import Problem

    p = Problem("luus-singular")
    x1, x2, x3 = p.state("x1", initial=0.0), p.state("x2", initial=-1.0), p.state("x3", initial=-np.sqrt(5.0))
    u = p.control("u", bounds=(0, 10))
    p.dynamics({x1: x2, x2: -x3 * u + 16 * p.time - 8, x3: u})
    p.final_time(fixed=1.0)
    p.minimize_integral(x1**2 + x2**2 + 5e-4 * (x2 + 16 * p.time - 8 - 0.1 * x3 * u**2) ** 2)
    p.transcription(intervals)
    return p


def test_linear_steps_a_stiff_model_holds_back_hand_over_to_the_curved_step():
    """Along Luus' singular arc the convex model is stiffer than the problem: its linear steps stay inside the trust
    region with merit ratios near 2. Two of them in a row now count as pinned ones, and the curved step takes over:
    after 40 iterations on 50 intervals it has been taken and the cost is within 0.3% of PSOPT's 0.1192613 (before,
    none was, and the cost stood at 0.12013 after 40, 0.11952 after 489)."""
    sol = luus_singular(50).solve(max_iterations=40)
    assert any(r.solver_status == "curved" for r in sol.history)
    assert sol.objective < 0.1196
