"""Flat attitude family: Cai, Zhu, Zeng 2018 Table 1 reproduced, then verified by dense re-propagation."""

import numpy as np
import pytest

from convexguid import solve
from convexguid.families.flat_attitude.program import FlatAttitudeProgram, build_problem
from convexguid.spec import load_problem

PAPER = "problems/cai2018_flat_attitude.yaml"


@pytest.fixture(scope="module")
def paper_solution():
    return solve(PAPER)


def test_table1_objective_and_size(paper_solution):
    # Table 1, proposed method: J = 0.2607 with 99 decision variables (fmincon needed 246 iterations).
    sol = paper_solution
    assert sol.status == "converged"
    assert abs(sol.objective - 0.2607) / 0.2607 <= 5e-4
    assert sol.size.num_variables == 99
    assert sol.iterations <= 20


def test_table1_plan_verified_on_dense_grid(paper_solution):
    v = paper_solution.verification
    checks = {c.name: c for c in v.checks}
    assert v.passed and v.grid_points >= 1000
    assert checks["torque_Nm"].worst <= 1.0
    assert checks["keep_out_sun_deg"].worst >= 45.0
    assert v.final_errors["final_attitude_error_rad"] < 1e-3
    assert v.final_errors["final_rate_error_radps"] < 1e-4


def test_summary_keeps_contract_keys(paper_solution):
    summary = paper_solution.summary()
    for key in ("problem", "family", "method", "status", "objective", "iterations", "num_variables",
                "num_equality_constraints", "num_inequality_constraints", "wall_time_s", "solver"):
        assert key in summary
    for key in ("grid_points", "constraints", "max_violation", "final_state_error", "passed"):
        assert key in summary["verification"]
    assert summary["verification"]["max_violation"] == 0.0


def test_torque_jacobian_matches_central_differences():
    program = FlatAttitudeProgram(build_problem(load_problem(PAPER)))
    x = program.initial_guess() + 0.01 * np.sin(np.arange(program.num_variables))
    jac = program.evaluate(x).residual_jacobian
    h = 1e-6
    for j in (0, 17, 50, 98):
        e = np.zeros_like(x)
        e[j] = h
        fd = (program.evaluate(x + e, False).residuals - program.evaluate(x - e, False).residuals) / (2 * h)
        np.testing.assert_allclose(jac[:, j], fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_initial_guess_meets_boundary_conditions():
    program = FlatAttitudeProgram(build_problem(load_problem(PAPER)))
    lin = program.linear_constraints()
    residual = lin.A @ program.initial_guess() - lin.b
    # Attitudes exactly; Euler rates to the spline's interpolation error (the engine projects the rest).
    np.testing.assert_allclose(residual[[0, 1, 2, 6, 7, 8]], 0.0, atol=1e-12)
    np.testing.assert_allclose(residual, 0.0, atol=1e-6)
    assert lin.A.shape == (12, 99)


def test_saturated_torque_case_converges_and_verifies():
    sol = solve(PAPER, ["boundary.tf_s=25"])
    assert sol.status == "converged" and sol.verification.passed
    worst = {c.name: c.worst for c in sol.verification.checks}["torque_Nm"]
    assert worst == pytest.approx(1.0, abs=1e-5)  # the bound is active on the dense grid


def test_impossible_slew_ends_infeasible_with_diagnostics():
    # A 120 deg slew in 5 s needs tens of N m; only 1 N m is available.
    sol = solve(PAPER, ["boundary.tf_s=5", "solver.max_iterations=30"])
    assert sol.status in ("infeasible", "max_iterations")
    assert "torque_Nm" in sol.message or sol.status == "max_iterations"
    assert not sol.verification.passed
