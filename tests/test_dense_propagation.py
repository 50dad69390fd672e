"""Dense re-propagation of attitude plans: the written-out right-hand side, torque commands with breakpoints,
piecewise integration against tight references, the flat verification unchanged on the paper case."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from convexguid.dynamics.rigid_body import rigid_body_rhs, rigid_body_rhs_fast
from convexguid.dynamics.torque import LinearTorque, TorqueCommand
from convexguid.families.flat_attitude.solve import planning_setup, torque_command, verify_plan
from convexguid.families.quaternion_attitude.path_transfer import multicone_scenario, plan_path_transfer
from convexguid.families.quaternion_attitude.program import eigenaxis_start, transcribe_slew
from convexguid.families.quaternion_attitude.solve import build_case
from convexguid.problem_files import load_problem
from convexguid.rotations import euler321_to_quat, quat_angle_between
from convexguid.verification import propagate_attitude

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def test_fast_rhs_equals_reference_rhs():
    """Full inertia, unit quaternions, rates and torques of attitude-slew size: equal to 1e-15."""
    rng = np.random.default_rng(7)
    a = rng.standard_normal((3, 3))
    inertia = a @ a.T + 5.0 * np.eye(3)

    def torque(t: float) -> np.ndarray:
        return np.array([0.3 * np.sin(t), -0.2 * np.cos(2 * t), 0.1 * t])

    reference, fast = rigid_body_rhs(inertia, torque), rigid_body_rhs_fast(inertia, torque)
    for _ in range(200):
        q = rng.standard_normal(4)
        state = np.concatenate([q / np.linalg.norm(q), 0.1 * rng.standard_normal(3)])
        t = float(rng.uniform(-5, 5))
        np.testing.assert_allclose(fast(t, state), reference(t, state), rtol=0, atol=1e-15)
    # a torque given as a plain sequence of floats works too
    tuple_torque = rigid_body_rhs_fast(inertia, lambda t: (0.1, -0.2, 0.3))
    np.testing.assert_allclose(tuple_torque(0.0, state), rigid_body_rhs(inertia, lambda t: np.array([0.1, -0.2, 0.3]))(
        0.0, state), rtol=0, atol=1e-15)


def test_linear_torque_is_numpy_interp():
    rng = np.random.default_rng(1)
    times = np.cumsum(rng.uniform(0.5, 2.0, 12))
    values = rng.standard_normal((12, 3))
    command = LinearTorque(times, values)
    t = np.concatenate([rng.uniform(times[0] - 1, times[-1] + 1, 300), times])
    expected = np.column_stack([np.interp(t, times, values[:, i]) for i in range(3)])
    np.testing.assert_array_equal(np.array([command(tt) for tt in t]), expected)
    np.testing.assert_array_equal(command.sample(t), expected)
    np.testing.assert_array_equal(command.breakpoints, times[1:-1])


def test_torque_command_defaults():
    command = TorqueCommand(lambda t: np.array([t, 2 * t, 3 * t]), breakpoints=[2.0, 1.0, 2.0])
    np.testing.assert_array_equal(command.breakpoints, [1.0, 2.0])
    np.testing.assert_array_equal(command.sample([0.5, 1.0]), [[0.5, 1.0, 1.5], [1.0, 2.0, 3.0]])


@pytest.fixture(scope="module")
def kinked_plan():
    """Node torques of the multi-cone case's eigenaxis start on 12 intervals, perturbed: a kink at every node."""
    case = build_case(load_problem(PROBLEMS / "wang_multicone_time.yaml"))
    guess, tf = eigenaxis_start(case, 12)
    guess[:, 7:] += 0.3 * np.max(case.torque_max) * np.random.default_rng(5).standard_normal((13, 3))
    slew = transcribe_slew(case, 12, guess, tf)
    return case, slew.torque_command(slew.program.initial_guess()), tf


