"""The engine's check-repair-resolve loop on the cases that used to end unverified or falsely infeasible.

Each case is a committed problem file with ``--set`` overrides, as a user would try it; each must
come back converged AND verified by the dense re-propagation, at the known optimum. Impossible
cases must end ``infeasible`` with the certificate named (or ``unverified``), never with a traceback.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from convexguid.api import solve
from convexguid.cli import main
from convexguid.errors import SpecError

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

SLEW_180 = ["spacecraft.inertia_kgm2=[1,1,1]", "spacecraft.torque_max_Nm=1", "keep_out=[]",
            "spacecraft.rate_max_degps=1000", "boundary.final.axis=[1,0,0]", "boundary.final.angle_deg=180"]
"""Bilimoria & Wie (1993): unit inertia, |u_i| <= 1 N m, 180 deg rest-to-rest about a principal axis."""

BILIMORIA_WIE_TIME_S = 3.2432
"""Minimum time of that slew (Bilimoria & Wie 1993); the eigenaxis slew takes 2 sqrt(pi) = 3.5449 s."""


def _assert_verified(sol) -> None:
    assert sol.status == "converged", sol.message
    assert sol.verification is not None and sol.verification.passed, sol.summary()["verification"]
    assert sol.ok


def test_minimum_time_slew_from_the_default_eigenaxis_guess():
    """The eigenaxis start asks 1.5 N m of a 1 N m box: the engine moves it onto the box and goes on."""
    sol = solve(PROBLEMS / "wang_multicone_time.yaml", SLEW_180)
    _assert_verified(sol)
    assert sol.figures.maneuver_time_s == pytest.approx(BILIMORIA_WIE_TIME_S, rel=0.01)
    assert sol.figures.maneuver_time_s < 2 * np.sqrt(np.pi)  # shorter than the eigenaxis slew


CONE_ACROSS_PATH = ("keep_out=[{name: sun, body_axis: [0, -0.7071067811865476, 0.7071067811865476], "
                    "inertial_dir: [-0.7438, -0.6519, 0.148], half_angle_deg: 25}]")
"""A 25 deg cone centred where the sensor points halfway through the unconstrained 30 s slew."""

FLAT_SATURATED = ["boundary.tf_s=30", "spacecraft.torque_max_Nm=0.6", CONE_ACROSS_PATH]


@pytest.fixture(scope="module")
def flat_saturated():
    return solve(PROBLEMS / "cai2018_flat_attitude.yaml", FLAT_SATURATED)


def test_flat_attitude_with_torque_box_and_cone_active_is_verified(flat_saturated):
    sol = flat_saturated
    _assert_verified(sol)
    checks = {c.name: c for c in sol.verification.checks}
    assert checks["torque_Nm"].worst > 0.6 * (1 - 1e-3)  # the box is active ...
    assert checks["keep_out_sun_deg"].worst < 25.0 + 0.01  # ... and so is the cone
    rounds = sol.summary()["repair_rounds"]
    assert rounds[0]["passed"] is False and rounds[-1]["passed"] is True  # a repair was needed, and worked


def test_flat_attitude_saturated_case_is_within_half_a_percent_of_ipopt(flat_saturated):
    pytest.importorskip("casadi")
    from convexguid.families.flat_attitude.program import FlatAttitudeProgram, build_problem
    from convexguid.families.flat_attitude.reference import solve_flat_attitude_ipopt
    from convexguid.problem_files import load_problem

    # the same transcription (nodes and check points) from the same cubic guess, without the repairs
    problem = build_problem(load_problem(PROBLEMS / "cai2018_flat_attitude.yaml", FLAT_SATURATED))
    ipopt = solve_flat_attitude_ipopt(problem, FlatAttitudeProgram(problem).initial_guess())
    assert ipopt.success, ipopt.status
    assert flat_saturated.objective == pytest.approx(ipopt.objective, rel=5e-3)


RENDEZVOUS_LONG_BURN = ["spacecraft.accel_mps2=0.3", "boundary.initial.position_m=[15000,-500,0]",
                        "boundary.initial.velocity_mps=[-100,10,0]"]


def test_rendezvous_with_a_long_first_burn_refines_its_mesh_and_matches_lcvx():
    sol = solve(PROBLEMS / "wang2003_rendezvous_3d.yaml", RENDEZVOUS_LONG_BURN)
    _assert_verified(sol)
    s = sol.summary()
    assert s["subintervals_per_burn"] > 12  # the mesh was refined
    assert "mesh refined" in s["repair_rounds"][-1]["repair"]
    assert s["burn_time_s"] == pytest.approx(s["lcvx_burn_time_s"], rel=5e-3)


def test_rendezvous_with_too_little_thrust_is_certified_infeasible():
    sol = solve(PROBLEMS / "wang2003_rendezvous.yaml", ["spacecraft.accel_mps2=0.1"])
    assert sol.status == "infeasible"
    assert "certified by lcvx" in sol.message


def test_impossible_slew_is_infeasible_with_a_named_certificate_or_unverified(capsys):
    """A 180 deg slew in 3 s with a 1 N m box cannot be done (it needs at least 3.24 s), yet 3 s is above the bound
    the spec checks up front (2.69 s, any path with |u| <= sqrt(3) N m), so the SCP has to find out."""
    code = main(["solve", str(PROBLEMS / "wang_multicone_energy.yaml"), "--quiet", *sum(
        (["--set", o] for o in [*SLEW_180, "boundary.tf_s=3.0", "solver.max_iterations=60"]), [])])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1
    status = err[0].split(": ")[2]
    assert status in ("infeasible", "unverified", "max_iterations"), err[0]
    if status == "infeasible":
        assert "certificate" in err[0]


def test_inconsistent_hard_constraints_are_certified_by_the_elastic_program():
    """A final condition the bounds cannot meet (x + v = 3 at the end with x and v within [0, 1]): the hard linear
    constraints admit no point, which no check before the solve sees."""
    from convexguid.ocp import Problem

    p = Problem("unreachable")
    x = p.state("x", bounds=(0.0, 1.0), initial=0.0)
    v = p.state("v", bounds=(0.0, 1.0), initial=0.0)
    u = p.control("u", bounds=(-1.0, 1.0))
    p.dynamics({x: v, v: u})
    p.boundary_constraint("too_far", x + v - 3.0)
    p.final_time(fixed=2.0)
    p.minimize_energy()
    p.transcription(10)
    sol = p.solve()
    assert sol.status == "infeasible"
    assert "certificate" in sol.message and "elastic" in sol.message


def test_a_boundary_rate_outside_the_rate_box_is_one_line_naming_the_key():
    with pytest.raises(SpecError, match=r"boundary\.final\.rate_degps: a component is above "
                                        r"spacecraft\.rate_max_degps = 0\.5"):
        solve(PROBLEMS / "wang_multicone_time.yaml", ["spacecraft.rate_max_degps=0.5",
                                                      "boundary.final.rate_degps=[1, 0, 0]"])


def test_a_start_that_breaks_the_torque_box_is_restored_and_still_reaches_the_optimum():
    """The same slew from an eigenaxis start squeezed into 0.8 x its time: 1.56x the torque box at the ends."""
    from convexguid.families.quaternion_attitude.program import eigenaxis_guess, transcribe_slew
    from convexguid.families.quaternion_attitude.solve import QuaternionChecker, planning_setup
    from convexguid.problem_files import load_problem
    from convexguid.scp.check_repair import PlanningSetup

    spec = load_problem(PROBLEMS / "wang_multicone_time.yaml", SLEW_180)
    setup = planning_setup(spec)
    slew = setup.checker.slew(setup.program)
    tf = 0.8 * slew.program.final_time(slew.program.initial_guess())
    nodes = eigenaxis_guess(slew.case, np.linspace(0.0, tf, slew.intervals + 1))
    squeezed = transcribe_slew(slew.case, slew.intervals, nodes, tf)
    assert np.abs(squeezed.nodes(squeezed.program.initial_guess())[:, 7:]).max() > 1.5  # breaks the 1 N m box
    outcome = PlanningSetup(squeezed.program, setup.settings, QuaternionChecker(squeezed, spec.verification),
                            setup.budget).solve()
    assert outcome.status == "converged", outcome.message
    assert outcome.program.final_time(outcome.x) == pytest.approx(BILIMORIA_WIE_TIME_S, rel=0.01)
