"""Path-transfer planner (seed 003, Wang, Xu, Li): reference slew, actions, bounds and re-propagation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from convexguid.errors import SpecError
from convexguid.families.quaternion_attitude.path_transfer import (
    PathTransferProblem,
    bound_evaluation,
    multicone_scenario,
    plan_path_transfer,
    pointing_evaluation,
    relaxed_node_count,
)
from convexguid.geometry import PointingCone, eigenaxis_path, eigenaxis_rotation, keep_out_angles_deg
from convexguid.rotations import axis_angle_to_quat, quat_angle_between, quat_derivative
from convexguid.verification import propagate_attitude

REL = 1e-9  # round-off allowance on the torque and rate boxes


@pytest.fixture(scope="module")
def scenario() -> PathTransferProblem:
    return multicone_scenario()


@pytest.fixture(scope="module")
def plan(scenario):
    return plan_path_transfer(scenario)


def dense_grid(result, step: float = 0.02) -> np.ndarray:
    return np.union1d(np.arange(0.0, result.maneuver_time_s, step), result.breakpoints_s)


def cone_margins_deg(problem, q) -> np.ndarray:
    return np.array([keep_out_angles_deg(q, problem.boresight_body, c.inertial_dir).min()
                     - math.degrees(c.half_angle_rad) for c in problem.cones])


def single_cone_problem(direction, half_angle_deg: float = 10.0, **kw) -> PathTransferProblem:
    """90 deg slew about body x: the +z boresight sweeps from inertial +z to -y."""
    return PathTransferProblem(
        inertia=np.diag([10.0, 12.0, 15.0]), boresight_body=[0, 0, 1], q0=[0, 0, 0, 1],
        qf=axis_angle_to_quat([1, 0, 0], math.pi / 2), cones=(PointingCone("c", [0, 0, 1], direction,
                                                                               math.radians(half_angle_deg)),),
        torque_max=0.1, rate_max=math.radians(3.0), **kw)


def test_pointing_evaluation_sign():
    half = math.radians(20)
    assert pointing_evaluation(half + 0.1, half) < 0 < pointing_evaluation(half - 0.1, half)
    assert pointing_evaluation(half, half) == pytest.approx(0.0, abs=1e-15)
    assert np.all(np.diff(pointing_evaluation(np.linspace(0, math.pi, 50), half)) < 0)


def test_eigenaxis_path_geometry(scenario):
    path = eigenaxis_path(scenario.q0, scenario.qf, 41)
    np.testing.assert_allclose(path[0], scenario.q0, atol=1e-15)
    assert quat_angle_between(path[-1], scenario.qf) < 1e-12
    np.testing.assert_allclose(quat_angle_between(path[:-1], path[1:]), math.radians(4.0), atol=1e-12)
    axis, angle = eigenaxis_rotation(scenario.q0, scenario.qf)
    np.testing.assert_allclose(axis, np.array([1, -1, 0.5]) / 1.5, atol=1e-12)
    assert angle == pytest.approx(math.radians(160), abs=1e-12)
    # the unwinding fix (eqs. 18-19): -qf is the same attitude, still 160 deg and not 200 deg
    assert eigenaxis_rotation(scenario.q0, -scenario.qf)[1] == pytest.approx(math.radians(160), abs=1e-12)


def test_eigenaxis_slew_breaks_cones_1_and_2(scenario, plan):
    q = eigenaxis_path(scenario.q0, scenario.qf, 641)
    margins = cone_margins_deg(scenario, q)
    assert margins[0] < 0 and margins[1] < 0
    assert margins[2] > 0 and margins[3] > 0
    half = np.degrees(scenario.half_angles)
    np.testing.assert_allclose(plan.reference_min_angle_deg - half, margins, atol=0.05)


def test_scenario_plan_meets_cones_bounds_and_target(scenario, plan):
    assert plan.actions == ("circumvent", "none", "none", "none")
    assert plan.min_cone_margin_deg >= math.degrees(scenario.margin_rad) - 1e-9
    t = dense_grid(plan)
    q, omega, torque = plan.sample(t)
    assert cone_margins_deg(scenario, q).min() >= math.degrees(scenario.margin_rad) - 1e-6
    assert np.abs(torque).max() <= scenario.torque_max * (1 + REL)
    assert np.abs(omega).max() <= scenario.rate_max * (1 + REL)
    assert np.abs(plan.torque).max() <= scenario.torque_max * (1 + REL)
    assert quat_angle_between(plan.q[-1], scenario.qf) < 1e-10
    assert np.abs(plan.omega[[0, -1]]).max() < 1e-12
    np.testing.assert_allclose(plan.t, np.arange(plan.t.size) * scenario.node_period_s)
    assert plan.t[-1] == pytest.approx(plan.maneuver_time_s)
    assert plan.maneuver_time_s > plan.reference_maneuver_time_s
    assert 0 < plan.planning_time_s < 5.0
    for seg, a, b in zip(plan.segments, plan.waypoints[:-1], plan.waypoints[1:], strict=True):
        assert eigenaxis_rotation(a, b)[1] == pytest.approx(seg.angle_rad, abs=1e-9)  # legs: shortest rotations


def test_sample_is_consistent_with_kinematics_and_dynamics(scenario, plan):
    q_nodes, omega_nodes, torque_nodes = plan.sample(plan.t)
    np.testing.assert_allclose(q_nodes, plan.q)
    t = np.linspace(0.3, plan.maneuver_time_s - 0.3, 400)
    h = 1e-5
    qp, wp, _ = plan.sample(t + h)
    qm, wm, _ = plan.sample(t - h)
    q, w, u = plan.sample(t)
    smooth = np.min(np.abs(t[:, None] - plan.breakpoints_s[None]), axis=1) > 2 * h
    np.testing.assert_allclose(((qp - qm) / (2 * h))[smooth], quat_derivative(q, w)[smooth], atol=1e-8)
    u_fd = (wp - wm) / (2 * h) @ scenario.inertia.T + np.cross(w, w @ scenario.inertia.T)
    np.testing.assert_allclose(u_fd[smooth], u[smooth], atol=1e-8)
    q_one, w_one, u_one = plan.sample(10.0)
    assert q_one.shape == (4,) and w_one.shape == (3,) and u_one.shape == (3,)
    q_after, w_after, u_after = plan.sample(plan.maneuver_time_s + 5.0)
    assert quat_angle_between(q_after, scenario.qf) < 1e-10 and not w_after.any() and not u_after.any()


def test_propagated_closed_form_torque_reaches_target(scenario, plan):
    """Open loop, DOP853 rtol 1e-10: measured final attitude error 2.3e-8 rad; tolerance 1e-6 rad."""
    t = np.linspace(0.0, plan.maneuver_time_s, 1001)
    track = propagate_attitude(scenario.inertia, plan.torque_at, scenario.q0, np.zeros(3), t,
                               rtol=1e-10, atol=1e-12, max_step=0.5)
    assert quat_angle_between(track.q[-1], scenario.qf) < 1e-6
    assert np.linalg.norm(track.omega[-1]) < 1e-7
    assert cone_margins_deg(scenario, track.q).min() > math.degrees(scenario.margin_rad) - 1e-4


def test_propagated_torque_interpolant_reaches_target(scenario, plan):
    """Linear interpolant of the torque sampled every 0.05 s plus both sides of every jump.

    Measured final attitude error 2.9e-4 deg (the chords of the quadratic gyroscopic torque bias the
    integral); tolerance 2e-3 deg. On the plain 0.5 s node grid, which smears every jump over a node period,
    the same open-loop propagation drifts 7.3 deg: put interpolation nodes at ``breakpoints_s``.
    """
    eps = 1e-9
    bp = plan.breakpoints_s
    grid = np.unique(np.clip(np.concatenate([np.arange(0, plan.maneuver_time_s, 0.05), bp - eps, bp + eps,
                                             [plan.maneuver_time_s]]), 0.0, plan.maneuver_time_s))
    samples = plan.sample(grid)[2]

    def torque(tt: float) -> np.ndarray:
        return np.array([np.interp(tt, grid, samples[:, i]) for i in range(3)])

    t = np.linspace(0.0, plan.maneuver_time_s, 501)
    track = propagate_attitude(scenario.inertia, torque, scenario.q0, np.zeros(3), t, rtol=1e-10, atol=1e-12,
                               max_step=0.5)
    assert math.degrees(quat_angle_between(track.q[-1], scenario.qf)) < 2e-3
    assert np.linalg.norm(track.omega[-1]) < 1e-5


def test_relaxed_node_count_is_smallest_feasible(scenario):
    axis, angle = eigenaxis_rotation(scenario.q0, scenario.qf)
    n_ref, ramp, dt = 51, 0.2, scenario.node_period_s
    ju, jw = bound_evaluation(scenario.inertia, axis, angle, ramp, (n_ref - 1) * dt, scenario.torque_max,
                              scenario.rate_max)
    nodes = relaxed_node_count(ju, jw, n_ref)

    def worst(n: int) -> float:
        return max(bound_evaluation(scenario.inertia, axis, angle, ramp, (n - 1) * dt, scenario.torque_max,
                                    scenario.rate_max))

    assert worst(nodes) <= 1e-12 < worst(nodes - 1)
    assert relaxed_node_count(ju, jw, n_ref, weight=1.5) > nodes


def test_circumvent_and_none_actions():
    on_path = single_cone_problem([0, -1, 1])
    result = plan_path_transfer(on_path)
    assert result.actions == ("circumvent",)
    assert result.reference_min_angle_deg[0] < 10.0
    assert result.min_cone_margin_deg >= math.degrees(on_path.margin_rad) - 1e-9
    assert quat_angle_between(result.q[-1], on_path.qf) < 1e-10
    off_path = plan_path_transfer(single_cone_problem([1, 0, 0]))
    assert off_path.actions == ("none",) and off_path.waypoints.shape == (2, 4)
    assert off_path.maneuver_time_s == pytest.approx(off_path.reference_maneuver_time_s)


@pytest.mark.parametrize("problem", [
    single_cone_problem([0, -1, 1], node_period_s=10.0),
    multicone_scenario(node_period_s=10.0),
], ids=["single-cone", "scenario"])
def test_back_off_action_with_coarse_nodes(problem):
    """With 10 s node spacing a relaxed-path node jumps into the cone: back off one node, then circumvent."""
    result = plan_path_transfer(problem)
    assert "back_off_circumvent" in result.actions
    t = dense_grid(result, 0.05)
    q, omega, torque = result.sample(t)
    assert cone_margins_deg(problem, q).min() >= math.degrees(problem.margin_rad) - 1e-6
    assert np.abs(torque).max() <= problem.torque_max * (1 + REL)
    assert np.abs(omega).max() <= problem.rate_max * (1 + REL)
    assert quat_angle_between(result.q[-1], problem.qf) < 1e-10


def test_no_maneuver_when_q0_equals_qf():
    problem = single_cone_problem([1, 0, 0])
    result = plan_path_transfer(PathTransferProblem(**{**problem.__dict__, "qf": problem.q0}))
    assert result.maneuver_time_s == 0.0 and result.q.shape == (1, 4) and not result.segments


@pytest.mark.parametrize(("change", "match"), [
    ({"q0": [0, 0, 0, 0]}, "q0"),
    ({"qf": [0.0, 0.0, 0.0, 0.0]}, "qf"),
    ({"torque_max": 0.0}, "torque_max"),
    ({"rate_max": -1.0}, "rate_max"),
    ({"cones": (PointingCone("sun", [0, 0, 1], [0, 0, 1], 0.2),)}, "initial boresight is inside cone 'sun'"),
    ({"cones": (PointingCone("sun", [0, 0, 1], [0, -1, 0], 0.2),)}, "final boresight is inside cone 'sun'"),
    ({"inertia": np.diag([1.0, -1.0, 1.0])}, "inertia"),
    ({"boresight_body": [0, 0, 0]}, "boresight_body"),
])
def test_bad_input_raises_spec_error(change, match):
    base = single_cone_problem([1, 0, 0]).__dict__
    with pytest.raises(SpecError, match=match) as info:
        PathTransferProblem(**{**base, **change})
    assert "\n" not in str(info.value)


def test_bad_cone_and_path_arguments():
    with pytest.raises(SpecError, match="half_angle_rad"):
        PointingCone("x", [0, 0, 1], [1, 0, 0], 0.0)
    with pytest.raises(SpecError, match="inertial_dir"):
        PointingCone("x", [0, 0, 1], [0, 0, 0], 0.1)
    with pytest.raises(SpecError, match="n must be"):
        eigenaxis_path([0, 0, 0, 1], [0, 0, 1, 0], 1)
    with pytest.raises(SpecError, match="q0"):
        eigenaxis_path([0, 0, 0, 0], [0, 0, 1, 0], 5)