def test_piecewise_propagation_matches_tight_reference(kinked_plan):
    """Node to node at the verification's rtol 1e-10 against one DOP853 run at rtol 1e-12 with steps of h/50.

    Measured on the grid: 3.8e-11 (quaternion), 1.0e-12 rad/s (rate); one run across the kinks at rtol 1e-10
    with steps capped at h/4 (the former dense check) is 3.2e-10 and 3.1e-11 rad/s off.
    """
    case, command, tf = kinked_plan
    t_grid = np.linspace(case.t0, case.t0 + tf, 1001)
    track = propagate_attitude(case.inertia, command, case.q0, case.w0, t_grid, rtol=1e-10, atol=1e-12)
    y0 = np.concatenate([case.q0, case.w0])
    ref = solve_ivp(rigid_body_rhs(case.inertia, command), (t_grid[0], t_grid[-1]), y0, method="DOP853",
                    t_eval=t_grid, rtol=1e-12, atol=1e-14, max_step=tf / 12 / 50)
    assert ref.success
    q_ref = ref.y[:4].T / np.linalg.norm(ref.y[:4].T, axis=1, keepdims=True)
    np.testing.assert_array_equal(track.t, t_grid)
    np.testing.assert_allclose(track.q, q_ref, rtol=0, atol=1e-9)
    np.testing.assert_allclose(track.omega, ref.y[4:].T, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(track.torque, command.sample(t_grid))


def test_piecewise_propagation_needs_few_calls(kinked_plan):
    """The piecewise run takes a fraction of the right-hand-side calls of one run across the kinks."""
    case, command, tf = kinked_plan
    calls = {"n": 0}

    def counted(t: float) -> np.ndarray:
        calls["n"] += 1
        return command(t)

    t_grid = np.linspace(case.t0, case.t0 + tf, 1001)
    propagate_attitude(case.inertia, TorqueCommand(counted, command.breakpoints), case.q0, case.w0, t_grid,
                       rtol=1e-10, atol=1e-12)
    piecewise, calls["n"] = calls["n"], 0
    propagate_attitude(case.inertia, counted, case.q0, case.w0, t_grid, rtol=1e-10, atol=1e-12, max_step=tf / 48)
    assert piecewise < calls["n"] / 2


def test_path_transfer_torque_command():
    """The fast closed-form torque equals the sampled law; integrated between its jumps it reaches the target."""
    scenario = multicone_scenario()
    plan = plan_path_transfer(scenario)
    t = np.union1d(np.linspace(-5.0, plan.maneuver_time_s + 5.0, 3001), plan.breakpoints_s)
    np.testing.assert_allclose(np.array([plan.torque_at(tt) for tt in t]), plan.sample(t)[2], rtol=0, atol=1e-15)
    command = plan.torque_command()
    np.testing.assert_array_equal(command.breakpoints, plan.breakpoints_s)
    t_grid = np.linspace(0.0, plan.maneuver_time_s, 1001)
    track = propagate_attitude(scenario.inertia, command, scenario.q0, np.zeros(3), t_grid, rtol=1e-10, atol=1e-12)
    assert quat_angle_between(track.q[-1], scenario.qf) < 1e-9
    assert np.linalg.norm(track.omega[-1]) < 1e-11


@pytest.fixture(scope="module")
def flat_paper_plan():
    spec = load_problem(PROBLEMS / "cai2018_flat_attitude.yaml")
    outcome = planning_setup(spec).solve()
    return outcome.program.problem, outcome.x, spec.verification


def test_barycentric_torque_equals_interpolation_matrix(flat_paper_plan):
    problem, x, _ = flat_paper_plan
    command = torque_command(problem, x)
    t = np.concatenate([np.linspace(problem.t0, problem.tf, 501), problem.node_times])
    np.testing.assert_allclose(np.array([command(tt) for tt in t]), command.sample(t), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(command(problem.node_times[3]), problem.torques(x)[3])
    assert command.breakpoints.size == 0


def test_flat_verification_unchanged_on_paper_case(flat_paper_plan):
    """One integration with the tolerances only, against the former run with steps capped at tf/200.

    Measured: final attitude error 5.78e-9 rad against 6.15e-9 rad (the former run, 1e-13 from a tight
    reference), 3.7e-10 rad apart; worst torque equal, worst cone angle 9e-11 relative.
    """
    problem, x, settings = flat_paper_plan
    verification, _ = verify_plan(problem, x, settings)
    t_grid = np.linspace(problem.t0, problem.tf, settings.grid_points)
    command = torque_command(problem, x)
    former = propagate_attitude(problem.inertia, lambda t: command(t), euler321_to_quat(problem.rpy0), problem.rate0,
                                t_grid, settings.rtol, settings.atol, max_step=(problem.tf - problem.t0) / 200)
    attitude_error = quat_angle_between(former.q[-1], euler321_to_quat(problem.rpyf))
    assert verification.passed
    assert verification.final_errors["final_attitude_error_rad"] == pytest.approx(attitude_error, abs=1e-9)
    worst = {c.name: c.worst for c in verification.checks}
    assert worst["torque_Nm"] == pytest.approx(np.abs(former.torque).max(), rel=1e-12)
    cone = problem.cones[0]
    assert worst[f"keep_out_{cone.name}_deg"] == pytest.approx(cone.angles_deg(former.q).min(), rel=1e-8)
