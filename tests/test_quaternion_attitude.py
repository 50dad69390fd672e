"""Quaternion attitude family: Jacobians, the SCP against IPOPT, dense verification, bad input."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from convexguid.api import _spec, solve
from convexguid.errors import SpecError
from convexguid.families.quaternion_attitude.program import Slew, eigenaxis_start, transcribe_slew
from convexguid.families.quaternion_attitude.solve import build_case, scp_settings
from convexguid.problem_files import load_problem
from convexguid.rotations import quat_sign_continuous
from convexguid.scp.engine import solve_scp
from convexguid.spec import with_values

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MULTICONE = PROBLEMS / "wang_multicone_time.yaml"
GUO = PROBLEMS / "guo2011_scp_time.yaml"


def _slew(path: Path, intervals: int, overrides=(), tf: float | None = None) -> tuple[Slew, float, object]:
    """The slew from its eigenaxis start, that start's duration and the spec."""
    spec = _spec(path, list(overrides))
    case = build_case(spec)
    if tf is not None:
        case = replace(case, tf=tf)
    guess, tf0 = eigenaxis_start(case, intervals)
    return transcribe_slew(case, intervals, guess, tf0), tf0, spec


@pytest.mark.parametrize("path,tf", [(MULTICONE, None), (GUO, 150.0)])
def test_jacobians_match_finite_differences(path, tf):
    program = _slew(path, 8, tf=tf)[0].program
    rng = np.random.default_rng(3)
    x = program.initial_guess() + 1e-2 * rng.standard_normal(program.num_variables) * program.variable_scale()
    ev = program.evaluate(x)
    blocks = ev.equalities + ev.inequalities
    for _ in range(3):
        d = 1e-6 * rng.standard_normal(x.size) * program.variable_scale()
        plus, minus = program.evaluate(x + d, False), program.evaluate(x - d, False)
        for b, bp, bm in zip(blocks, plus.equalities + plus.inequalities, minus.equalities + minus.inequalities,
                             strict=True):
            fd = (bp.values - bm.values) / 2
            assert np.abs(b.jacobian @ d - fd).max() <= 1e-9 * max(1.0, np.abs(fd).max()), b.name


def test_min_time_matches_ipopt_on_the_same_nlp():
    pytest.importorskip("casadi")
    from convexguid.families.quaternion_attitude.reference import solve_quaternion_attitude_ipopt

    slew, tf_guess, spec = _slew(MULTICONE, 20)
    result = solve_scp(slew.program, scp_settings(spec.solver))
    assert result.status == "converged"
    ref = solve_quaternion_attitude_ipopt(slew.case, 20, slew.nodes(slew.program.initial_guess()), tf_guess)
    assert ref.success
    assert abs(result.objective - ref.objective) <= 1e-3 * ref.objective
    # and it beats the eigenaxis guess's duration, which breaks two cones
    assert result.objective < tf_guess


def test_minimum_time_plan_is_verified_and_meets_every_cone():
    sol = solve(MULTICONE, ["discretization.intervals=24"])
    assert sol.ok, sol.message
    names = {c.name: c for c in sol.verification.checks}
    for cone in ("body1", "body2", "body3", "body4"):
        check = names[f"keep_out_{cone}_deg"]
        assert check.worst >= check.bound
    assert names["rate_degps"].worst <= 3.0 + 1e-9
    assert names["torque_Nm"].worst <= 0.1 + 1e-9
    assert sol.figures.min_cone_margin_deg >= 0
    # the eigenaxis slew passes within a fraction of a degree of cones 1 and 2 (inside them)
    eig = sol.figures.eigenaxis_min_angle_deg
    assert eig["body1"] < 20 and eig["body2"] < 15


def test_energy_at_fixed_time_uses_less_energy_than_min_time():
    """At twice the minimum time, the minimum-energy plan uses less than half the energy.

    The final time is taken to all its digits: those digits move with round-off (through the dense check's
    repair margins), and this 16-interval energy SCP once swung with them (4 of 9 final times within 1e-4 s ended at
    max_iterations or a solver error); measured now: all 9 converge, 25-41 iterations, on one smooth optimum.
    """
    t_min = solve(GUO, ["discretization.intervals=16"])
    energy = solve(GUO, ["discretization.intervals=16", "objective=energy",
                         f"boundary.tf_s={2 * t_min.figures.maneuver_time_s!r}"])
    assert t_min.ok and energy.ok
    assert energy.figures.energy < 0.5 * t_min.figures.energy
    forbidden = [c for c in energy.verification.checks if c.name.startswith("forbidden")][0]
    assert forbidden.worst >= 10.0


def test_sign_continuous_quaternions():
    q = np.array([[0, 0, 0, 1.0], [0, 0, -0.1, -0.995], [0, 0, 0.2, 0.98]])
    out = quat_sign_continuous(q)
    assert np.all(np.sum(out[1:] * out[:-1], axis=1) >= 0)
    assert np.allclose(np.abs(out), np.abs(q))


