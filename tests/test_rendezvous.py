"""Rendezvous family (Wang & Tang 2003): exact dynamics, transcription, both methods, verification, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from convexguid.api import solve
from convexguid.cli import main
from convexguid.dynamics.clohessy_wiltshire import cw_hold_input_casadi, cw_matrices, cw_stm, cw_stm_casadi, cw_zoh
from convexguid.errors import SpecError
from convexguid.families.rendezvous.arc_phases import PhasedArcsProgram
from convexguid.families.rendezvous.case import build_case
from convexguid.families.rendezvous.lcvx import burn_structure, solve_lcvx
from convexguid.problem_files import load_problem

PAPER = Path(__file__).parent.parent / "problems" / "wang2003_rendezvous.yaml"
SPACE = Path(__file__).parent.parent / "problems" / "wang2003_rendezvous_3d.yaml"
N = 0.0011313


# --- exact: dynamics and transcription -------------------------------------------------------

@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("dt", [0.5, 60.0, 600.0, 5400.0])
def test_stm_matches_matrix_exponential(dim, dt):
    A, _ = cw_matrices(N, 0.5, dim)
    assert np.allclose(cw_stm(N, dt, dim), expm(A * dt), rtol=1e-12, atol=1e-12 * max(1.0, dt))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("dt", [0.5, 8.0, 600.0, 5400.0])
def test_closed_form_hold_input_is_the_matrix_exponential_one(dim, dt):
    """The lcvx flow's input matrix in closed form against Van Loan's matrix exponential (cw_zoh)."""
    closed = np.array(ca.evalf(cw_hold_input_casadi(N, 0.5, dt, dim)))
    exponential = cw_zoh(N, 0.5, dt, dim)[1]
    assert np.abs(closed - exponential).max() <= 1e-11 * np.abs(exponential).max()


@pytest.mark.parametrize("dim", [2, 3])
def test_casadi_stm_is_the_numpy_one(dim):
    duration = ca.SX.sym("t")
    stm = ca.Function("stm", [duration], [cw_stm_casadi(N, duration, dim)])
    for dt in (0.5, 600.0, 5400.0):
        assert np.array_equal(np.asarray(stm(dt)), cw_stm(N, dt, dim))


def test_zoh_matches_integration_with_constant_thrust():
    u = np.array([0.3, -0.8, 0.52])
    x0 = np.array([1000.0, -50.0, 20.0, -3.0, 1.0, 0.5])
    A, B = cw_matrices(N, 0.5, 3)
    phi, gam = cw_zoh(N, 0.5, 7.0, 3)
    ref = solve_ivp(lambda t, x: A @ x + B @ u, (0, 7.0), x0, rtol=1e-12, atol=1e-12).y[:, -1]
    assert np.allclose(phi @ x0 + gam @ u, ref, rtol=1e-10, atol=1e-9)


# --- the paper's NLP -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def paper_case():
    return build_case(load_problem(PAPER))


def test_burn_defects_are_fourth_order(paper_case):
    """Hermite-Simpson (eqs. 5-8) on a burn flown exactly along a constant direction: halving the sub-intervals
    divides the defects by about 32 (local error O(h^5))."""
    direction, duration, errors = np.array([0.6, -0.8]), 200.0, []
    for subintervals in (4, 8):
        program = PhasedArcsProgram(paper_case, 2, subintervals)
        states, directions, durations = (part.copy() for part in program.layout.split(program.paper_guess()))
        phi, gamma = cw_zoh(N, paper_case.accel, duration / subintervals, 2)
        nodes = program.layout.burn_nodes(0)
        for previous, k in zip(nodes[:-1], nodes[1:], strict=True):
            states[k] = phi @ states[previous] + gamma @ direction
        directions[nodes], durations[0] = direction, duration
        z = program.from_design_vector(program.layout.join(states, directions, durations))
        defects = next(b for b in program.evaluate(z, False).equalities if b.name == "burn1: dynamics_defects")
        errors.append(np.abs(defects.values).max())
    assert errors[0] / errors[1] > 25


def test_nlp_dimensions_are_the_papers(paper_case):
    size = PhasedArcsProgram(paper_case, 2, 12).size()
    assert (size.num_variables, size.num_equality_constraints, size.num_inequality_constraints) == (159, 135, 3)
    space = build_case(load_problem(SPACE))
    size = PhasedArcsProgram(space, 2, 12).size()
    assert (size.num_variables, size.num_equality_constraints, size.num_inequality_constraints) == (237, 189, 3)


@pytest.mark.parametrize("coasts", [(False, False), (True, True)], ids=["paper", "lead-and-trail-coasts"])
def test_arcs_jacobians_match_finite_differences(paper_case, coasts):
    program = PhasedArcsProgram(paper_case, 2, 4, None, *coasts)
    rng = np.random.default_rng(0)
    x = program.initial_guess() + 0.01 * program.variable_scale() * rng.normal(size=program.num_variables)
    ev = program.evaluate(x)
    scale = program.variable_scale()
    for k, block in enumerate(ev.equalities):
        jac = block.jacobian.toarray()
        for j in rng.choice(program.num_variables, 12, replace=False):
            step = 1e-6 * scale[j]
            xp, xm = x.copy(), x.copy()
            xp[j] += step
            xm[j] -= step
            numeric = (program.evaluate(xp, False).equalities[k].values
                       - program.evaluate(xm, False).equalities[k].values) / (2 * step)
            assert np.allclose(jac[:, j], numeric, rtol=1e-5, atol=1e-9), (block.name, j)


@pytest.fixture(scope="module")
def paper_solution():
    return solve(PAPER)


@pytest.fixture(scope="module")
def fine_lcvx(paper_case):
    return solve_lcvx(paper_case, 2400)


def test_scp_arcs_converges_to_the_lcvx_optimum(paper_solution, paper_case, fine_lcvx):
    s = paper_solution.summary()
    assert s["status"] == "converged"
    assert (s["num_variables"], s["num_equality_constraints"], s["num_inequality_constraints"]) == (159, 135, 3)
    assert fine_lcvx.status == "converged"
    gap = (s["burn_time_s"] - fine_lcvx.objective) / fine_lcvx.objective
    assert abs(gap) < 5e-3
    # never below the global optimum of the grid by more than the two discretizations' error
    coarse = solve_lcvx(paper_case, 600).objective
    discretization = abs(coarse - fine_lcvx.objective) + abs(s["planned_direction_norm_min"] - 1) * s["burn_time_s"]
    assert s["burn_time_s"] >= fine_lcvx.objective - discretization


def test_burn_structure_agrees_within_a_subinterval(paper_solution, fine_lcvx):
    arcs = paper_solution.summary()["burn_arcs_s"]
    assert len(arcs) == len(fine_lcvx.burns) == 2
    for (start, end), burn in zip(arcs, fine_lcvx.burns, strict=True):
        subinterval = (end - start) / 12
        assert abs(start - burn.start_s) < subinterval
        assert abs(end - burn.end_s) < subinterval


def test_dense_verification_of_the_paper_plan(paper_solution):
    v = paper_solution.verification
    assert v.passed
    assert v.final_errors["final_position_error_m"] < 1.0
    assert v.final_errors["final_velocity_error_mps"] < 0.01
    thrust = paper_solution.dense.columns["thrust_accel_mps2"]
    burning = thrust > 0
    assert np.allclose(thrust[burning], 0.5, rtol=1e-12)  # the engine flies full thrust on burns
    assert paper_solution.summary()["planned_direction_norm_min"] > 0.9999


def test_lcvx_is_nearly_bang_off_bang(paper_case):
    plan = solve_lcvx(paper_case, 600)
    assert plan.status == "converged"
    assert plan.figures.intermediate_throttle_share < 0.02
    assert plan.figures.lossless_gap_max < 1e-6
    assert len(plan.burns) == 2


def test_burn_structure_reads_partial_steps():
    grid = np.arange(11.0)
    throttle = np.array([0, 0.5, 1, 1, 0, 0, 0.25, 0, 1, 0.4])
    arcs = burn_structure(grid, throttle)
    assert [(a.start_s, a.end_s) for a in arcs] == [(1.5, 4.0), (6.0, 6.25), (8.0, 9.4)]


def test_out_of_plane_case_converges_and_verifies():
    sol = solve(SPACE)
    s = sol.summary()
    assert sol.ok
    assert s["num_variables"] == 26 * 9 + 3
    assert abs(s["lcvx_gap_rel"]) < 5e-3
    assert np.abs(sol.dense.columns["z_m"]).max() > 100  # the z motion is really there


# --- bad input and infeasible problems --------------------------------------------------------------

@pytest.mark.parametrize("method", ["scp_arcs", "lcvx"])
def test_too_little_thrust_is_infeasible(method):
    sol = solve(PAPER, [f"method={method}", "spacecraft.accel_mps2=0.1"])
    assert sol.status == "infeasible"
    assert "infeasible" in sol.message and "\n" not in sol.message


@pytest.mark.parametrize("override, key", [
    ("boundary.tf_s=0", "boundary.tf_s"),
    ("boundary.tf_s=-5", "boundary.tf_s"),
    ("discretization.subintervals_per_burn=0", "discretization.subintervals_per_burn"),
    ("boundary.initial.position_m=[.nan, 0]", "boundary.initial.position_m.0"),
    ("boundary.initial.velocity_mps=[1, 2, 3]", "boundary.initial.velocity_mps"),
    ("spacecraft.accel_mps2=0", "spacecraft.accel_mps2"),
    ("method=shooting", "method"),
])
def test_bad_input_names_the_key(override, key):
    with pytest.raises(SpecError) as err:
        load_problem(PAPER, [override])
    message = str(err.value)
    assert "\n" not in message and str(PAPER) in message and key in message


def test_cli_summary_json(tmp_path):
    out = tmp_path / "summary.json"
    assert main(["solve", str(PAPER), "--quiet", "--summary-json", str(out)]) == 0
    summary = json.loads(out.read_text())
    assert summary["family"] == "rendezvous" and summary["method"] == "scp_arcs"
    assert summary["verification"]["passed"] is True
    assert summary["num_equality_constraints"] == 135


LATE_END = ["boundary.initial.position_m=[10357.669, -492.569, 851.612]",
            "boundary.initial.velocity_mps=[-86.7778, -1.6184, -3.2168]"]
"""A 3-D case whose lcvx optimum ends its second burn at 290 s of 600: the paper's arcs (ending on a burn) cannot
fly it, and from the boundary conditions alone the SCP stopped 0.21% above it (measured before the lcvx start)."""


def test_auto_burns_follow_the_lcvx_optimum_including_a_trailing_coast():
    sol = solve(SPACE, [*LATE_END, "discretization.burns=auto"])
    summary = sol.summary()
    assert sol.ok, sol.message
    assert summary["num_burns"] == len(summary["lcvx_burn_arcs_s"]) == 2
    assert summary["burn_arcs_s"][-1][1] < 300.0  # the plan coasts to the target after its last burn
    assert abs(summary["lcvx_gap_rel"]) <= 1e-4
    assert summary["kkt"]["met"]
    assert "above the lcvx optimum" not in sol.message


def test_too_few_burns_are_named_against_the_lcvx_optimum():
    sol = solve(SPACE, ["discretization.burns=1"])
    assert sol.summary()["lcvx_gap_rel"] > 1e-3
    assert "above the lcvx optimum on 600 steps" in sol.message
    assert "1 burns where the lcvx optimum has 2" in sol.message


@pytest.mark.parametrize("problem", [PAPER, SPACE])
def test_a_grid_too_fine_for_lcvx_is_refused_by_the_family_naming_its_key(problem):
    """The family's estimate of the ``lcvx`` grid bounds ``convexguid.ocp``'s own of the problem it states, so the
    refusal names the YAML key, not the transcription's."""
    from convexguid.families import FAMILIES
    from convexguid.families.rendezvous.lcvx import lcvx_problem
    from convexguid.ocp.size import estimate_size

    spec = load_problem(problem, ["method=lcvx", "certify=false"])
    family = FAMILIES["rendezvous"].estimate_size(spec).memory_bytes
    assert family >= estimate_size(lcvx_problem(build_case(spec), spec.discretization.grid_steps)).memory_bytes
    with pytest.raises(SpecError, match=r"discretization\.grid_steps: problem too large"):
        solve(problem, ["method=lcvx", "discretization.grid_steps=50000"])
