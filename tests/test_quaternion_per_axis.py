"""Quaternion attitude with a per-axis torque box and Z-Y-X Euler boundary attitudes: Feng, Chen, Yang (2018).

``spacecraft.torque_max_Nm`` is one number or three (x, y, z); ``boundary.initial``/``final`` may be
``roll_pitch_yaw_deg``. The nominal of ``problems/feng2018_nominal.yaml`` is planned, verified per axis and
compared with IPOPT on the same transcription; a single bound still gives the single check ``torque_Nm``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from convexguid.api import solve
from convexguid.errors import SpecError
from convexguid.families.quaternion_attitude.program import (
    AttitudeCase,
    eigenaxis_guess,
    eigenaxis_start,
    eigenaxis_time_guess,
    transcribe_slew,
)
from convexguid.families.quaternion_attitude.solve import build_case, path_transfer_problem, scp_settings
from convexguid.problem_files import load_problem
from convexguid.rotations import axis_angle_to_quat, quat_angle_between, quat_to_euler321
from convexguid.scp.engine import solve_scp
from convexguid.verification import TORQUE_AXIS_CHECKS, AttitudeTrack, torque_box_checks, verify_attitude_track

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
FENG = PROBLEMS / "feng2018_nominal.yaml"
FENG_BOX = (5.0, 10.0, 10.0)
TIGHT = ["spacecraft.torque_max_Nm=[0.5, 6.0, 10.0]"]
"""A box the Feng nominal (peaks about 0.74, 6.7, 7.4 N m) breaks on x and y: both bounds become active."""


@pytest.fixture(scope="module")
def nominal():
    return solve(FENG)


# --- problem file ---------------------------------------------------------------------------------------------

def test_feng_file_reads_the_paper_scenario():
    spec = load_problem(FENG)
    case = build_case(spec)
    assert spec.spacecraft.torque_max_Nm == FENG_BOX
    np.testing.assert_array_equal(case.torque_max, FENG_BOX)
    np.testing.assert_array_equal(np.diag(case.inertia), [5.0, 70.0, 70.0])
    np.testing.assert_allclose(np.degrees(quat_to_euler321(case.q0)), [60.0, -30.0, 75.0], atol=1e-12)
    np.testing.assert_allclose(np.degrees(quat_to_euler321(case.qf)), [0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.degrees(case.w0), 0.0)
    np.testing.assert_allclose(np.degrees(case.wf), [0.0, 1.0, -0.5])
    assert case.tf == 8.0 and spec.objective == "energy" and not case.cones


def test_roll_pitch_yaw_matches_axis_angle():
    """Yaw 90 deg (Z-Y-X) is a 90 deg rotation about z: the same scalar-last, body-to-inertial quaternion."""
    by_euler = load_problem(FENG, ["boundary.final={roll_pitch_yaw_deg: [0, 0, 90]}"]).boundary.final.q
    by_axis = load_problem(FENG, ["boundary.final={axis: [0, 0, 1], angle_deg: 90}"]).boundary.final.q
    np.testing.assert_allclose(by_euler, by_axis, atol=1e-15)
    np.testing.assert_allclose(by_euler, axis_angle_to_quat([0, 0, 1], np.pi / 2), atol=1e-15)
    assert float(quat_angle_between(by_euler, by_axis)) < 1e-12


@pytest.mark.parametrize("final", [
    "{quaternion: [0, 0, 0, 1], roll_pitch_yaw_deg: [0, 0, 0]}",
    "{axis: [0, 0, 1], angle_deg: 90, roll_pitch_yaw_deg: [0, 0, 90]}",
    "{angle_deg: 90, roll_pitch_yaw_deg: [0, 0, 90]}",
    "{rate_degps: [0, 1, -0.5]}",
])
def test_attitude_needs_exactly_one_form(final):
    with pytest.raises(SpecError) as err:
        load_problem(FENG, [f"boundary.final={final}"])
    message = str(err.value)
    assert "\n" not in message and "boundary.final" in message and "roll_pitch_yaw_deg" in message


@pytest.mark.parametrize("value,needle", [
    ("[5, 0, 10]", "torque_max_Nm.1"), ("[5, 10]", "torque_max_Nm"), ("0", "torque_max_Nm"),
    ("-1", "torque_max_Nm"), ("[5, 10, .inf]", "torque_max_Nm.2"), ("'5'", "torque_max_Nm"),
])
def test_bad_torque_box_is_a_one_line_error(value, needle):
    with pytest.raises(SpecError) as err:
        load_problem(FENG, [f"spacecraft.torque_max_Nm={value}"])
    message = str(err.value)
    assert "\n" not in message and f"spacecraft.{needle}:" in message and FENG.name in message


def test_a_single_bound_becomes_three_and_dumps_as_given():
    spec = load_problem(FENG, ["spacecraft.torque_max_Nm=2"])
    assert spec.spacecraft.torque_max_Nm == 2.0 and spec.spacecraft.model_dump()["torque_max_Nm"] == 2.0
    np.testing.assert_array_equal(build_case(spec).torque_max, [2.0, 2.0, 2.0])
    case = AttitudeCase("scalar", np.eye(3), 0.1, 0.1, 0.0, np.array([0, 0, 0, 1.0]), np.zeros(3),
                        np.array([0, 0, 0, 1.0]), np.zeros(3))
    assert case.torque_max.shape == (3,) and not case.torque_max.flags.writeable
    np.testing.assert_array_equal(replace(case, tf=5.0).torque_max, [0.1, 0.1, 0.1])


# --- the per-axis box inside ----------------------------------------------------------------------------------

def test_program_rows_and_scales_are_per_axis():
    case = build_case(load_problem(FENG))
    guess, tf = eigenaxis_start(case, 6)
    program = transcribe_slew(case, 6, guess, tf).program
    torques = slice(program.control_start, program.slack_start)  # the node torques, node by node
    np.testing.assert_array_equal(program.variable_scale()[torques].reshape(7, 3), np.tile(FENG_BOX, (7, 1)))
    lin = program.linear_constraints()
    # node 0's torque columns: +u <= box, -u <= box
    torque_rows = lin.G.tocsr()[:, program.control_start: program.control_start + 3]
    hit = np.flatnonzero(np.abs(torque_rows).sum(axis=1).A1)
    np.testing.assert_array_equal(lin.h[hit], np.concatenate([FENG_BOX, FENG_BOX]))
    assert path_transfer_problem(case).torque_max == 5.0  # the planner takes the tightest (smallest) bound


def test_eigenaxis_time_is_set_by_the_tightest_axis():
    """Rest to rest about (1, 1, 0): y needs 70/sqrt(2) N m per rad/s^2 against x's 5/sqrt(2), so y's 10 N m binds.

    The cubic profile then peaks at exactly the y bound (gyroscopic torque is on z alone), x stays well inside.
    """
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    case = AttitudeCase("tightest", np.diag([5.0, 70.0, 70.0]), np.array(FENG_BOX), 10.0, 0.0,
                        np.array([0, 0, 0, 1.0]), np.zeros(3), axis_angle_to_quat(axis, np.pi / 2), np.zeros(3))
    T = eigenaxis_time_guess(case)
    assert T == pytest.approx(np.sqrt(6 * (np.pi / 2) / (10.0 / (70.0 / np.sqrt(2)))), rel=1e-12)
    peak = np.abs(eigenaxis_guess(case, np.linspace(0.0, T, 2001))[:, 7:]).max(axis=0)
    assert peak[1] == pytest.approx(10.0, rel=1e-9)
    assert peak[0] < 5.0 and peak[2] < 10.0


def test_torque_checks_are_one_for_equal_bounds_and_three_otherwise():
    torque = np.array([[0.5, -3.0, 2.0], [-1.0, 1.0, -4.0]])
    for equal in (4.0, [4.0, 4.0, 4.0], np.full(3, 4.0)):
        (check,) = torque_box_checks(torque, equal)
        assert (check.name, check.worst, check.bound) == ("torque_Nm", 4.0, 4.0)
    checks = torque_box_checks(torque, [0.8, 5.0, 5.0])
    assert [(c.name, c.worst, c.bound) for c in checks] == [
        ("torque_x_Nm", 1.0, 0.8), ("torque_y_Nm", 3.0, 5.0), ("torque_z_Nm", 4.0, 5.0)]
    assert checks[0].violation == pytest.approx(0.2) and checks[1].violation == 0.0
    track = AttitudeTrack(np.array([0.0, 1.0]), np.tile([0, 0, 0, 1.0], (2, 1)), np.zeros((2, 3)), torque)
    verification = verify_attitude_track(track, [0.8, 5.0, 5.0], (), np.array([0, 0, 0, 1.0]), np.zeros(3),
                                         1e-6, 1e-3, 1e-4)
    assert not verification.passed and set(verification.to_dict()["constraints"]) == set(TORQUE_AXIS_CHECKS)


# --- the Feng nominal -----------------------------------------------------------------------------------------

def test_feng_nominal_is_planned_and_verified_per_axis(nominal):
    assert nominal.status == "converged" and nominal.ok, nominal.message
    assert nominal.verification.passed
    constraints = nominal.verification.to_dict()["constraints"]
    assert list(constraints) == [*TORQUE_AXIS_CHECKS, "rate_degps"]
    for name, bound in zip(TORQUE_AXIS_CHECKS, FENG_BOX, strict=True):
        assert constraints[name]["bound"] == bound
        assert constraints[name]["worst"] <= bound
    dense = nominal.dense.columns
    for i, bound in enumerate(FENG_BOX):
        assert np.abs(dense[f"u{i + 1}_Nm"]).max() <= bound
    # the 200 deg/s rate bound of the file is ours, chosen not to bind
    assert constraints["rate_degps"]["worst"] < 0.2 * constraints["rate_degps"]["bound"]
    assert nominal.figures.energy == pytest.approx(nominal.objective, rel=1e-5)
    assert nominal.figures.max_quaternion_norm_error < 1e-4


def test_an_active_per_axis_box_is_met_on_each_axis():
    sol = solve(FENG, TIGHT)
    assert sol.ok, sol.message
    checks = {c.name: c for c in sol.verification.checks}
    assert "torque_Nm" not in checks
    for name, bound, active in zip(TORQUE_AXIS_CHECKS, (0.5, 6.0, 10.0), (True, True, False), strict=True):
        assert checks[name].bound == bound
        assert checks[name].worst <= bound * (1 + 1e-6)
        assert (checks[name].worst > bound * (1 - 1e-3)) == active, name


@pytest.mark.parametrize("box", ["10", "[10, 10, 10]"])
def test_equal_bounds_keep_the_single_torque_check(tmp_path, box):
    path = tmp_path / "scalar.yaml"
    path.write_text(FENG.read_text().replace("torque_max_Nm: [5.0, 10.0, 10.0]", f"torque_max_Nm: {box}"))
    sol = solve(path)
    assert sol.ok, sol.message
    assert list(sol.verification.to_dict()["constraints"]) == ["torque_Nm", "rate_degps"]
    assert sol.verification.checks[0].bound == 10.0


@pytest.mark.parametrize("overrides", [[], TIGHT], ids=["nominal", "active_box"])
def test_energy_matches_ipopt_on_the_same_transcription(overrides):
    pytest.importorskip("casadi")
    from convexguid.families.quaternion_attitude.reference import solve_quaternion_attitude_ipopt

    spec = load_problem(FENG, overrides)
    case, intervals = build_case(spec), spec.discretization.intervals
    guess, tf = eigenaxis_start(case, intervals)
    slew = transcribe_slew(case, intervals, guess, tf)
    program = slew.program
    result = solve_scp(program, scp_settings(spec.solver))
    assert result.status == "converged"
    ref = solve_quaternion_attitude_ipopt(case, intervals, guess, tf)
    assert ref.success, ref.status
    print(f"Feng {overrides or 'nominal'}: SCP energy {result.objective:.6f}, IPOPT {ref.objective:.6f} "
          f"({ref.iterations} it)")
    assert abs(result.objective - ref.objective) <= 5e-3 * ref.objective
    lin = program.linear_constraints()
    # IPOPT's optimum meets the per-axis rows of the family's program
    assert np.max(lin.G @ slew.from_node_rows(ref.x) - lin.h) < 1e-7


def test_torque_plot_draws_each_axis_bound(nominal, tmp_path, monkeypatch):
    import matplotlib.axes

    from convexguid.solution_plots import plot_solution

    drawn = []
    original = matplotlib.axes.Axes.axhline

    def record(self, y=0, *args, **kwargs):
        drawn.append((self.get_title(), y, kwargs.get("label")))
        return original(self, y, *args, **kwargs)

    monkeypatch.setattr(matplotlib.axes.Axes, "axhline", record)
    paths = plot_solution(nominal, tmp_path)
    assert {p.stem for p in paths} == {"quaternion", "torques", "body_rates"}
    limits = {label: y for _, y, label in drawn if label and label.endswith(" limit")}
    assert limits == {"u1 limit": 5.0, "u2, u3 limit": 10.0}
