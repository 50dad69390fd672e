"""Outputs are never lost or corrupted (issue 14).

* :mod:`convexguid.outputs`: atomic files (temporary file + rename, nothing left on failure), staged output
  folders swapped in whole, and the checks that refuse an unusable path before any work.
* The command line: bad output paths are exit 2 with one line before the solve; a write failure after the solve
  is exit 1 with one line saying where the summary went; a reused ``--out`` keeps nothing of an earlier run;
  20 concurrent pairs of runs into one ``--out`` always leave one run's complete folder.
* ``convexguid validate``: a problem without ``reference:`` is solved, verified and reported as having nothing
  to compare; the report carries no compute time (they go to the timings file), so it is the same every run.
"""

from __future__ import annotations

import csv
import dataclasses
import errno
import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

import convexguid.solution_plots
from convexguid.cli import main
from convexguid.errors import OutputError
from convexguid.outputs import (
    atomic_file,
    check_output_file,
    check_output_folder,
    staged_folder,
    write_text_atomic,
)
from convexguid.problem_files import load_problem
from convexguid.validation.run import CaseResult, render
from convexguid.validation.timings import render_timings, timings_path

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "problems" / "cai2018_flat_attitude.yaml"
NO_REFERENCE = ROOT / "problems" / "cai2018_flat_attitude_sun_active.yaml"
TIMING_KEYS = ("wall_time_s", "timing")
"""Summary keys that change from run to run (everything else of a run is reproducible to the byte)."""


def _entries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@pytest.fixture
def unwritable(tmp_path) -> Path:
    """A folder in which no file can be created (a read-only folder; as root, /sys)."""
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o500)
    candidates = [folder, Path("/sys")]
    for candidate in candidates:
        try:
            (candidate / "probe").touch()
        except OSError:
            yield candidate
            break
        (candidate / "probe").unlink()
    else:
        pytest.skip("no unwritable folder on this machine (running as root without /sys)")
    folder.chmod(0o700)


@pytest.fixture
def no_solve(monkeypatch):
    """Fail the test if anything is solved or simulated."""

    def refuse(*args, **kwargs):
        raise AssertionError("an output problem must be reported before the solve")

    monkeypatch.setattr("convexguid.api.solve", refuse)
    monkeypatch.setattr("convexguid.api.simulate", refuse)


# --- atomic files and staged folders ----------------------------------------------------------------------


def test_atomic_file_replaces_whole_or_not_at_all(tmp_path):
    target = tmp_path / "data.txt"
    write_text_atomic(target, "old\n")
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~_umask()  # as a plain open() would create it
    target.chmod(0o640)
    with pytest.raises(RuntimeError), atomic_file(target) as fh:
        fh.write("half of the new")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old\n"
    assert _entries(tmp_path) == ["data.txt"]  # no temporary file left
    write_text_atomic(target, "new\n")
    assert target.read_text() == "new\n"
    assert stat.S_IMODE(target.stat().st_mode) == 0o640  # the replaced file's permissions are kept
    assert _entries(tmp_path) == ["data.txt"]


def test_atomic_file_follows_a_link_and_writes_a_device_directly(tmp_path):
    real = tmp_path / "real.json"
    real.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    write_text_atomic(link, "[1]")
    assert link.is_symlink() and real.read_text() == "[1]"
    write_text_atomic(os.devnull, "discarded")  # not replaced by a regular file
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode)


def test_concurrent_writers_never_share_a_temporary_file(tmp_path):
    target = tmp_path / "summary.json"
    with atomic_file(target) as first, atomic_file(target) as second:
        assert first.name != second.name
        first.write("first")
        second.write("second")
    assert target.read_text() == "first"  # the last one closed (the outer block) wins, whole
    assert _entries(tmp_path) == ["summary.json"]


def test_staged_folder_is_published_whole_and_replaces_everything_before_it(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "stale.png").write_text("from an earlier problem")
    with staged_folder(out, replace=True) as staging:
        (staging / "summary.json").write_text("{}")
        assert _entries(out) == ["stale.png"]  # nothing visible until the block completes
    assert _entries(out) == ["summary.json"]
    assert stat.S_IMODE(out.stat().st_mode) == 0o777 & ~_umask()
    assert _entries(tmp_path) == ["out"]  # no staging or replaced folder left


