"""``convexguid simulate`` on the Guo, Li, Ma (2011) scenarios: summary contract, checks, bad input, Fig. 2 time."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import convexguid
from convexguid.errors import SpecError
from convexguid.problem_files import load_problem

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
FIXED = PROBLEMS / "guo2011_fixed_gains.yaml"
ADAPTIVE = PROBLEMS / "guo2011_adaptive.yaml"
SWEEP = PROBLEMS / "guo2011_sweep.yaml"
NO_FORBIDDEN = PROBLEMS / "guo2011_no_forbidden.yaml"
SUMMARY_KEYS = ("maneuver_time_1deg_s", "maneuver_time_01deg_s", "min_theta_b_deg", "theta_m_deg",
                "max_abs_torque_Nm", "energy_N2m2s", "final_error_deg")


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "convexguid.cli", *args], capture_output=True, text=True)


def test_fig3_simulate_writes_summary_trajectory_and_plots(tmp_path):
    out, summary_path = tmp_path / "out", tmp_path / "s.json"
    res = run("simulate", str(ADAPTIVE), "--out", str(out), "--summary-json", str(summary_path))
    assert res.returncode == 0, res.stderr
    assert "simulating guo2011-adaptive" in res.stdout and "verification (2601 points): passed" in res.stdout
    s = json.loads(summary_path.read_text())
    assert (s["family"], s["method"], s["status"], s["solver"]) == (
        "potential_function", "potential_function", "converged", "rk4")
    assert s["iterations"] == 2600 and s["num_variables"] == 0
    assert all(key in s for key in SUMMARY_KEYS)
    assert s["theta_m_deg"] == 10.0 and s["min_theta_b_deg"] > 10.0
    assert s["max_abs_torque_Nm"] <= 0.5 and s["final_error_deg"] < 0.1
    assert s["maneuver_time_1deg_s"] < s["maneuver_time_01deg_s"] < 260.0
    assert s["objective"] == pytest.approx(s["energy_N2m2s"]) and s["escape_time_s"] > 0
    v = s["verification"]
    assert v["passed"] and v["max_violation"] == 0.0
    assert set(v["constraints"]) == {"torque_Nm", "rate_degps", "forbidden_angle_deg"}
    assert v["constraints"]["forbidden_angle_deg"] == {"worst": s["min_theta_b_deg"], "bound": 10.0}
    assert v["constraints"]["rate_degps"]["worst"] < 1.91
    assert json.loads((out / "summary.json").read_text())["status"] == "converged"
    lines = (out / "trajectory.csv").read_text().splitlines()
    assert len(lines) == 2602
    header = lines[0].split(",")
    for column in ("t_s", "q1", "q4", "omega3_degps", "u3_Nm", "theta_b_deg", "theta_e_deg", "escape_active"):
        assert column in header
    for png in ("quaternion", "body_rates", "torques", "theta_b", "attitude_error"):
        assert (out / f"{png}.png").stat().st_size > 1000


def test_fig2_maneuver_time_about_25_to_31_s(tmp_path):
    res = run("simulate", str(FIXED), "--quiet", "--summary-json", str(tmp_path / "s.json"))
    assert res.returncode == 0, res.stderr
    s = json.loads((tmp_path / "s.json").read_text())
    assert 25.0 <= s["maneuver_time_1deg_s"] <= 31.0  # paper: "about 25 s"
    assert s["maneuver_time_01deg_s"] < 32.0
    assert s["min_theta_b_deg"] > 10.0 and s["verification"]["constraints"].keys() == {"forbidden_angle_deg"}
    assert 100.0 < s["max_abs_torque_Nm"] < 1000.0  # no torque limit: hundreds of N m


def test_sweep_with_two_angles(tmp_path):
    out = tmp_path / "out"
    res = run("simulate", str(SWEEP), "--set", "sweep.theta_m_deg=[5, 40]", "--out", str(out))
    assert res.returncode == 0, res.stderr
    s = json.loads((out / "summary.json").read_text())
    assert [case["theta_m_deg"] for case in s["sweep"]] == [5.0, 40.0]
    assert [case["theta_0_deg"] for case in s["sweep"]] == pytest.approx([6.0, 48.0])
    for case in s["sweep"]:
        assert case["passed"] and case["min_theta_b_deg"] > case["theta_m_deg"]
        assert all(key in case for key in SUMMARY_KEYS)
    constraints = s["verification"]["constraints"]
    assert constraints["sweep_theta_m_40_forbidden_angle_deg"]["bound"] == 40.0
    assert s["verification"]["passed"] and s["status"] == "converged"
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert "sweep_theta_m_5_theta_b_deg" in header and "sweep_theta_m_40_theta_b_deg" in header
    assert (out / "theta_b_sweep.png").stat().st_size > 1000


@pytest.mark.parametrize("problem, override, key", [
    (ADAPTIVE, "gains.theta_0_deg=10", "gains.theta_0_deg"),
    (ADAPTIVE, "boundary.command.quaternion_xyzw=[0, 0, 0.4226182617, 0.906307787]", "boundary.command"),
    (SWEEP, "sweep.theta_m_deg=[10, 46]", "boundary.command"),
    (FIXED, "gains.g=-1", "gains.g"),
    (ADAPTIVE, "gains.u_s_Nm=0", "gains.u_s_Nm"),
    (ADAPTIVE, "gains.colour=1", "gains.colour"),
    (ADAPTIVE, "boundary.forbidden.quaternion_xyzw=[0, 0, 1, 1]", "boundary.forbidden.quaternion_xyzw"),
    (FIXED, "gains.theta_lm_deg=1", "gains.theta_lm_deg"),
])
def test_bad_input_one_line_exit_2(tmp_path, problem, override, key):
    summary = tmp_path / "s.json"
    res = run("simulate", str(problem), "--set", override, "--summary-json", str(summary))
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and key in lines[0] and str(problem) in lines[0], res.stderr
    assert "Traceback" not in res.stderr and not summary.exists()


def test_command_not_reached_exit_1_with_summary(tmp_path):
    res = run("simulate", str(ADAPTIVE), "--quiet", "--set", "simulation.t_final_s=60",
              "--summary-json", str(tmp_path / "s.json"))
    assert res.returncode == 1 and "Traceback" not in res.stderr and "not reached" in res.stderr
    s = json.loads((tmp_path / "s.json").read_text())
    assert s["status"] == "max_iterations" and s["verification"]["passed"] is False
    assert s["maneuver_time_01deg_s"] is None


def test_simulate_rejects_a_planned_family():
    res = run("simulate", str(PROBLEMS / "cai2018_flat_attitude.yaml"))
    assert res.returncode == 2 and "family" in res.stderr and "convexguid solve" in res.stderr


def test_solve_dispatches_fig5_without_forbidden_attitude():
    sol = convexguid.solve(NO_FORBIDDEN)  # the path `convexguid validate` takes
    assert sol.ok and sol.family == "potential_function"
    assert "theta_b_deg" not in sol.dense.columns
    summary = sol.summary()
    assert summary["min_theta_b_deg"] is None and "forbidden_angle_deg" not in summary["verification"]["constraints"]
    assert summary["max_abs_torque_Nm"] <= 0.5 and summary["max_rate_degps"] < 1.91
    with pytest.raises(SpecError, match="planned, not simulated"):
        convexguid.simulate(PROBLEMS / "cai2018_flat_attitude.yaml")


def test_paper_quaternions_rounded_as_printed_are_normalised():
    spec = load_problem(ADAPTIVE, ["boundary.command.quaternion_xyzw=[0, 0, 0.707, 0.707]",
                                   "boundary.forbidden.quaternion_xyzw=[0, 0, 0.383, 0.924]"])
    np.testing.assert_allclose(spec.boundary.command.quaternion, [0, 0, math.sqrt(0.5), math.sqrt(0.5)])
    assert np.linalg.norm(spec.boundary.forbidden.quaternion) == pytest.approx(1.0, abs=1e-15)


def test_problem_files_carry_references():
    for path in (FIXED, ADAPTIVE, SWEEP, NO_FORBIDDEN):
        spec = load_problem(path)
        assert spec.family == "potential_function" and spec.reference is not None
        assert "Guo Yanning" in spec.reference.citation
    assert load_problem(FIXED).reference.values == {"maneuver_time_1deg_s": 25.0}
    assert [m for m, _ in load_problem(SWEEP).cases()] == [10.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0]
