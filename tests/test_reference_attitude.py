"""Cross-check the quaternion attitude transcription against an independent IPOPT solve of the same NLP.

The IPOPT reference (:mod:`convexguid.families.quaternion_attitude.reference`) writes the rigid-body dynamics,
the Hermite-Simpson defects, the cone cosines and the forbidden-attitude rows again in CasADi;
its optima must satisfy the numpy transcription's constraints
(:func:`~convexguid.families.quaternion_attitude.program.transcribe_slew`), respect bounds that
hold for any feasible slew, and clear every cone of the multi-cone scenario of docs/parameters.md.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("casadi")

from convexguid.families.quaternion_attitude.program import (  # noqa: E402
    AttitudeCase,
    Forbidden,
    Slew,
    cone_cosine,
    eigenaxis_start,
    transcribe_slew,
)
from convexguid.families.quaternion_attitude.reference import solve_quaternion_attitude_ipopt  # noqa: E402
from convexguid.families.quaternion_attitude.solve import build_case  # noqa: E402
from convexguid.geometry import PointingCone, keep_out_angles_deg  # noqa: E402
from convexguid.problem_files import load_problem
from convexguid.rotations import axis_angle_to_quat, quat_angle_between  # noqa: E402

MULTICONE = Path(__file__).resolve().parents[1] / "problems" / "wang_multicone_time.yaml"
DEFECT_TOL = 1e-6
"""Largest scaled Hermite-Simpson defect of the numpy transcription at IPOPT's optimum."""
CONSTRAINT_TOL = 1e-7
"""Largest violation of a box, boundary, cone (cosine) or forbidden-attitude row at IPOPT's optimum."""
K_SMALL = 20


def _rest_to_rest(inertia: np.ndarray, angle: float = np.pi / 2, **extra) -> AttitudeCase:
    """A rest-to-rest slew by ``angle`` about body z, torque 0.1 N m and rate 3 deg/s per axis."""
    return AttitudeCase("rest_to_rest", np.asarray(inertia, dtype=float), 0.1, np.radians(3.0), 0.0,
                        np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), axis_angle_to_quat([0, 0, 1], angle),
                        np.zeros(3), **extra)


def _assert_satisfies_program(slew: Slew, x: np.ndarray) -> None:
    """The family's program (the case stated on convexguid.ocp) holds at the reference's node rows ``x``: its
    defects, boundary rows, boxes, cones and forbidden rows."""
    program, x = slew.program, slew.from_node_rows(x)
    ev = program.evaluate(x, jacobians=False)
    for block in ev.equalities:
        assert np.max(np.abs(block.values)) < DEFECT_TOL, block.name
    for block in ev.inequalities:
        assert np.max(block.values) < CONSTRAINT_TOL, block.name
    lin = program.linear_constraints()
    assert np.max(np.abs(lin.A @ x - lin.b)) < CONSTRAINT_TOL
    assert np.max(lin.G @ x - lin.h) < CONSTRAINT_TOL


@pytest.fixture(scope="module")
def no_cone_time():
    case = _rest_to_rest(np.diag([10.0, 12.0, 15.0]))
    guess, tf_guess = eigenaxis_start(case, K_SMALL)
    result = solve_quaternion_attitude_ipopt(case, K_SMALL, guess, tf_guess)
    print(f"no-cone minimum time {result.objective:.6f} s ({result.status}, {result.iterations} it, "
          f"{result.wall_time_s:.3f} s)")
    return case, guess, tf_guess, result


def test_minimum_time_satisfies_the_numpy_transcription(no_cone_time):
    case, guess, tf_guess, result = no_cone_time
    assert result.success, result.status
    slew = transcribe_slew(case, K_SMALL, guess, tf_guess)
    assert slew.from_node_rows(result.x).shape == (slew.program.num_variables,)
    assert result.objective == pytest.approx(slew.program.final_time(slew.from_node_rows(result.x)))
    _assert_satisfies_program(slew, result.x)


def test_minimum_time_lies_between_physical_bounds(no_cone_time):
    """At most the (feasible) eigenaxis guess's duration; at least angle / max |omega| = angle / (sqrt(3) rate_max)."""
    case, _, tf_guess, result = no_cone_time
    assert result.objective <= tf_guess
    assert result.objective >= (np.pi / 2) / (np.sqrt(3.0) * case.rate_max)


