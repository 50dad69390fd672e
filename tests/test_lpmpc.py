"""The ``lpmpc`` family end to end (Feng, Chen, Yang 2018): single case, a short Monte Carlo, bad input.

Long runs (the 200-run Monte Carlo) belong to ``convexguid validate``; here the same code flies a few.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from convexguid.api import simulate
from convexguid.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
SINGLE = PROBLEMS / "feng2018_lpmpc_single.yaml"
MONTE_CARLO = PROBLEMS / "feng2018_lpmpc_montecarlo.yaml"
TRACK = PROBLEMS / "guo2011_lpmpc_track.yaml"


@pytest.fixture(scope="module")
def single():
    return simulate(SINGLE)


def test_single_case_flies_every_law_and_lpmpc_meets_the_target(single):
    assert single.ok, single.message
    runs = {r.controller: r for r in single.figures.runs}
    assert list(runs) == ["lpmpc", "lqr_tracking_r0.01", "lqr_direct_r0.01", "lqr_tracking_r0.1", "lqr_direct_r0.1"]
    lpmpc = runs["lpmpc"]
    assert lpmpc.final_angle_error_deg < 0.5 and lpmpc.final_rate_error_degps < 0.2
    # the paper's ordering: tracking laws end within a degree, direct regulation degrees away (Table 2)
    for r in (0.01, 0.1):
        assert runs[f"lqr_tracking_r{r:g}"].final_angle_error_deg < 1.5
        assert runs[f"lqr_direct_r{r:g}"].final_angle_error_deg > 5.0
    assert single.figures.corrections >= 1 and single.figures.update_checks == 4  # checks at t = 0, 2, 4, 6 s
    assert single.figures.nominal_status == "converged"  # the nominal passed its own dense check
    assert abs(lpmpc.energy_N2m2s - single.figures.nominal_energy_N2m2s) / single.figures.nominal_energy_N2m2s < 0.2


def test_single_case_histories_and_summary(single, tmp_path):
    dense = single.dense
    assert dense.t[0] == 0.0 and dense.t[-1] == pytest.approx(8.0)
    # the LPMPC flight ends at the target attitude (0, 0, 0) deg within its measured error
    final = np.array([dense.columns[f"lpmpc_{a}_deg"][-1] for a in ("roll", "pitch", "yaw")])
    assert np.abs(final).max() < single.figures.lpmpc_final_angle_error_deg + 1e-9
    summary = single.summary()
    assert summary["family"] == "lpmpc" and summary["status"] == "converged"
    assert summary["runs"][0]["controller"] == "lpmpc" and "monte_carlo" not in summary


@pytest.fixture(scope="module")
def short_monte_carlo():
    return simulate(MONTE_CARLO, ["monte_carlo.runs=10", "monte_carlo.workers=2", "timing_nodes=[8]"])


def test_short_monte_carlo_lpmpc_ends_closer_than_lqr_tracking(short_monte_carlo):
    mc = short_monte_carlo.figures.monte_carlo
    assert mc.runs == 10 and len(mc.per_run) == 10
    assert mc.lpmpc_angle_error_deg.mean < mc.lqr_angle_error_deg.mean
    assert mc.lpmpc_energy_N2m2s.mean > 0 and mc.lqr_energy_N2m2s.mean > 0  # both reported
    for run in mc.per_run:
        saving = (run["lqr_energy_N2m2s"] - run["lpmpc_energy_N2m2s"]) / run["lqr_energy_N2m2s"]
        assert mc.saving_range[0] - 1e-12 <= saving <= mc.saving_range[1] + 1e-12
    assert 1 <= mc.corrections_range[0] <= mc.corrections_range[1] <= 4
    assert short_monte_carlo.figures.update_time_ms["lpmpc_n8"] > 0


def test_monte_carlo_runs_do_not_depend_on_the_number_of_workers(short_monte_carlo):
    serial = simulate(MONTE_CARLO, ["monte_carlo.runs=3", "monte_carlo.workers=1"]).figures.monte_carlo
    for a, b in zip(serial.per_run, short_monte_carlo.figures.monte_carlo.per_run[:3], strict=True):
        assert a["euler_error_deg"] == b["euler_error_deg"]
        assert a["lpmpc_energy_N2m2s"] == pytest.approx(b["lpmpc_energy_N2m2s"], rel=1e-12)


@pytest.mark.parametrize(("override", "key"), [
    ("lpmpc.nodes=2", "lpmpc.nodes"),
    ("lpmpc.threshold_mrp=0", "lpmpc.threshold_mrp"),
    ("lpmpc.threshold_rate_degps=-1", "lpmpc.threshold_rate_degps"),
    ("lpmpc.check_interval_s=0", "lpmpc.check_interval_s"),
    ("monte_carlo.runs=0", "monte_carlo.runs"),
    ("nominal.problem=missing.yaml", "nominal.problem"),
])
def test_bad_input_is_one_line_naming_file_key_and_value(override, key, capsys):
    code = main(["simulate", str(MONTE_CARLO), "--quiet", "--set", override])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "feng2018_lpmpc_montecarlo.yaml" in err[0] and key in err[0]


def test_bad_nominal_input_names_the_nominal_file(capsys):
    code = main(["simulate", str(SINGLE), "--quiet", "--set", "nominal.set=['spacecraft.inertia_kgm2=[0, 70, 70]']"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "feng2018_nominal.yaml" in err[0] and "inertia_kgm2" in err[0]


def test_an_infeasible_nominal_ends_with_its_honest_status():
    # 0.2 N m cannot do the 108 deg slew in 8 s, yet passes the spec's up-front bound (needs 0.17 N m or more)
    sol = simulate(SINGLE, ["nominal.set=['spacecraft.torque_max_Nm=0.2', 'solver.max_iterations=15']"])
    assert sol.status in ("infeasible", "max_iterations", "unverified") and not sol.ok
    assert sol.message.startswith("nominal plan feng2018-nominal")
    assert sol.figures.runs == ()  # nothing is flown on an unverified nominal


def test_a_padded_plan_is_flown_against_the_limit_as_written():
    """guo2011_lpmpc_track plans 0.5 deg away from the forbidden attitude (``nominal.set``); the flight is held to
    the problem file's own 10 deg, not to the padding."""
    from convexguid.api import PLANNER
    from convexguid.families.lpmpc.solve import build_scenario
    from convexguid.problem_files import load_problem

    track = load_problem(PROBLEMS / "guo2011_lpmpc_track.yaml", ["nominal.tf_from=null", "nominal.tf_s=196.8"])
    scenario, nominal = build_scenario(track, PLANNER)
    assert nominal.ok, nominal.message
    assert [bound for _, _, bound in scenario.forbidden] == [10.0]
    planned = [c for c in nominal.verification.checks if c.name.startswith("forbidden")][0]
    assert planned.bound == 10.5 and planned.worst >= 10.5 - 1e-6


def test_simulate_solves_the_problem_a_linked_input_names_first(tmp_path, capsys):
    """guo2011_lpmpc_track takes its nominal's final time from guo2011-adaptive's result (``nominal.tf_from``):
    ``convexguid simulate`` flies that case's file (beside it) first, as validate does, and takes the figure."""
    summary = tmp_path / "summary.json"
    assert main(["simulate", str(TRACK), "--summary-json", str(summary)]) == 0
    out = capsys.readouterr().out
    assert f"solving {PROBLEMS / 'guo2011_adaptive.yaml'} first" in out
    assert "guo2011-lpmpc-track: nominal.tf_s = 196.8 (from guo2011-adaptive: converged)" in out
    assert json.loads(summary.read_text())["status"] == "converged"


def test_a_linked_problem_missing_beside_the_file_is_one_line_before_anything_runs(tmp_path, capsys):
    lonely = tmp_path / TRACK.name
    shutil.copyfile(TRACK, lonely)
    assert main(["simulate", str(lonely), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1, captured
    assert f"{lonely}: nominal.tf_from.problem: no problem file in {tmp_path} has that name " \
           "(got 'guo2011-adaptive')" in captured.err
