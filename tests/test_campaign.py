"""Campaigns: planning (seeds, overrides, replay), execution on a real Dask LocalCluster against the serial runs,
interruption and resume, error rows, bad campaign files, the report, and that ``import convexguid`` stays light.

The campaigns here vary the Cai, Zhu, Zeng (2018) flat-attitude slew (a fraction of a second per solve).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml

import convexguid
from convexguid.campaign import run_campaign
from convexguid.campaign.definition import SUMMARY_KEYS, load_campaign
from convexguid.campaign.execute import figure_values, make_tasks
from convexguid.campaign.plan import plan_runs
from convexguid.campaign.progress import Progress, ProgressLine
from convexguid.cli import main
from convexguid.errors import SpecError
from convexguid.families import get_family
from convexguid.spec import apply_overrides

ROOT = Path(__file__).resolve().parents[1]
PROBLEM = ROOT / "problems" / "cai2018_flat_attitude.yaml"
FIGURES = ["max_torque_Nm", "min_separation_deg", "verification.constraints.torque_Nm.worst"]


def write_campaign(folder: Path, name: str = "campaign.yaml", **changes) -> Path:
    """A campaign over the flat-attitude file: final time on a grid, two dispersed boundary angles, 2 samples."""
    data = {"name": "cai-test", "problem": str(PROBLEM),
            "grid": [{"key": "boundary.tf_s", "values": [90.0, 110.0]}],
            "dispersions": [{"key": "boundary.initial.roll_pitch_yaw_deg.0", "distribution": "normal", "std": 2.0},
                            {"key": "boundary.final.roll_pitch_yaw_deg.2", "distribution": "uniform",
                             "low": 40.0, "high": 50.0}],
            "samples": 2, "seed": 11, "figures": FIGURES}
    data.update(changes)
    data = {k: v for k, v in data.items() if v is not None}
    path = folder / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def table(path: Path):
    """The results table without the wall times (the one column that differs between sessions)."""
    return pq.read_table(path).drop(["wall_time_s"])


def assert_same_runs(got: Path, expected: Path) -> None:
    """The same runs with the same statuses, texts and figures (numbers to 1e-9 relative).

    Another process may sum in another order (its BLAS threads, say): its answers agree to round-off, not to the
    last bit, and a test must not ask for more than the solver's tolerances can promise.
    """
    a, b = table(got), table(expected)
    assert a.schema == b.schema and a.num_rows == b.num_rows
    for name in a.column_names:
        left, right = a.column(name).to_pylist(), b.column(name).to_pylist()
        if pa.types.is_floating(a.schema.field(name).type):
            assert np.allclose(np.array(left, dtype=float), np.array(right, dtype=float), rtol=1e-9, atol=0,
                               equal_nan=True), name
        else:
            assert left == right, name


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    folder = tmp_path_factory.mktemp("serial")
    result = run_campaign(write_campaign(folder), folder / "out", serial=True)
    return folder, result


def test_plan_grid_times_samples_with_seeded_draws_and_exact_overrides(tmp_path):
    campaign = load_campaign(write_campaign(tmp_path, samples=3))
    runs = plan_runs(campaign)
    assert [(r.run_id, r.sample) for r in runs] == [(i, i % 3) for i in range(6)]
    assert [r.values["boundary.tf_s"] for r in runs] == [90.0] * 3 + [110.0] * 3
    # sample s draws from the first child of child s of the campaign seed, in the file's order
    for s, child in enumerate(np.random.SeedSequence(11).spawn(3)):
        rng = np.random.default_rng(child.spawn(2)[0])
        expected = {"boundary.initial.roll_pitch_yaw_deg.0": rng.normal(60.0, 2.0),
                    "boundary.final.roll_pitch_yaw_deg.2": rng.uniform(40.0, 50.0)}
        for run in (runs[s], runs[3 + s]):  # the same draws at every grid point
            assert {k: run.values[k] for k in expected} == expected
    # the override strings give the exact values back
    data = yaml.safe_load(PROBLEM.read_text())
    for run in runs:
        applied = apply_overrides(data, run.overrides, "x")
        assert applied["boundary"]["tf_s"] == run.values["boundary.tf_s"]
        assert applied["boundary"]["initial"]["roll_pitch_yaw_deg"][0] == run.values[
            "boundary.initial.roll_pitch_yaw_deg.0"]
        assert run.seed is None
    assert plan_runs(load_campaign(write_campaign(tmp_path, samples=3))) == runs


def test_seed_key_gives_each_sample_its_own_seed(tmp_path):
    lpmpc = ROOT / "problems" / "feng2018_lpmpc_single.yaml"
    runs = plan_runs(load_campaign(write_campaign(tmp_path, problem=str(lpmpc), dispersions=None, grid=None,
                                                  samples=4, seed_key="simulation.seed", figures=None)))
    assert len({r.seed for r in runs}) == 4 and all(0 <= r.seed < 2**63 for r in runs)
    assert all(r.overrides == (f"simulation.seed={r.seed}",) for r in runs)


def test_serial_campaign_rows_replay_with_set(serial):
    folder, result = serial
    assert (result.runs, result.finished, result.executed, result.workers) == (4, 4, 4, 1)
    rows = pq.read_table(result.table).to_pylist()
    assert [r["run_id"] for r in rows] == [0, 1, 2, 3]
    assert all(r["status"] == "converged" and r["verified"] is True for r in rows)
    assert result.ok and result.counts == {"converged": 4}
    row = rows[3]
    solution = convexguid.solve(PROBLEM, overrides=row["overrides"])
    assert solution.objective == row["objective"]
    assert solution.figure("max_torque_Nm") == row["max_torque_Nm"]
    assert solution.summary()["verification"]["constraints"]["torque_Nm"]["worst"] == row[FIGURES[2]]
    assert row["boundary.tf_s"] == 110.0


def test_local_cluster_gives_the_serial_results_run_for_run(serial, tmp_path, monkeypatch):
    folder, expected = serial
    # the problem named relative to the campaign file, the command run from an unrelated folder: the workers get
    # the problem's data, not a path to resolve
    (tmp_path / "campaigns").mkdir()
    (tmp_path / "elsewhere").mkdir()
    path = write_campaign(tmp_path / "campaigns", problem=os.path.relpath(PROBLEM, tmp_path / "campaigns"))
    monkeypatch.chdir(tmp_path / "elsewhere")
    tasks = make_tasks(load_campaign(path), plan_runs(load_campaign(path)))
    assert tasks[0].problem == yaml.safe_load(PROBLEM.read_text()) and Path(tasks[0].source) == PROBLEM
    result = run_campaign(path, tmp_path / "out", workers=2)
    assert result.workers == 2 and result.executed == 4
    assert_same_runs(result.table, expected.table)


def test_interrupted_campaign_resumes_to_the_uninterrupted_table(serial, tmp_path):
    folder, expected = serial
    out = tmp_path / "out"
    seen = []

    def stop_after_two(progress):
        seen.append(progress.done)
        if progress.done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_campaign(write_campaign(folder), out, workers=2, progress=stop_after_two)
    interrupted = pq.read_table(out / "results.parquet")
    assert interrupted.num_rows == 2 and not (out / "results.parts").exists()
    assert not (out / "report.md").exists()
    resumed = run_campaign(write_campaign(folder), out, serial=True)
    assert (resumed.executed, resumed.finished) == (2, 4)
    assert set(pq.read_table(out / "results.parquet").column("run_id").to_pylist()) == {0, 1, 2, 3}
    assert_same_runs(out / "results.parquet", expected.table)
    again = run_campaign(write_campaign(folder), out, serial=True)
    assert again.executed == 0 and again.finished == 4


def test_a_run_that_raises_is_an_error_row_and_the_campaign_goes_on(tmp_path, capsys):
    path = write_campaign(tmp_path, grid=None, samples=4, seed=14, figures=["max_torque_Nm"], dispersions=[
        {"key": "spacecraft.torque_max_Nm", "distribution": "uniform", "low": -0.5, "high": 1.5}])
    assert main(["campaign", str(path), "--out", str(tmp_path / "out"), "--serial", "--quiet"]) == 1
    rows = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    assert len(rows) == 4
    negative = [r for r in rows if r["spacecraft.torque_max_Nm"] <= 0]
    assert negative and len(negative) < 4  # this seed draws both kinds (the positive ones large: quick solves)
    for r in rows:
        if r["spacecraft.torque_max_Nm"] <= 0:
            assert r["status"] == "error" and r["objective"] is None and r["verified"] is None
            assert "spacecraft.torque_max_Nm" in r["message"] and "\n" not in r["message"]
        else:
            assert r["status"] != "error"
    report = (tmp_path / "out" / "report.md").read_text()
    assert "## Runs that did not converge and verify" in report
    out = capsys.readouterr().out
    assert "4/4 runs" in out and f"error {len(negative)}" in out


def test_a_figure_that_is_not_a_number_is_an_error_row_naming_it(tmp_path):
    path = write_campaign(tmp_path, grid=None, samples=1, figures=["verification.constraints"])
    result = run_campaign(path, tmp_path / "out", serial=True)
    row = pq.read_table(result.table).to_pylist()[0]
    assert row["status"] == "error"
    assert "verification.constraints is a mapping, not a number" in row["message"]


def test_figure_values_follow_dotted_paths_through_mappings_and_lists():
    summary = {"runs": [{"energy": 1.5}, {"energy": 2}], "verification": {"passed": True, "c": {"worst": None}},
               "burn_time_s": float("nan")}
    values = figure_values(summary, ["runs.1.energy", "verification.passed", "verification.c.worst", "runs.5.energy",
                                     "burn_time_s", "absent"])
    assert values == {"runs.1.energy": 2.0, "verification.passed": 1.0, "verification.c.worst": None,
                      "runs.5.energy": None, "burn_time_s": None, "absent": None}
    with pytest.raises(SpecError, match=r"runs is a list, not a number .* e\.g\. runs\.0"):
        figure_values(summary, ["runs"])


def test_progress_line_counts_failures_and_estimates_the_time_left(monkeypatch):
    import io

    monkeypatch.delenv("CONVEXGUID_PROGRESS", raising=False)

    stream = io.StringIO()
    assert ProgressLine("quiet", stream).__call__(Progress(10, 4, 1, 2, 6.0)) is None and not stream.getvalue()
    line = ProgressLine("demo", stream, interval_s=0.0, mode="lines")  # as with CONVEXGUID_PROGRESS=1 off a terminal
    line(Progress(total=10, done=4, failures=1, resumed=2, elapsed_s=6.0))
    line(Progress(total=10, done=10, failures=1, resumed=2, elapsed_s=24.0))
    first, last = stream.getvalue().splitlines()
    assert first == "demo: 4/10 runs (2 from before), 1 failed, ETA 18 s"  # 2 runs in 6 s, 6 left
    assert last == "demo: 10/10 runs (2 from before), 1 failed, ETA 0 s"


BAD_CAMPAIGNS = [
    ({"colour": "red"}, "colour: unknown key (got 'red')"),
    ({"dispersions": [{"key": "method", "distribution": "normal", "std": 1.0}]},
     "dispersions.0.key: method is not a number"),
    ({"dispersions": [{"key": "boundary.initial.roll_pitch_yaw_deg", "distribution": "normal", "std": 1.0}]},
     "e.g. boundary.initial.roll_pitch_yaw_deg.0"),
    ({"grid": [{"key": "boundary.tf_s", "values": []}]}, "grid.0.values: gives zero runs (got [])"),
    ({"samples": 0}, "samples: gives zero runs (got 0)"),
    ({"figures": ["energyy"]}, "figures.0: not a summary key of family flat_attitude (got 'energyy')"),
    ({"grid": [{"key": "boundary.tf_s", "values": [100.0, -5.0]}]}, "grid.0: the problem is invalid at"),
    ({"grid": [{"key": "boundary.tf_s", "values": [90.0]}, {"key": "boundary.tf_s", "values": [80.0]}]},
     "grid.1: key already varied or set by grid.0 (got 'boundary.tf_s')"),
]


@pytest.mark.parametrize(("changes", "expected"), BAD_CAMPAIGNS, ids=lambda v: str(v)[:40])
def test_bad_campaign_file_is_one_line_and_writes_nothing(tmp_path, capsys, changes, expected):
    path = write_campaign(tmp_path, **changes)
    assert main(["campaign", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"convexguid: {path}: ")
    assert expected in err
    assert not (tmp_path / "out").exists()


def test_unreachable_scheduler_is_one_line_and_writes_nothing(tmp_path, capsys):
    path = write_campaign(tmp_path)
    with pytest.raises(SpecError) as info:
        run_campaign(path, tmp_path / "out", scheduler="tcp://127.0.0.1:1", connect_timeout_s=1.0)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}: --scheduler: ")
    assert "'tcp://127.0.0.1:1'" in message
    assert main(["campaign", str(path), "--out", str(tmp_path / "out"), "--scheduler", "not an address::"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scheduler: no Dask scheduler answers at 'not an address::'" in err
    assert not (tmp_path / "out").exists()


def test_a_results_folder_of_another_campaign_is_refused(serial, capsys):
    folder, result = serial
    other = write_campaign(folder, name="other.yaml", seed=12)
    assert main(["campaign", str(other), "--out", str(result.directory), "--serial"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "was written by another campaign" in err
    assert pq.read_table(result.table).num_rows == 4


def test_report_statistics_plots_and_rewrite(serial):
    folder, result = serial
    report = result.report.read_text()
    rows = pq.read_table(result.table).to_pylist()
    values = [r["max_torque_Nm"] for r in rows]
    line = next(x for x in report.splitlines() if x.startswith("| `max_torque_Nm` | converged |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[2:5] == ["4", f"{np.mean(values):.6g}", f"{np.std(values, ddof=1):.6g}"]
    assert cells[-1] == f"{max(values):.6g}"
    assert "| converged | 4 | 4 |" in report
    for name in ("objective", "max_torque_Nm", "min_separation_deg"):
        assert (result.directory / f"sweep_{name}.png").stat().st_size > 1000
        assert f"(sweep_{name}.png)" in report
    assert "wall" not in report.lower()
    before = result.report.read_bytes()
    again = run_campaign(write_campaign(folder), result.directory, serial=True)
    assert again.executed == 0 and again.report.read_bytes() == before


def test_monte_carlo_report_has_histograms_and_scatter(tmp_path):
    result = run_campaign(write_campaign(tmp_path, grid=None, samples=3), tmp_path / "out", serial=True)
    report = result.report.read_text()
    for png in ("histograms.png", "scatter.png"):
        assert f"({png})" in report and (result.directory / png).stat().st_size > 1000
    assert "## By grid point" not in report


def test_summary_keys_are_the_summarys_common_numeric_keys():
    solution = convexguid.solve(PROBLEM)
    figures = set(get_family("flat_attitude").figures.names())
    text = {k for k, v in solution.summary().items() if isinstance(v, str)}
    assert set(solution.summary()) - figures - text == set(SUMMARY_KEYS)


def test_import_and_help_load_neither_dask_nor_pyarrow_nor_matplotlib():
    code = ("import sys, convexguid; from convexguid.cli import _parser; _parser(); "
            "import json; print(json.dumps(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'dask', 'distributed', 'pyarrow', 'matplotlib'})))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert json.loads(out.stdout) == []
    assert "run_campaign" in dir(convexguid)


def test_a_campaign_over_a_problem_module_varies_build_parameters_and_replays(tmp_path, capsys):
    """examples/proxops_openscvx.py as the problem: a grid over build()'s intervals, its entrance depth dispersed
    about build()'s default; each row replays with `convexguid solve MODULE --set ...`."""
    module = ROOT / "examples" / "proxops_openscvx.py"
    data = {"name": "module-test", "problem": str(module), "grid": [{"key": "intervals", "values": [10, 20]}],
            "dispersions": [{"key": "entrance_depth", "distribution": "normal", "std": 2.0}],
            "samples": 1, "seed": 3, "figures": ["final_time_s"]}
    path = tmp_path / "campaign.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    campaign = load_campaign(path)
    assert campaign.family.name == "ocp" and campaign.nominal == {"entrance_depth": 20.0}
    result = run_campaign(path, tmp_path / "out", serial=True)
    rows = pq.read_table(result.table).to_pylist()
    assert result.ok and [r["intervals"] for r in rows] == [10, 20]
    from convexguid.ocp.module import load_module_problem

    replayed = load_module_problem(module, rows[1]["overrides"]).solve()
    assert replayed.objective == pytest.approx(rows[1]["objective"], rel=1e-9)
    assert rows[1]["final_time_s"] == pytest.approx(replayed.figures.final_time_s, rel=1e-9)
    # a key that is not a parameter of build(): one line naming the campaign file and the key, nothing written
    data["dispersions"][0]["key"] = "depth"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    assert main(["campaign", str(path), "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "dispersions.0.key: depth is not a build() parameter" in err
    assert not (tmp_path / "bad").exists()
