"""Plots of the quaternion_attitude family: files written, sky projection, wrap splitting, cone circles."""

from __future__ import annotations

import numpy as np
import pytest

from convexguid.families.quaternion_attitude.figures import ConeGeometry, QuaternionAttitudeFigures
from convexguid.families.quaternion_attitude.plots import (
    az_el_deg,
    cone_circle,
    cone_curves,
    inertial_axis,
    sky_cones,
    sky_coordinates,
    split_at_wrap,
    tracked_axes,
)
from convexguid.geometry import eigenaxis_path, keep_out_angles_deg
from convexguid.rotations import dcm_to_quat, quat_conjugate, quat_multiply, quat_sign_continuous
from convexguid.scp.problem import ProgramSize
from convexguid.solution import Solution, Trajectory
from convexguid.solution_plots import plot_solution
from convexguid.verification import ConstraintCheck, Verification

SUN = ConeGeometry("sun", (0, 0, 1), (-np.cos(np.radians(10)), 0, np.sin(np.radians(10))), 20.0, True)
EARTH = ConeGeometry("earth", (1, 0, 0), (0, 0, -1), 60.0, False)
FILES = {"boresight_sky", "boresight_sphere_3d", "quaternion", "body_rates", "torques", "cone_angles"}


def _rot(axis: int, angle_deg: float) -> np.ndarray:
    """Active rotation matrix about a coordinate axis."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def _attitudes(az_deg: np.ndarray, el_deg: np.ndarray) -> np.ndarray:
    """Quaternions whose body +z points at (az, el) and body +x towards the south: C_IB = Rz(az) Ry(-el) Ry(90)."""
    c_ib = np.stack([_rot(2, a) @ _rot(1, -e) @ _rot(1, 90.0) for a, e in zip(az_deg, el_deg, strict=True)])
    return quat_sign_continuous(dcm_to_quat(np.transpose(c_ib, (0, 2, 1))))


def _solution(with_nodes: bool = True, cones: bool = True) -> Solution:
    """120 deg slew of the +z boresight from azimuth 120 to 240 deg round the sun cone at azimuth 180 deg."""
    t = np.linspace(0.0, 60.0, 241)
    s = t / t[-1]
    q = _attitudes(120.0 + 120.0 * s, 10.0 + 35.0 * np.sin(np.pi * s))
    dq = np.gradient(q, t, axis=0)
    omega = 2 * quat_multiply(quat_conjugate(q), dq)[:, :3]
    torque = np.gradient(omega, t, axis=0) * np.array([10.0, 12.0, 8.0])
    cols = {f"q{i + 1}": q[:, i] for i in range(4)}
    cols |= {f"omega{i + 1}_degps": np.degrees(omega[:, i]) for i in range(3)}
    cols |= {f"u{i + 1}_Nm": torque[:, i] for i in range(3)}
    for cone in (SUN, EARTH):
        kind = "keep_out" if cone.keep_out else "keep_in"
        cols[f"{kind}_{cone.name}_deg"] = keep_out_angles_deg(q, np.array(cone.body_axis, float),
                                                              np.array(cone.inertial_dir))
    checks = (ConstraintCheck("torque_Nm", float(np.abs(torque).max()), 0.5, "max"),
              ConstraintCheck("rate_degps", float(np.degrees(np.abs(omega).max())), 5.0, "max"))
    nodes = Trajectory(t[::20], {k: v[::20] for k, v in cols.items()}) if with_nodes else None
    return Solution(
        problem="synthetic_slew", family="quaternion_attitude", method="scp" if with_nodes else "path_transfer",
        status="converged", objective=1.0, iterations=3, size=ProgramSize(10, 5, 5), wall_time_s=0.1,
        solver="none", verification=Verification(len(t), checks, 0.0, {}, True), nodes=nodes,
        dense=Trajectory(t, cols),
        figures=QuaternionAttitudeFigures(eigenaxis_min_angle_deg={"sun": 0.0}, cones=(SUN, EARTH)) if cones else None)


@pytest.mark.parametrize("with_nodes", [True, False])
def test_every_png_is_written(tmp_path, with_nodes):
    paths = plot_solution(_solution(with_nodes), tmp_path)
    assert {p.stem for p in paths} == FILES
    for p in paths:
        assert p.exists() and p.stat().st_size > 1000


def test_without_cone_geometry_only_histories_and_angles(tmp_path):
    paths = plot_solution(_solution(cones=False), tmp_path)
    assert {p.stem for p in paths} == FILES - {"boresight_sky", "boresight_sphere_3d"}


@pytest.mark.parametrize(("v", "az", "el"), [
    ([1, 0, 0], 0, 0), ([0, 1, 0], 90, 0), ([-1, 0, 0], 180, 0), ([0, -1, 0], -90, 0),
    ([0, 0, 1], 0, 90), ([0, 0, -1], 0, -90), ([1, 0, 1], 0, 45), ([-1, -1, -np.sqrt(2)], -135, -45),
    ([3, 0, 0], 0, 0),
])
def test_az_el_of_known_directions(v, az, el):
    got_az, got_el = az_el_deg(v)
    assert got_az == pytest.approx(az, abs=1e-12) and got_el == pytest.approx(el, abs=1e-12)


def test_inertial_axis_matches_the_cone_angle_convention():
    sol = _solution()
    q = np.column_stack([sol.dense.columns[f"q{i}"] for i in (1, 2, 3, 4)])
    boresight = inertial_axis(q, [0, 0, 1])
    az, el = az_el_deg(boresight[[0, -1]])
    np.testing.assert_allclose(az, [120.0, -120.0], atol=1e-9)
    np.testing.assert_allclose(el, [10.0, 10.0], atol=1e-9)
    angle = np.degrees(np.arccos(np.clip(boresight @ np.array(SUN.inertial_dir), -1, 1)))
    np.testing.assert_allclose(angle, sol.dense.columns["keep_out_sun_deg"], atol=1e-9)
    # yaw by +90 deg about z: body +x points along inertial +y
    np.testing.assert_allclose(inertial_axis([0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)], [1, 0, 0]),
                               [0, 1, 0], atol=1e-15)


def test_eigenaxis_slew_crosses_the_sun_and_the_wrap():
    """The synthetic slew is a rotation about inertial z: the boresight stays at 10 deg elevation."""
    sol = _solution()
    q = np.column_stack([sol.dense.columns[f"q{i}"] for i in (1, 2, 3, 4)])
    az, el = az_el_deg(inertial_axis(eigenaxis_path(q[0], q[-1], 121), [0, 0, 1]))
    np.testing.assert_allclose(el, 10.0, atol=1e-9)
    pieces = split_at_wrap(az, el)
    assert len(pieces) == 2
    assert pieces[0][0][-1] == 180.0 and pieces[1][0][0] == -180.0


def test_split_at_wrap_pieces_have_no_jump():
    az = np.array([150.0, 170.0, -170.0, -150.0, -179.0, 179.0, 160.0])
    el = np.array([0.0, 10.0, 30.0, 40.0, 50.0, 60.0, 70.0])
    pieces = split_at_wrap(az, el)
    assert len(pieces) == 3
    for a, _ in pieces:
        assert np.all(np.abs(np.diff(a)) <= 180.0) and np.all(np.abs(a) <= 180.0)
    (a0, e0), (a1, e1), (a2, e2) = pieces
    assert (a0[-1], a1[0], a1[-1], a2[0]) == (180.0, -180.0, -180.0, 180.0)
    assert e0[-1] == e1[0] == pytest.approx(20.0) and e1[-1] == e2[0] == pytest.approx(55.0)
    assert sum(len(a) for a, _ in pieces) == len(az) + 4


def test_points_at_a_pole_take_the_azimuth_of_their_neighbours():
    points = np.array([[0, 0, 1], [-0.1, -0.1, 1], [-0.5, 0.5, 0], [0, 0, -1]])
    az, el = sky_coordinates(points)
    np.testing.assert_allclose(az, [-135, -135, 135, 135], atol=1e-12)
    np.testing.assert_allclose(el[[0, 3]], [90, -90], atol=1e-12)
    np.testing.assert_array_equal(sky_coordinates(np.array([[0, 0, 1.0]]))[0], [0.0])


def test_split_at_wrap_keeps_a_continuous_curve_whole():
    az, el = np.linspace(-170, 170, 50), np.zeros(50)
    (a, e), = split_at_wrap(az, el)
    np.testing.assert_array_equal(a, az)


@pytest.mark.parametrize("direction", [[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 2, 0.5], [0.3, -0.2, -4]])
@pytest.mark.parametrize("half_angle", [0.5, 20.0, 90.0, 150.0])
def test_cone_circle_is_at_the_half_angle(direction, half_angle):
    pts = cone_circle(direction, half_angle)
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    angle = np.arctan2(np.linalg.norm(np.cross(pts, d), axis=1), pts @ d)
    np.testing.assert_allclose(angle, np.radians(half_angle), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(pts, axis=1), 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(pts[0], pts[-1], atol=1e-12)


def test_cone_circle_round_a_pole_wraps_once():
    az, el = az_el_deg(cone_circle([0, 0, 1], 30.0))
    np.testing.assert_allclose(el, 60.0, atol=1e-9)
    assert len(split_at_wrap(az, el)) <= 2


def test_tracked_axes_and_cone_curves():
    sol = _solution()
    cones = sky_cones(sol)
    axes = tracked_axes(cones)
    np.testing.assert_array_equal(axes[0], [0, 0, 1])
    np.testing.assert_array_equal(axes[1], [1, 0, 0])
    np.testing.assert_array_equal(tracked_axes([])[0], [0, 0, 1])
    curves = {c.column: c for c in cone_curves(sol, cones)}
    assert curves["keep_out_sun_deg"].limit == 20.0 and curves["keep_out_sun_deg"].eigenaxis_min == 0.0
    assert curves["keep_in_earth_deg"].limit == 60.0 and curves["keep_in_earth_deg"].color == cones[1].color
