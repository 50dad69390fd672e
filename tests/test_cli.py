"""The command line contract of design.md: exit codes, one-line errors, outputs."""

import json
import subprocess
import sys

import pytest
import yaml

PAPER = "problems/cai2018_flat_attitude.yaml"


def run(*args):
    return subprocess.run([sys.executable, "-m", "convexguid.cli", *args], capture_output=True, text=True)


def test_solve_writes_outputs(tmp_path):
    out = tmp_path / "out"
    res = run("solve", PAPER, "--out", str(out), "--summary-json", str(tmp_path / "s.json"))
    assert res.returncode == 0, res.stderr
    assert "iter" in res.stdout and "verification (2001 points): passed" in res.stdout
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["status"] == "converged" and summary["num_variables"] == 99
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header.startswith("t_s,") and "u1_Nm" in header and "roll_propagated_deg" in header
    assert len((out / "trajectory.csv").read_text().splitlines()) == 2002
    for png in ("euler_angles.png", "body_rates.png", "torques.png"):
        assert (out / png).stat().st_size > 1000


def test_quiet_and_set_override(tmp_path):
    res = run("solve", PAPER, "--quiet", "--set", "boundary.tf_s=120", "--summary-json", str(tmp_path / "s.json"))
    assert res.returncode == 0, res.stderr
    assert "iter" not in res.stdout.splitlines()[0]
    assert json.loads((tmp_path / "s.json").read_text())["objective"] < 0.2607  # longer slew, less energy


def _bad(tmp_path, mutate):
    data = yaml.safe_load(open(PAPER))
    mutate(data)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("mutate, expected", [
    (lambda d: d["spacecraft"].pop("inertia_kgm2"), "spacecraft.inertia_kgm2"),
    (lambda d: d.update(colour="red"), "colour"),
    (lambda d: d["boundary"].update(tf_s="long"), "boundary.tf_s"),
    (lambda d: d["discretization"].update(nodes=3), "discretization.nodes"),
    (lambda d: d["keep_out"][0].update(body_axis=[0, 0, 0]), "keep_out.0.body_axis"),
    (lambda d: d["boundary"]["initial"].update(roll_pitch_yaw_deg=[0, 90, 0]), "roll_pitch_yaw_deg"),
    (lambda d: d["solver"].update(backend="gurobi"), "solver.backend"),
])
def test_bad_input_one_line_exit_2(tmp_path, mutate, expected):
    path = _bad(tmp_path, mutate)
    summary = tmp_path / "s.json"
    res = run("solve", str(path), "--summary-json", str(summary))
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0] and str(path) in lines[0]
    assert "Traceback" not in res.stderr and not summary.exists()


def test_unknown_override_path_is_an_error():
    res = run("solve", PAPER, "--set", "boundary.nothing.here=1")
    assert res.returncode == 2 and "boundary.nothing" in res.stderr


def test_infeasible_exit_1_with_summary(tmp_path):
    res = run("solve", PAPER, "--quiet", "--set", "boundary.tf_s=5", "--set", "solver.max_iterations=30",
              "--summary-json", str(tmp_path / "s.json"))
    assert res.returncode == 1 and "Traceback" not in res.stderr
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["status"] in ("infeasible", "max_iterations")
    assert summary["verification"]["passed"] is False
