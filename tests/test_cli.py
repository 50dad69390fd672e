"""The command line contract of docs/cli.md: exit codes, one-line errors, outputs.

Everything runs in process through :func:`convexguid.cli.main` (output captured with ``capsys``) except
:func:`test_console_script_solves_and_writes_outputs`, which runs the installed ``convexguid`` script
end to end, as users do.
"""

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from convexguid.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAPER = str(ROOT / "problems" / "cai2018_flat_attitude.yaml")
PAPER_J, PAPER_J_RTOL = 0.2607, 5e-4  # Cai, Zhu, Zeng 2018, Table 1 (J at tf = 100 s) and the file's tolerance
ITERATION_HEADER = "iter      objective"


def _console_script() -> str:
    """The ``convexguid`` script of the running interpreter's environment (else the one on PATH)."""
    beside = Path(sys.executable).parent / "convexguid"
    exe = str(beside) if beside.exists() else shutil.which("convexguid")
    assert exe is not None, "the convexguid console script is not installed (pip install -e .)"
    return exe


def test_console_script_solves_and_writes_outputs(tmp_path):
    out = tmp_path / "out"
    res = subprocess.run([_console_script(), "solve", PAPER, "--out", str(out), "--summary-json",
                          str(tmp_path / "s.json")], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stderr
    assert res.stderr == ""
    assert res.stdout.startswith(ITERATION_HEADER)
    assert "cai2018-flat-attitude: converged" in res.stdout
    assert "verification (2001 points): passed" in res.stdout
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["status"] == "converged", summary["message"]
    assert summary["verification"]["passed"] is True
    assert summary["num_variables"] == 99
    assert summary["objective"] == pytest.approx(PAPER_J, rel=PAPER_J_RTOL)
    assert json.loads((out / "summary.json").read_text()) == summary
    with open(out / "trajectory.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    assert header[0] == "t_s" and "u1_Nm" in header and "roll_propagated_deg" in header
    assert len(rows) == 2002  # header + the 2001 dense verification points
    first, last = (dict(zip(header, map(float, r), strict=True)) for r in (rows[1], rows[-1]))
    assert (first["t_s"], last["t_s"]) == (0.0, pytest.approx(100.0))
    # the re-propagated attitude ends at the file's final attitude (-60, -45, 45) deg
    final = [last[f"{a}_propagated_deg"] for a in ("roll", "pitch", "yaw")]
    assert final == pytest.approx([-60.0, -45.0, 45.0], abs=1e-3)
    for png in ("euler_angles.png", "body_rates.png", "torques.png"):
        assert (out / png).stat().st_size > 1000


def test_quiet_and_set_override(tmp_path, capsys):
    summary_path = tmp_path / "s.json"
    code = main(["solve", PAPER, "--quiet", "--set", "boundary.tf_s=120", "--summary-json", str(summary_path)])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert out.startswith("\ncai2018-flat-attitude: converged"), out  # the result block only: no iteration table
    summary = json.loads(summary_path.read_text())
    assert summary["status"] == "converged" and summary["verification"]["passed"] is True, summary["message"]
    # Rest-to-rest with free rates in between: stretching time by s scales the torque by 1/s^2, so the
    # minimum energy scales as (100 / tf)^3 (the torque bound stays slack): J(120 s) = J(100 s) (100/120)^3.
    assert summary["objective"] == pytest.approx(PAPER_J * (100 / 120) ** 3, rel=PAPER_J_RTOL)


def _bad(tmp_path, mutate):
    data = yaml.safe_load(open(PAPER))
    mutate(data)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _one_line(err: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), f"expected exactly one line on stderr, got {err!r}"
    return lines[0]


@pytest.mark.parametrize("mutate, key, value", [
    (lambda d: d["spacecraft"].pop("inertia_kgm2"), "spacecraft.inertia_kgm2", "missing required key"),
    (lambda d: d.update(colour="red"), "colour", "(got 'red')"),
    (lambda d: d["boundary"].update(tf_s="long"), "boundary.tf_s", "(got 'long')"),
    (lambda d: d["discretization"].update(nodes=3), "discretization.nodes", "(got 3)"),
    (lambda d: d["keep_out"][0].update(body_axis=[0, 0, 0]), "keep_out.0.body_axis", "(got [0, 0, 0])"),
    (lambda d: d["boundary"]["initial"].update(roll_pitch_yaw_deg=[0, 90, 0]),
     "boundary.initial.roll_pitch_yaw_deg", "(got 90"),
    (lambda d: d["solver"].update(backend="gurobi"), "solver.backend", "(got 'gurobi')"),
], ids=["missing", "unknown-key", "wrong-type", "out-of-range", "zero-axis", "gimbal-lock", "unknown-backend"])
def test_bad_input_one_line_exit_2(tmp_path, capsys, mutate, key, value):
    path = _bad(tmp_path, mutate)
    summary = tmp_path / "s.json"
    code = main(["solve", str(path), "--summary-json", str(summary)])
    line = _one_line(capsys.readouterr().err)
    assert code == 2
    assert line.startswith(f"convexguid: {path}: {key}"), line  # the file, then the key path
    assert value in line, line  # the offending value
    assert not summary.exists()


def test_unknown_override_path_is_an_error(capsys):
    code = main(["solve", PAPER, "--set", "boundary.nothing.here=1"])
    line = _one_line(capsys.readouterr().err)
    assert code == 2
    assert line.startswith(f"convexguid: {PAPER}: boundary.nothing:"), line
    assert "'boundary.nothing.here=1'" in line, line


def test_infeasible_exit_1_with_summary(tmp_path, capsys):
    # The 155 deg slew needs more than 18 s with 1 N m per axis, but not so much more that the spec's lower bound
    # (17.7 s, tests/test_hardening.py) can tell: the SCP certifies it.
    summary_path = tmp_path / "s.json"
    code = main(["solve", PAPER, "--quiet", "--set", "boundary.tf_s=18", "--set", "solver.max_iterations=30",
                 "--summary-json", str(summary_path)])
    line = _one_line(capsys.readouterr().err)
    assert code == 1
    assert line.startswith(f"convexguid: {PAPER}: infeasible: "), line
    summary = json.loads(summary_path.read_text())
    assert summary["status"] == "infeasible", summary["message"]
    # docs/cli.md: the summary's `verification` is always an object (the planned control re-propagated)
    assert isinstance(summary["verification"], dict), f"verification is {summary['verification']!r}"
    assert summary["verification"]["passed"] is False