def test_full_inertia_keep_in_and_forbidden_attitude():
    """Off-diagonal inertia, a keep-in cone and a forbidden attitude, with a 1 deg node margin.

    With products of inertia the minimum-time slew tilts body z by about 34 deg and passes within
    about 34 deg of the eigenaxis midpoint :math:`R_z(45^\\circ)`; forbidding 38 deg around that
    midpoint and keeping body z within 40 deg of inertial z makes both constraints active
    (at 38 + 1 and 40 - 1 deg with the margin).
    """
    inertia = np.array([[10.0, 1.0, 0.5], [1.0, 12.0, -0.3], [0.5, -0.3, 15.0]])
    zenith = np.array([0.0, 0.0, 1.0])
    case = _rest_to_rest(inertia, cones=(PointingCone("zenith", zenith, zenith, np.radians(40.0), keep_out=False),),
                         forbidden=(Forbidden("midway", axis_angle_to_quat([0, 0, 1], np.pi / 4), np.radians(38.0)),))
    guess, tf_guess = eigenaxis_start(case, K_SMALL)
    margin = np.radians(1.0)
    result = solve_quaternion_attitude_ipopt(case, K_SMALL, guess, tf_guess, margin=margin)
    assert result.success, result.status
    slew = transcribe_slew(case, K_SMALL, guess, tf_guess, margin)
    _assert_satisfies_program(slew, result.x)
    q = slew.nodes(slew.from_node_rows(result.x))[:, :4]
    q = q / np.linalg.norm(q, axis=1, keepdims=True)  # |q| drifts O(h^4) from 1: compare normalised attitudes
    closest = np.degrees(quat_angle_between(q, case.forbidden[0].q).min())
    widest = keep_out_angles_deg(q, zenith, zenith).max()
    print(f"full inertia: {result.objective:.6f} s, closest to forbidden {closest:.5f} deg, "
          f"widest from zenith {widest:.5f} deg")
    assert closest == pytest.approx(39.0, abs=1e-3)
    assert widest == pytest.approx(39.0, abs=1e-3)


def test_energy_decreases_with_the_final_time():
    """Fixed-time energy; time scaling a feasible slew by s divides its energy by s^3, so E(70) <= E(50) (5/7)^3."""
    base = _rest_to_rest(np.diag([10.0, 12.0, 15.0]))
    energies = []
    for tf in (50.0, 70.0):
        case = replace(base, tf=tf)
        guess, _ = eigenaxis_start(case, K_SMALL)
        result = solve_quaternion_attitude_ipopt(case, K_SMALL, guess, tf)
        assert result.success, result.status
        slew = transcribe_slew(case, K_SMALL, guess, tf)
        assert slew.from_node_rows(result.x).shape == (slew.program.num_variables,)
        _assert_satisfies_program(slew, result.x)
        ev = slew.program.evaluate(slew.from_node_rows(result.x), jacobians=False)
        assert result.objective == pytest.approx(np.sum(slew.program.residual_weights() * ev.residuals**2),
                                                 rel=1e-10)
        energies.append(result.objective)
    print(f"energy: tf=50 s {energies[0]:.8g}, tf=70 s {energies[1]:.8g}")
    assert energies[1] < energies[0]
    assert energies[1] <= energies[0] * (50.0 / 70.0) ** 3 * (1 + 1e-6)


def test_multicone_minimum_time_clears_every_cone():
    """The four-cone scenario (docs/parameters.md) from the (cone-crossing) eigenaxis guess, K = 30."""
    case = build_case(load_problem(MULTICONE, []))
    intervals = 30
    guess, tf_guess = eigenaxis_start(case, intervals)
    result = solve_quaternion_attitude_ipopt(case, intervals, guess, tf_guess)
    print(f"multicone K={intervals}: minimum time {result.objective:.6f} s ({result.status}, {result.iterations} it, "
          f"solve {result.wall_time_s:.3f} s, setup {result.setup_time_s:.3f} s)")
    assert result.success, result.status
    slew = transcribe_slew(case, intervals, guess, tf_guess)
    _assert_satisfies_program(slew, result.x)
    q = slew.nodes(slew.from_node_rows(result.x))[:, :4]
    assert len(case.cones) == 4
    for cone in case.cones:
        cosine, _ = cone_cosine(cone, q)
        assert np.all(cosine <= np.cos(cone.half_angle_rad) + CONSTRAINT_TOL), cone.name