def _write(tmp_path: Path, text: str, replace_from: str, replace_to: str) -> Path:
    out = tmp_path / "case.yaml"
    out.write_text(text.replace(replace_from, replace_to))
    return out


@pytest.mark.parametrize("old,new,needle", [
    ("final: {axis: [1.0, -1.0, 0.5], angle_deg: 160.0}", "final: {quaternion: [0.0, 0.0, 0.0, 0.0]}",
     "quaternion"),
    ("final: {axis: [1.0, -1.0, 0.5], angle_deg: 160.0}", "final: {quaternion: [0.0, 0.0, 0.0, 2.0]}",
     "quaternion"),
    ("torque_max_Nm: 0.1", "torque_max_Nm: 0.0", "torque_max_Nm"),
    ("rate_max_degps: 3.0", "rate_max_degps: -3.0", "rate_max_degps"),
    ("inertial_dir: [-0.466, -0.688, 0.556], half_angle_deg: 20", "inertial_dir: [0, 0, 1], half_angle_deg: 20",
     "half_angle_deg"),
])
def test_bad_input_is_a_one_line_error(tmp_path, old, new, needle):
    path = _write(tmp_path, MULTICONE.read_text(), old, new)
    with pytest.raises(SpecError) as err:
        load_problem(path)
    message = str(err.value)
    assert "\n" not in message and needle in message and str(path.name) in message


def test_keep_in_inside_keep_out_is_rejected(tmp_path):
    text = MULTICONE.read_text() + ("keep_in:\n  - {name: inside, body_axis: [0, 0, 1], "
                                    "inertial_dir: [-0.466, -0.688, 0.556], half_angle_deg: 5}\n")
    path = tmp_path / "case.yaml"
    path.write_text(text)
    with pytest.raises(SpecError, match="keep_in"):
        load_problem(path)


def test_initial_attitude_inside_the_forbidden_zone_is_rejected(tmp_path):
    path = _write(tmp_path, GUO.read_text(), "min_angle_deg: 10.0", "min_angle_deg: 50.0")
    with pytest.raises(SpecError, match="forbidden"):
        load_problem(path)


def test_scp_plan_uses_less_energy_than_the_controller_at_its_maneuver_time():
    """Issue 5's comparison: same slew and limits, tf = the potential-function controller's 0.1 deg time.

    The energy case takes its final time from the controller's result (``boundary.tf_from``); the comparison
    table renders the three results it is given, in that order, and solves nothing itself.
    """
    from convexguid.validation.comparisons import comparison_sections
    from convexguid.validation.links import link_values
    from convexguid.validation.run import CaseResult

    # The files' own 50-interval grid: on a 16-interval grid the minimum-energy SCP ends in a slow tail
    # (the path grazes the forbidden cone at a node and a midpoint; 80-140 iterations), which would make
    # this test about iteration limits rather than the comparison.
    coarse: list[str] = []
    controller_spec = load_problem(PROBLEMS / "guo2011_adaptive.yaml")
    controller = solve(controller_spec)
    tf = controller.figures.maneuver_time_01deg_s
    energy_file = PROBLEMS / "guo2011_scp_energy.yaml"
    linked = link_values(load_problem(energy_file), {controller_spec.name: controller})
    assert linked == {"boundary.tf_from": None, "boundary.tf_s": float(tf)}
    energy_spec = with_values(load_problem(energy_file, coarse), linked)
    time_spec = load_problem(GUO, coarse)
    energy_plan, time_plan = solve(energy_spec), solve(time_spec)
    assert energy_plan.ok and time_plan.ok
    assert energy_plan.figures.maneuver_time_s == pytest.approx(tf)
    assert energy_plan.figures.energy < controller.figures.energy_N2m2s
    assert time_plan.figures.maneuver_time_s < tf
    results = [CaseResult(spec, sol, (), ()) for spec, sol in
               ((controller_spec, controller), (time_spec, time_plan), (energy_spec, energy_plan))]
    lines = comparison_sections(results)
    rows = [line for line in lines if line.startswith("| ") and not line.startswith("| method")]
    assert [row.split(" | ")[0] for row in rows] == [
        "| potential-function controller (Fig. 3 case, closed loop, disturbed)", "| SCP, minimum time",
        "| SCP, minimum energy at the controller's maneuver time"]
    assert rows[0].split(" | ")[1] == f"{tf:.2f}" == rows[2].split(" | ")[1]
    assert rows[0].split(" | ")[2] == f"{controller.figures.energy_N2m2s:.4g}"
    assert rows[1].split(" | ")[1] == f"{time_plan.figures.maneuver_time_s:.2f}"
    saving = 100 * (1 - energy_plan.figures.energy / controller.figures.energy_N2m2s)
    table = "\n".join(lines)
    assert f"uses {saving:.1f}% less energy" in table
    assert f"finishes in {time_plan.figures.maneuver_time_s:.1f} s" in table
