"""The attitude benchmark (SCP vs IPOPT against the grid size) runs end to end on a small grid.

One ``K = 10`` run with ``repeat = 1`` (a few seconds): every method has a row with positive
times, the markdown carries the table, and ``convexguid bench`` passes ``quaternion_attitude``
files to :func:`convexguid.families.quaternion_attitude.bench.run_attitude_bench`. The IPOPT rows
are checked only when ``casadi`` is installed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import convexguid.families.quaternion_attitude.bench as attitude_bench
from convexguid.cli import main
from convexguid.families.quaternion_attitude.bench import COLUMNS, attitude_bench_markdown, bench_attitude_rows
from convexguid.reference import casadi_available

MULTICONE = Path(__file__).resolve().parents[1] / "problems" / "wang_multicone_time.yaml"
K = 10


@pytest.fixture(scope="module")
def rows():
    return bench_attitude_rows(MULTICONE, [K], repeat=1)


def _row(rows, method):
    found = [r for r in rows if r.method == method]
    assert len(found) == 1, f"{method}: {len(found)} rows"
    return found[0]


def test_path_transfer_row_once(rows):
    row = _row(rows, "path_transfer")
    assert row.intervals is None
    assert row.ok and row.tf_s > 0 and row.wall_s > 0


@pytest.mark.parametrize("objective", ["time", "energy"])
def test_scp_rows_have_positive_times(rows, objective):
    row = _row(rows, f"scp {objective}")
    assert row.intervals == K
    assert row.wall_s > 0 and row.scp_s > 0 and row.solver_s > 0
    assert row.scp_s <= row.wall_s
    assert row.iterations > 0


def test_energy_final_time_is_the_factor_times_the_minimum_time(rows):
    scp_time, scp_energy = _row(rows, "scp time"), _row(rows, "scp energy")
    if not scp_time.ok:
        pytest.skip(f"minimum-time SCP did not converge: {scp_time.message}")
    assert scp_energy.tf_s == pytest.approx(attitude_bench.ENERGY_TF_FACTOR * scp_time.tf_s)


@pytest.mark.parametrize("objective", ["time", "energy"])
def test_ipopt_rows_have_positive_times_and_gaps(rows, objective):
    if not casadi_available():
        pytest.skip("casadi is not installed")
    ipopt = _row(rows, f"ipopt {objective}")
    assert ipopt.wall_s > 0 and ipopt.setup_s > 0 and ipopt.iterations > 0
    assert ipopt.gap is None  # the reference of the gaps
    scp = _row(rows, f"scp {objective}")
    if scp.ok and ipopt.ok:
        assert scp.gap == pytest.approx((scp.value - ipopt.value) / ipopt.value)
        polish = _row(rows, f"ipopt @scp {objective}")
        assert polish.wall_s > 0 and polish.setup_s > 0


def test_no_ipopt_rows_without_ipopt():
    if casadi_available():
        pytest.skip("covered by the module run; this checks the rows a casadi-less install gets")
    rows = bench_attitude_rows(MULTICONE, [K], repeat=1)
    assert not [r for r in rows if r.solver.startswith("ipopt")]


def test_markdown_has_the_table_and_notes(rows):
    text = attitude_bench_markdown(rows, MULTICONE, [K], 1)
    assert "| " + " | ".join(COLUMNS) + " |" in text
    assert "OPENBLAS_NUM_THREADS=" in text
    assert "--nodes 10 --repeat 1" in text
    for method in ("path_transfer", "scp time", "scp energy"):
        assert f"| {method} |" in text
    assert "SCP minimum time at K = 10 (11 nodes) under 1 s" in text or not _row(rows, "scp time").ok


def test_bench_command_dispatches_attitude_files(monkeypatch, tmp_path):
    """``convexguid bench`` hands the file on; the command line's flat default grid means the attitude default."""
    calls = []
    monkeypatch.setattr(attitude_bench, "run_attitude_bench", lambda *args: calls.append(args) or 0)
    out = tmp_path / "bench.md"
    assert main(["bench", str(MULTICONE), "--repeat", "2", "--output", str(out)]) == 0
    assert main(["bench", str(MULTICONE), "--nodes", "12", "24", "--repeat", "1"]) == 0
    assert calls == [(MULTICONE, attitude_bench.DEFAULT_INTERVALS, 2, out), (MULTICONE, [12, 24], 1, None)]