def test_a_failed_staged_folder_leaves_the_target_alone(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("previous run")
    with pytest.raises(OSError, match="disk full"), staged_folder(out, replace=True) as staging:
        (staging / "trajectory.csv").write_text("t_s\n")
        raise OSError(errno.ENOSPC, "disk full")
    assert _entries(out) == ["summary.json"] and (out / "summary.json").read_text() == "previous run"
    assert _entries(tmp_path) == ["out"]


def test_a_folder_filled_meanwhile_is_not_replaced_without_permission(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(OutputError, match="the outputs of this run are in") as caught:
        with staged_folder(out, replace=False) as staging:
            (staging / "summary.json").write_text("this run")
            out.mkdir()
            (out / "summary.json").write_text("another run")
    assert (out / "summary.json").read_text() == "another run"
    kept = Path(str(caught.value).rsplit(" ", 1)[-1])
    assert (kept / "summary.json").read_text() == "this run"  # the outputs are not lost


def test_output_checks_refuse_unusable_paths(tmp_path, unwritable):
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    with pytest.raises(OutputError, match="it is a folder"):
        check_output_file(tmp_path, "summary JSON")
    with pytest.raises(OutputError, match="does not exist"):
        check_output_file(tmp_path / "missing" / "s.json", "summary JSON")
    with pytest.raises(OutputError, match="is not a folder"):
        check_output_file(a_file / "s.json", "summary JSON")
    with pytest.raises(OutputError, match="cannot write in"):
        check_output_file(unwritable / "s.json", "summary JSON")
    with pytest.raises(OutputError, match="exists and is not a folder"):
        check_output_folder(a_file, overwrite=True)
    with pytest.raises(OutputError, match="cannot write in"):
        check_output_folder(unwritable / "out", overwrite=True)
    with pytest.raises(OutputError, match="not empty; give --overwrite"):
        check_output_folder(tmp_path, overwrite=False)
    with pytest.raises(OutputError, match="would remove"):
        check_output_folder(tmp_path, overwrite=True, keep=[a_file])
    check_output_file(os.devnull, "summary JSON")
    check_output_folder(tmp_path / "new" / "out", overwrite=False)  # missing parents are created later
    assert _entries(tmp_path) == ["a_file", "read-only"]  # the checks create nothing


# --- the command line ------------------------------------------------------------------------------------


def _bad_output_args(tmp: Path, unwritable: Path) -> dict[str, list[str]]:
    (tmp / "a_file").write_text("")
    (tmp / "full").mkdir()
    (tmp / "full" / "keep.txt").write_text("")
    return {
        "out-is-a-file": ["--out", str(tmp / "a_file")],
        "out-parent-is-a-file": ["--out", str(tmp / "a_file" / "out")],
        "out-unwritable": ["--out", str(unwritable / "out")],
        "out-not-empty": ["--out", str(tmp / "full")],
        "summary-is-a-folder": ["--summary-json", str(tmp / "full")],
        "summary-folder-missing": ["--summary-json", str(tmp / "missing" / "s.json")],
        "summary-unwritable": ["--summary-json", str(unwritable / "s.json")],
    }


@pytest.mark.parametrize("case", ["out-is-a-file", "out-parent-is-a-file", "out-unwritable", "out-not-empty",
                                  "summary-is-a-folder", "summary-folder-missing", "summary-unwritable"])
@pytest.mark.parametrize("command", ["solve", "simulate"])
def test_bad_output_paths_are_exit_2_before_the_run(tmp_path, capsys, unwritable, no_solve, case, command):
    problem = PAPER if command == "solve" else ROOT / "problems" / "guo2011_fixed_gains.yaml"
    args = _bad_output_args(tmp_path, unwritable)[case]
    before = _entries(tmp_path)
    assert main([command, str(problem), "--quiet", *args]) == 2
    out, err = capsys.readouterr()
    assert err.startswith("convexguid: ") and err.count("\n") == 1 and "Traceback" not in err, err
    assert args[1] in err
    assert _entries(tmp_path) == before and _entries(tmp_path / "full") == ["keep.txt"]  # nothing written


@pytest.mark.parametrize("where", ["missing", "unwritable", "a-folder"])
def test_validate_report_problems_are_exit_2_before_solving(tmp_path, capsys, unwritable, no_solve, where):
    report = {"missing": tmp_path / "missing" / "REPORT.md", "unwritable": unwritable / "REPORT.md",
              "a-folder": tmp_path}[where]
    assert main(["validate", str(PAPER), "--report", str(report)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"convexguid: {report}: cannot write the report here") and err.count("\n") == 1, err
    assert _entries(tmp_path) == ["read-only"]  # only the fixture's folder: nothing written


def test_a_write_failure_after_the_solve_keeps_the_summary(tmp_path, capsys, monkeypatch):
    def disk_full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(convexguid.solution_plots, "plot_solution", disk_full)
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))  # where the summary is rescued
    out = tmp_path / "out"
    assert main(["solve", str(PAPER), "--quiet", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"could not write --out {out}: No space left on device; the summary was written to " in err
    rescued = Path(err.strip().rsplit(" ", 1)[-1])
    summary = json.loads(rescued.read_text())
    assert summary["problem"] == "cai2018-flat-attitude" and summary["status"] == "converged"
    assert _entries(tmp_path) == [rescued.name]  # no --out folder, no staging folder left

    capsys.readouterr()
    given = tmp_path / "s.json"
    assert main(["solve", str(PAPER), "--quiet", "--out", str(out), "--summary-json", str(given)]) == 1
    err = capsys.readouterr().err
    assert err.strip().endswith(f"the summary is in {given}") and json.loads(given.read_text())["objective"]


def test_a_reused_out_folder_keeps_nothing_of_the_earlier_problem(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["solve", str(PAPER), "--quiet", "--set", "keep_out.0.name=moon", "--out", str(out)]) == 0
    assert "keep_out_moon_deg.png" in _entries(out)
    assert main(["solve", str(PAPER), "--quiet", "--out", str(out), "--overwrite"]) == 0
    assert "keep_out_moon_deg.png" not in _entries(out) and "keep_out_sun_deg.png" in _entries(out)
    assert _entries(tmp_path) == ["out"]


# --- concurrency: 20 pairs of processes into one --out -----------------------------------------------------

VARIANTS = {
    "16 nodes, 100 s": ["--set", "discretization.nodes=16"],
    "20 nodes, 120 s": ["--set", "discretization.nodes=20", "--set", "boundary.tf_s=120"],
}
"""Two runs that differ in every file they write (node count, final time, objective)."""
PAIRS = 20


def _run(variant: str, out: Path) -> subprocess.Popen:
    command = [sys.executable, "-m", "convexguid.cli", "solve", str(PAPER), "--quiet", "--overwrite",
               "--out", str(out), *VARIANTS[variant]]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)


def _folder(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _without_times(summary: bytes) -> dict:
    return {k: v for k, v in json.loads(summary).items() if k not in TIMING_KEYS}


def _check_csv(name: str, data: bytes) -> int:
    """Every row of a CSV has the header's number of fields, all numbers; the number of data rows."""
    rows = list(csv.reader(data.decode().splitlines()))
    assert rows and rows[0][0] == "t_s", name
    for i, row in enumerate(rows[1:], start=2):
        assert len(row) == len(rows[0]), f"{name} line {i}: {len(row)} fields, header {len(rows[0])}"
        [float(v) for v in row]
    return len(rows) - 1


def test_concurrent_runs_into_one_out_folder_never_mix(tmp_path):
    """20 times, two runs of different problems start together into the same ``--out``; after each pair the
    folder is one run's complete output: every file byte-identical to that run's solo output (the summary up to
    its timings), every CSV row complete, no staging folder left."""
    solo = {}
    for variant in VARIANTS:
        process = _run(variant, tmp_path / variant)
        assert process.wait() == 0, process.stderr.read()
        solo[variant] = _folder(tmp_path / variant)
    assert solo["16 nodes, 100 s"]["nodes.csv"] != solo["20 nodes, 120 s"]["nodes.csv"]
    shared = tmp_path / "pairs" / "out"
    shared.parent.mkdir()
    winners = []
    for pair in range(PAIRS):
        processes = [_run(variant, shared) for variant in VARIANTS]
        for process in processes:
            assert process.wait() == 0, f"pair {pair}: {process.stderr.read()}"
        assert _entries(shared.parent) == ["out"], f"pair {pair}: left behind"
        found = _folder(shared)
        summary = _without_times(found["summary.json"])
        variant = next((v for v in VARIANTS if _without_times(solo[v]["summary.json"]) == summary), None)
        assert variant is not None, f"pair {pair}: summary.json of neither run"
        assert sorted(found) == sorted(solo[variant]), f"pair {pair}: files of both runs"
        for name in ("trajectory.csv", "nodes.csv"):
            _check_csv(name, found[name])
        mixed = [name for name in found if name != "summary.json" and found[name] != solo[variant][name]]
        assert not mixed, f"pair {pair}: {mixed} not from the run of summary.json ({variant})"
        winners.append(variant)
    print(f"last run to finish, by pair: {winners}")


# --- validate: no reference, no compute times in the report ----------------------------------------------


def test_validate_without_a_reference_solves_verifies_and_says_so(tmp_path, capsys):
    report = tmp_path / "REPORT.md"
    assert main(["validate", str(NO_REFERENCE), "--report", str(report)]) == 0
    out = capsys.readouterr().out
    assert "verified, nothing to compare (no reference)" in out
    text = report.read_text()
    assert "has no `reference:` block: the case is solved and verified, and there is nothing to compare" in text
    assert "| cai2018-flat-attitude-sun-active | converged | passed | no reference |" in text
    assert "Dense verification (2001 points" in text
    assert _entries(tmp_path) == ["REPORT.md", "REPORT.timings.md", "figures"]
    figures = _entries(tmp_path / "figures" / "cai2018-flat-attitude-sun-active")
    assert figures and all(f"figures/cai2018-flat-attitude-sun-active/{f})" in text for f in figures)
    first = {p.name: p.read_bytes() for p in (tmp_path / "figures" / "cai2018-flat-attitude-sun-active").iterdir()}

    assert main(["validate", str(NO_REFERENCE), "--report", str(report)]) == 0
    assert report.read_text() == text  # the same report on the second run
    second = {p.name: p.read_bytes() for p in (tmp_path / "figures" / "cai2018-flat-attitude-sun-active").iterdir()}
    assert second == first


def test_the_report_has_no_compute_times_and_the_timings_file_has_them(tmp_path):
    from convexguid.api import solve

    spec = load_problem(PAPER)
    solution = solve(spec)
    runs = [dataclasses.replace(solution, wall_time_s=wall, timing={**solution.timing, "scp_s": wall / 2,
                                                                    "solver_s": wall / 4})
            for wall in (1.234567, 98.7654)]
    reports = [render([CaseResult(spec, sol, (), ())], tmp_path, (), "REPORT.timings.md") for sol in runs]
    assert reports[0] == reports[1]
    assert "`REPORT.timings.md` beside this report" in reports[0]
    timings = [render_timings([CaseResult(spec, sol, (), ())]) for sol in runs]
    assert "| 1.235 | 0.617 | 0.309 |" in timings[0] and "| 98.765 | 49.383 | 24.691 |" in timings[1]
    assert timings_path(tmp_path / "REPORT.md") == tmp_path / "REPORT.timings.md"


def test_validate_reports_a_write_failure_after_solving_on_one_line(tmp_path, capsys, monkeypatch):
    def disk_full(path, text):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr("convexguid.validation.run.write_text_atomic", disk_full)
    report = tmp_path / "REPORT.md"
    assert main(["validate", str(NO_REFERENCE), "--report", str(report)]) == 1
    err = capsys.readouterr().err
    assert err == f"convexguid: could not write the validation outputs: {report}: No space left on device\n"
