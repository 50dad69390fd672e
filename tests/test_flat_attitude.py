"""Flat attitude family: Cai, Zhu, Zeng 2018 Table 1 reproduced, then verified by dense re-propagation."""

import json
from pathlib import Path

import numpy as np
import pytest

from convexguid import solve
from convexguid.families.flat_attitude.program import FlatAttitudeProgram, build_problem
from convexguid.problem_files import load_problem

PAPER = str(Path(__file__).resolve().parents[1] / "problems" / "cai2018_flat_attitude.yaml")
PAPER_J, PAPER_J_RTOL = 0.2607, 5e-4  # Table 1 (J at tf = 100 s) and the tolerance of the file's reference block


@pytest.fixture(scope="module")
def paper_solution():
    return solve(PAPER)


def test_table1_objective_and_size(paper_solution):
    # Table 1, proposed method: J = 0.2607 with 99 decision variables (fmincon needed 246 iterations).
    sol = paper_solution
    assert sol.status == "converged", sol.message
    assert sol.objective == pytest.approx(PAPER_J, rel=PAPER_J_RTOL)
    assert sol.size.num_variables == 99
    assert sol.iterations <= 20


def test_table1_plan_verified_on_dense_grid(paper_solution):
    assert paper_solution.status == "converged", paper_solution.message
    v = paper_solution.verification
    checks = {c.name: c for c in v.checks}
    assert v.passed and v.grid_points >= 1000
    assert checks["torque_Nm"].worst <= 1.0
    assert checks["keep_out_sun_deg"].worst >= 45.0
    assert v.final_errors["final_attitude_error_rad"] < 1e-3
    assert v.final_errors["final_rate_error_radps"] < 1e-4


def test_summary_reports_the_verified_plan(paper_solution):
    """The summary (the contract of docs/cli.md) carries this run's figures, JSON-clean."""
    sol = paper_solution
    summary = json.loads(json.dumps(sol.summary(), allow_nan=False))
    assert summary["status"] == "converged", summary["message"]
    assert {k: summary[k] for k in ("problem", "family", "method", "solver", "num_variables",
                                    "num_equality_constraints")} == {
        "problem": "cai2018-flat-attitude", "family": "flat_attitude", "method": "scp",
        "solver": "auto -> daqp (condensed)", "num_variables": 99, "num_equality_constraints": 12}
    assert summary["num_inequality_constraints"] == sol.size.num_inequality_constraints > 0
    assert summary["objective"] == pytest.approx(PAPER_J, rel=PAPER_J_RTOL)
    assert summary["iterations"] == sol.iterations > 0 and summary["wall_time_s"] > 0
    v, checks = summary["verification"], {c.name: c for c in sol.verification.checks}
    assert v["passed"] is True and v["max_violation"] == 0.0
    assert v["grid_points"] == sol.verification.grid_points >= 1000
    assert v["constraints"] == {"torque_Nm": {"worst": checks["torque_Nm"].worst, "bound": 1.0},
                                "keep_out_sun_deg": {"worst": checks["keep_out_sun_deg"].worst, "bound": 45.0}}
    assert 0.0 <= v["final_state_error"] < 1e-3


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
    assert sol.status == "converged", sol.message
    assert sol.verification.passed
    worst = {c.name: c.worst for c in sol.verification.checks}["torque_Nm"]
    assert worst == pytest.approx(1.0, abs=1e-5)  # the bound is active on the dense grid
    # Stretching time by s scales the torque by 1/s^2 and the energy by 1/s^3: the 100 s optimum squeezed
    # into 25 s costs 64 J(100 s) but peaks at 16 x 0.0725 = 1.16 N m, so with the bound it costs more.
    assert sol.objective > PAPER_J * (100 / 25) ** 3 * (1 - PAPER_J_RTOL)


def test_impossible_slew_ends_infeasible_with_a_certificate():
    # The 155 deg slew cannot be done in 18 s with 1 N m per axis, though 18 s is above the bound the spec checks
    # up front (17.7 s, any path with |u| <= sqrt(3) N m): the SCP has to certify it.
    sol = solve(PAPER, ["boundary.tf_s=18", "solver.max_iterations=30"])
    assert sol.status == "infeasible", f"{sol.status}: {sol.message}"
    assert "certificate" in sol.message and "torque_Nm" in sol.message, sol.message
    assert not sol.ok


def test_lagrangian_hessian_from_local_hessians_matches_differences():
    """The flat program's Hessian, assembled from the torque map's and the sun cone's local Hessians, against
    central differences of the whole program's Lagrangian gradient, at a point off the guess with random
    multipliers."""
    from differenced import differenced_hessian

    from convexguid.scp.lagrangian import CurvatureWeights

    sun_active = Path(PAPER).with_name("cai2018_flat_attitude_sun_active.yaml")
    program = FlatAttitudeProgram(build_problem(load_problem(sun_active)))
    x = program.initial_guess() + 0.01 * np.sin(np.arange(program.num_variables))
    ev = program.evaluate(x)
    rng = np.random.default_rng(0)
    n_ineq = sum(b.values.size for b in ev.inequalities)
    assert n_ineq > 0
    for residual in (rng.normal(size=ev.residuals.size), np.zeros(ev.residuals.size)):
        weights = CurvatureWeights(residual, np.abs(rng.normal(size=n_ineq)), np.zeros(0))
        differenced = differenced_hessian(program, x, weights, np.ones(program.num_variables))
        local = program.lagrangian_hessian(x, weights)
        assert np.abs(local - differenced).max() <= 1e-6 * np.abs(differenced).max()


def test_jacobians_added_to_an_evaluation_are_those_of_a_whole_evaluation():
    """with_jacobians (the engine's second look at an accepted trial point) gives evaluate's numbers, bitwise."""
    program = FlatAttitudeProgram(build_problem(load_problem(Path("problems/cai2018_flat_attitude_sun_active.yaml"))))
    x = program.initial_guess() + 0.01 * np.random.default_rng(0).normal(size=program.num_variables)
    whole, added = program.evaluate(x), program.with_jacobians(x, program.evaluate(x, jacobians=False))
    np.testing.assert_array_equal(added.residual_jacobian, whole.residual_jacobian)
    for a, b in zip(added.inequalities, whole.inequalities, strict=True):
        assert a.name == b.name
        np.testing.assert_array_equal(a.values, b.values)
        np.testing.assert_array_equal(a.jacobian, b.jacobian)
