"""The attitude benchmark (SCP vs IPOPT against the grid size) runs end to end on a small grid.

One ``K = 10`` run with ``repeat = 1`` (a few seconds): every method has a row with positive
times, the runs that are compared (gaps, the energy rows' final time, the timing note) must have
converged first, the markdown carries the table, and ``convexguid bench`` passes
``quaternion_attitude`` files to :func:`convexguid.families.quaternion_attitude.bench.run_attitude_bench`.
The IPOPT rows are checked only when ``casadi`` is installed (skipped, not passed, without it).
"""

from __future__ import annotations

from pathlib import Path

import pytest

import convexguid.families.quaternion_attitude.bench as attitude_bench
from convexguid.cli import main
from convexguid.families.quaternion_attitude.bench import COLUMNS, attitude_bench_markdown, bench_attitude_rows
from convexguid.problem_files import load_problem
from convexguid.reference import casadi_available

MULTICONE = Path(__file__).resolve().parents[1] / "problems" / "wang_multicone_time.yaml"
K = 10


@pytest.fixture(scope="module")
def rows():
    return bench_attitude_rows(load_problem(MULTICONE), [K], repeat=1)


def _row(rows, method):
    found = [r for r in rows if r.method == method]
    assert len(found) == 1, f"{method}: {len(found)} rows"
    return found[0]


def _ok_row(rows, method):
    """The row of ``method``, which must have succeeded (converged, or IPOPT reported success)."""
    row = _row(rows, method)
    assert row.ok, f"K = {K} {method} did not succeed: {row.status}: {row.message}"
    return row


def test_path_transfer_row_once(rows):
    row = _ok_row(rows, "path_transfer")
    assert row.intervals is None
    assert row.tf_s > 0 and row.wall_s > 0


def test_path_transfer_is_skipped_without_a_rate_bound():
    """The planner's time law needs a rate bound; a file without one (Betts' slew) gets a row saying so, not a
    failure."""
    spec = load_problem(MULTICONE.parent / "betts_asymmetric_slew.yaml")
    row = attitude_bench._path_transfer_row(attitude_bench.build_case(spec), 1)
    assert row.status == "skipped" and "rate bound" in row.message


@pytest.mark.parametrize("objective", ["time", "energy"])
def test_scp_rows_have_positive_times(rows, objective):
    row = _row(rows, f"scp {objective}")
    assert row.intervals == K
    assert row.wall_s > 0 and row.scp_s > 0 and row.solver_s > 0
    assert row.scp_s <= row.wall_s
    assert row.iterations > 0


@pytest.mark.parametrize("solver", ["scp", "ipopt"])
def test_energy_final_time_is_the_factor_times_the_minimum_time(rows, solver):
    if solver == "ipopt":
        pytest.importorskip("casadi")
    scp_time = _ok_row(rows, "scp time")
    energy = _ok_row(rows, f"{solver} energy")
    assert energy.tf_s == pytest.approx(attitude_bench.ENERGY_TF_FACTOR * scp_time.tf_s)


@pytest.mark.parametrize("objective", ["time", "energy"])
def test_ipopt_rows_have_positive_times_and_gaps(rows, objective):
    pytest.importorskip("casadi")
    ipopt = _ok_row(rows, f"ipopt {objective}")
    assert ipopt.wall_s > 0 and ipopt.setup_s > 0 and ipopt.iterations > 0
    assert ipopt.gap is None  # the reference of the gaps
    scp = _ok_row(rows, f"scp {objective}")
    polish = _ok_row(rows, f"ipopt @scp {objective}")
    assert polish.wall_s > 0 and polish.setup_s > 0
    for row in (scp, polish):
        assert row.gap == pytest.approx((row.value - ipopt.value) / ipopt.value), row.method


def test_no_ipopt_rows_without_ipopt():
    if casadi_available():
        pytest.skip("covered by the module run; this checks the rows a casadi-less install gets")
    rows = bench_attitude_rows(load_problem(MULTICONE), [K], repeat=1)
    assert not [r for r in rows if r.solver.startswith("ipopt")]


def test_markdown_has_the_table_and_notes(rows):
    text = attitude_bench_markdown(rows, str(MULTICONE), [K], 1)
    assert "| " + " | ".join(COLUMNS) + " |" in text
    assert "OPENBLAS_NUM_THREADS=" in text
    assert "--nodes 10 --repeat 1" in text
    for method in ("path_transfer", "scp time", "scp energy"):
        assert f"| {method} |" in text
    _ok_row(rows, "scp time")  # the timing note is written for a converged minimum-time SCP only
    assert "SCP minimum time at K = 10 (11 nodes) under 1 s" in text
    # a file without a target gets the times only
    other = attitude_bench_markdown(rows, str(MULTICONE.with_name("my_slew.yaml")), [K], 1)
    assert "SCP minimum time at K = 10 (11 nodes): whole solve" in other and "met)" not in other


def test_bench_command_dispatches_attitude_files(monkeypatch, tmp_path):
    """``convexguid bench`` hands the loaded file on; without ``--nodes`` the attitude default grid."""
    calls = []
    monkeypatch.setattr(attitude_bench, "run_attitude_bench", lambda *args: calls.append(args) or 0)
    out = tmp_path / "bench.md"
    assert main(["bench", str(MULTICONE), "--repeat", "2", "--output", str(out)]) == 0
    assert main(["bench", str(MULTICONE), "--nodes", "12", "24", "--repeat", "1"]) == 0
    assert [(spec.source, *rest) for spec, *rest in calls] == [
        (str(MULTICONE), attitude_bench.DEFAULT_INTERVALS, 2, out), (str(MULTICONE), [12, 24], 1, None)]
