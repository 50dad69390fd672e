"""Input that never crashes, diagnoses that name the real cause, size limits, progress and Ctrl-C (issue 14, part B).

Everything runs in process; nothing here solves a full problem except where a solve is the point.
"""

from __future__ import annotations

import _thread
import io
import multiprocessing
import os
import shutil
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

import convexguid
from convexguid import progress
from convexguid.cli import main
from convexguid.dynamics.rigid_body import min_slew_time
from convexguid.errors import SpecError
from convexguid.families import FAMILIES
from convexguid.problem_files import load_problem
from convexguid.spec.loader import MAX_EXPANDED_NODES

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ROOT / "problems"
FLAT = str(PROBLEMS / "cai2018_flat_attitude.yaml")


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.endswith("\n") and err.startswith("convexguid: "), repr(err)
    return err.strip()


def _flat_file(tmp_path: Path, **replace: str) -> Path:
    """The paper's flat-attitude file with some lines replaced (``old=new`` pairs), unquoted as a user types them."""
    text = Path(FLAT).read_text()
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "p.yaml"
    path.write_text(text)
    return path


# --- numbers as people type them -------------------------------------------------------------------------------

@pytest.mark.parametrize(("typed", "value"), [("1e2", 100.0), ("1E2", 100.0), ("1.0e2", 100.0), ("+2.5e1", 25.0)])
def test_scientific_notation_in_overrides_is_a_number(typed, value):
    assert load_problem(FLAT, [f"boundary.tf_s={typed}"]).boundary.tf_s == value


def test_scientific_notation_in_a_file_keeps_names_and_makes_whole_numbers_integers(tmp_path):
    path = _flat_file(tmp_path, **{"tf_s: 100.0": "tf_s: 1e2", "name: cai2018-flat-attitude": "name: 1e5",
                                   "nodes: 32": "nodes: 3.2e1"})
    spec = load_problem(path)
    assert spec.boundary.tf_s == 100.0 and type(spec.boundary.tf_s) is float
    assert spec.name == "1e5"  # a string key gets the text as written
    assert spec.discretization.nodes == 32 and type(spec.discretization.nodes) is int


def test_negative_scientific_time_is_judged_as_a_number():
    with pytest.raises(SpecError, match=r"boundary\.tf_s: must be greater than boundary\.t0_s .*\(got -0\.035\)"):
        load_problem(FLAT, ["boundary.tf_s=-3.5E-2"])


def test_a_quoted_number_stays_a_string():
    with pytest.raises(SpecError, match=r"boundary\.tf_s: wrong type \(got '1e2'\)"):
        load_problem(FLAT, ["boundary.tf_s='1e2'"])


def test_a_fractional_scientific_integer_is_refused():
    with pytest.raises(SpecError, match=r"discretization\.nodes: wrong type"):
        load_problem(FLAT, ["discretization.nodes=3.25e1"])


# --- hostile YAML ----------------------------------------------------------------------------------------------

def _alias_bomb(levels: int) -> str:
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels)]
    return "\n".join(lines + [f"name: *a{levels - 1}", "family: flat_attitude"]) + "\n"


def test_alias_bomb_is_refused_on_one_line(tmp_path, capsys):
    path = tmp_path / "bomb.yaml"
    path.write_text(_alias_bomb(10))  # 9^10 = 3.5e9 strings once expanded
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    line = _one_line_error(capsys)
    assert f"aliases expand to more than {MAX_EXPANDED_NODES} values" in line, line
    assert not (tmp_path / "out").exists()


def test_aliases_below_the_limit_still_work(tmp_path):
    path = _flat_file(tmp_path, **{"-60], rate_degps: [0, 0, 0]}": "-60], rate_degps: &rest [0, 0, 0]}",
                                   "45], rate_degps: [0, 0, 0]}": "45], rate_degps: *rest}"})
    assert load_problem(path).boundary.final.rate_degps == (0.0, 0.0, 0.0)


def test_self_referencing_alias_and_deep_nesting_are_refused(tmp_path):
    cycle = tmp_path / "cycle.yaml"
    cycle.write_text("name: &a [1, *a]\nfamily: flat_attitude\n")
    with pytest.raises(SpecError, match="refer to themselves"):
        load_problem(cycle)
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: " + "[" * 20000 + "]" * 20000 + "\nfamily: flat_attitude\n")
    with pytest.raises(SpecError, match="nested too deeply"):
        load_problem(deep)


def test_a_large_value_is_shown_cut_short(tmp_path):
    path = tmp_path / "big.yaml"
    data = yaml.safe_load(Path(FLAT).read_text())
    data["name"] = [list(range(100))] * 500  # 50 000 values: below the alias limit, far too long to print
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SpecError) as info:
        load_problem(path)
    message = str(info.value)
    assert message.startswith(f"{path}: name: wrong type") and "\n" not in message
    assert len(message) < 400, message


# --- the Python API ----------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("call", "expected"), [
    (lambda: convexguid.solve(None), r"^problem: expected the path of a problem YAML file or a loaded spec \(got None"),
    (lambda: convexguid.solve(5), r"^problem: .*\(got 5\)"),
    (lambda: convexguid.solve(FLAT, overrides=[5]), r"^overrides\[0\]: expected a 'key\.path=value' string \(got 5\)"),
    (lambda: convexguid.solve(FLAT, overrides={"a": 1}), r"^overrides: expected a list"),
    (lambda: convexguid.solve(FLAT, log=5), r"^log: expected a function or None \(got 5\)"),
    (lambda: convexguid.simulate(FLAT, overrides=b"x=1"), r"^overrides: expected a list"),
])
def test_api_arguments_of_the_wrong_type_are_spec_errors(call, expected):
    with pytest.raises(SpecError, match=expected) as info:
        call()
    assert "\n" not in str(info.value)


def test_api_reads_a_plain_string_as_one_override_and_none_as_no_overrides():
    # both are refused for a reason that shows how they were read, before anything is solved
    with pytest.raises(SpecError, match=r"boundary\.tf_s: a 1e-06 s maneuver is too short"):
        convexguid.solve(FLAT, overrides="boundary.tf_s=1e-6")
    with pytest.raises(SpecError, match="is planned, not simulated"):
        convexguid.simulate(FLAT, overrides=None)


def test_a_loaded_spec_is_read_only_with_a_spec_error():
    spec = load_problem(FLAT)
    with pytest.raises(SpecError, match=r"^AttitudeBoundary\.tf_s: a problem spec is read-only \(got 25\)"):
        spec.boundary.tf_s = 25
    with pytest.raises(SpecError, match="read-only"):
        spec.new_key = 1
    with pytest.raises(SpecError, match="read-only"):
        del spec.name
    assert spec.boundary.tf_s == 100.0


# --- diagnoses that name the real cause --------------------------------------------------------------------------

def test_min_slew_time_is_the_bang_bang_time_and_never_above_a_known_optimum():
    inertia = np.diag([2.0, 3.0, 5.0])
    # rest to rest: 2 sqrt(theta lambda_min / tau)
    assert min_slew_time(inertia, 4.0, 1.5) == pytest.approx(2 * np.sqrt(1.5 * 2.0 / 4.0))
    # Bilimoria & Wie (1993): unit inertia, |u_i| <= 1, 180 deg about a principal axis takes 3.24 s at best
    bound = min_slew_time(np.eye(3), np.sqrt(3.0), np.pi)
    assert bound < 3.24
    # boundary rates can only shorten the bound; the bisection agrees with the closed form at (almost) rest
    assert min_slew_time(np.eye(3), 1.0, np.pi, 0.5, 0.5) < min_slew_time(np.eye(3), 1.0, np.pi)
    assert min_slew_time(np.eye(3), 1.0, np.pi, 1e-12, 0.0) == pytest.approx(min_slew_time(np.eye(3), 1.0, np.pi))


@pytest.mark.parametrize("tf", ["1.0e-6", "17"])
def test_an_impossible_maneuver_time_is_refused_up_front_with_the_bound(tf, tmp_path, capsys):
    assert main(["solve", FLAT, "--set", f"boundary.tf_s={tf}", "--out", str(tmp_path / "out")]) == 2
    line = _one_line_error(capsys)
    assert "boundary.tf_s: a " in line and "too short" in line and "at least 17.71 s" in line, line
    assert not (tmp_path / "out").exists()


def test_the_quaternion_family_refuses_an_impossible_energy_time():
    with pytest.raises(SpecError, match=r"boundary\.tf_s: a 0\.5 s maneuver is too short"):
        load_problem(PROBLEMS / "wang_multicone_energy.yaml", ["boundary.tf_s=0.5"])


@pytest.mark.parametrize("which", ["initial", "final"])
def test_a_flat_attitude_boundary_inside_a_keep_out_cone_is_refused(which):
    # roll 20 deg points the sensor 25 deg from the sun, inside the 45 deg cone
    with pytest.raises(SpecError, match=rf"keep_out\.0\.half_angle_deg: the {which} attitude points 'sun'"):
        load_problem(FLAT, [f"boundary.{which}.roll_pitch_yaw_deg=[20, 0, 0]"])


@pytest.mark.parametrize("key", ["initial.position_m", "initial.velocity_mps", "final.position_m",
                                 "final.velocity_mps"])
def test_a_rendezvous_vector_with_the_wrong_length_is_the_one_named(key):
    with pytest.raises(SpecError, match=rf"rendezvous\.yaml: boundary\.{key}: has 3 components but .* have 2"):
        load_problem(PROBLEMS / "wang2003_rendezvous.yaml", [f"boundary.{key}=[1, 2, 3]"])


@pytest.mark.parametrize(("args", "expected"), [
    (["--repeat", "0"], "--repeat: must be at least 1 (got 0)"),
    (["--nodes", "16", "-3"], "--nodes: must be at least 1 (got -3)"),
    (["--backends", "clarabel", "gurobi"], "--backends: unknown backend 'gurobi'; installed: auto, clarabel"),
])
def test_bench_arguments_are_checked_before_anything_runs(args, expected, capsys):
    assert main(["bench", FLAT, *args]) == 2
    assert expected in _one_line_error(capsys)


def test_bench_of_a_file_whose_linked_problem_is_missing_names_its_own_key(tmp_path, capsys):
    lonely = tmp_path / "guo2011_lpmpc_track.yaml"
    shutil.copyfile(PROBLEMS / lonely.name, lonely)
    assert main(["bench", str(lonely)]) == 2
    line = _one_line_error(capsys)
    assert "guo2011_lpmpc_track.yaml: nominal.tf_from.problem:" in line and "give nominal.tf_s instead" in line, line
    assert "--set" not in line  # bench takes no overrides


def test_flat_bench_exits_1_when_a_row_failed(monkeypatch, capsys):
    from convexguid.families.flat_attitude import bench

    rows = [bench.BenchRow(16, "scp/osqp [nodes]", "solver_error", message="backend osqp failed"),
            bench.BenchRow(16, "scp/clarabel [nodes]", "converged", 0.26, 5, 0.1, ok=True)]
    monkeypatch.setattr(bench, "bench_nodes", lambda *args: rows)
    monkeypatch.setattr("convexguid.bench_common.casadi_available", lambda: False)
    assert bench.run_bench(load_problem(FLAT), [16], 1, ["osqp", "clarabel"]) == 1
    monkeypatch.setattr(bench, "bench_nodes", lambda *args: rows[1:])
    assert bench.run_bench(load_problem(FLAT), [16], 1, ["clarabel"]) == 0


# --- size limits -------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("nodes", [1000, 100000])
def test_a_flat_problem_above_the_memory_limit_is_refused_with_the_estimate(nodes, tmp_path, capsys):
    assert main(["solve", FLAT, "--quiet", "--set", f"discretization.nodes={nodes}", "--out",
                 str(tmp_path / "out")]) == 2
    line = _one_line_error(capsys)
    assert "discretization.nodes: problem too large: a run needs about" in line and "iB of memory" in line, line
    assert "above the flat_attitude family's limit of 2 GiB" in line and f"(got {nodes})" in line, line
    assert not (tmp_path / "out").exists()


def test_the_flat_estimate_grows_with_nodes_check_points_and_cones():
    estimate = FAMILIES["flat_attitude"].estimate_size
    base = estimate(load_problem(FLAT)).memory_bytes
    assert estimate(load_problem(FLAT, ["discretization.nodes=64"])).memory_bytes > base
    assert estimate(load_problem(FLAT, ["discretization.check_points_per_interval=5"])).memory_bytes > base
    assert estimate(load_problem(FLAT, ["keep_out=[]"])).memory_bytes < base


@pytest.mark.parametrize(("problem", "overrides", "key"), [
    ("guo2011_sweep.yaml", ["simulation.dt_s=0.001"], "simulation.dt_s"),  # 3e6 steps x 9 cases
    ("feng2018_lpmpc_montecarlo.yaml", ["monte_carlo.runs=10000000"], "monte_carlo.runs"),
    ("feng2018_lpmpc_single.yaml", ["simulation.dt_s=1e-6"], "simulation.dt_s"),
])
def test_simulations_above_the_memory_limit_are_refused(problem, overrides, key):
    with pytest.raises(SpecError, match=rf"{problem}: {key}: problem too large: .* of memory \("):
        convexguid.simulate(PROBLEMS / problem, overrides)


def test_every_problem_file_is_within_its_family_limit():
    for path in sorted(PROBLEMS.glob("*.yaml")):
        spec = load_problem(path)
        family = FAMILIES[spec.family]
        assert family.estimate_size is not None, spec.family
        assert family.estimate_size(spec).memory_bytes < family.memory_limit_bytes / 4, path.name


def test_out_of_memory_is_one_line_not_a_traceback(monkeypatch, capsys):
    import dataclasses

    def exhausted(spec, log, planner):
        raise MemoryError

    monkeypatch.setitem(FAMILIES, "flat_attitude", dataclasses.replace(FAMILIES["flat_attitude"], solve=exhausted))
    assert main(["solve", FLAT, "--quiet"]) == 2
    assert "out of memory" in _one_line_error(capsys)


# --- progress and Ctrl-C -----------------------------------------------------------------------------------------

def test_report_outside_a_run_does_nothing():
    progress.report("anything", 1, 2)  # no run: no display, no interrupt


def test_run_returns_and_raises_what_the_work_does_and_shows_nothing_off_a_terminal():
    stream = io.StringIO()
    assert progress.run(lambda: 42, "job", stream) == 42
    with pytest.raises(ValueError, match="boom"):
        progress.run(lambda: (_ for _ in ()).throw(ValueError("boom")), "job", stream)
    assert stream.getvalue() == ""


def test_forced_progress_prints_heartbeat_lines_with_the_stage(monkeypatch):
    monkeypatch.setenv(progress.ENVIRONMENT, "1")
    monkeypatch.setattr(progress, "SHOW_AFTER_S", 0.0)
    monkeypatch.setattr(progress, "HEARTBEAT_S", 0.0)
    stream = io.StringIO()

    def work():
        while "simulation step 7/10" not in stream.getvalue():
            progress.report("simulation step", 7, 10)
            time.sleep(0.01)
        return "done"

    assert progress.run(work, "simulate x", stream) == "done"
    assert "simulate x: simulation step 7/10 (70%)" in stream.getvalue()


@pytest.fixture
def ctrl_c_reaches_python():
    """Python's own SIGINT handler for the test. A process that a non-interactive shell starts in the background
    inherits SIGINT ignored, and ``_thread.interrupt_main()`` then does nothing: the tests below waited forever."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_the_work_at_its_next_report(ctrl_c_reaches_python):
    started, stopped = threading.Event(), threading.Event()

    def work():
        try:
            while True:
                progress.report("step")
                started.set()
                time.sleep(0.005)
        finally:
            stopped.set()

    def press_ctrl_c():
        started.wait()
        _thread.interrupt_main()

    threading.Thread(target=press_ctrl_c).start()
    with pytest.raises(KeyboardInterrupt):
        progress.run(work, "loop", io.StringIO())
    assert stopped.wait(progress.STOP_GRACE_S * 5), "the work kept running after Ctrl-C"


def test_ctrl_c_during_a_simulation_exits_130_and_writes_nothing(monkeypatch, tmp_path, capsys,
                                                                  ctrl_c_reaches_python):
    from convexguid.families.potential_function import plant as reaction_wheel

    calls = []

    def report_then_press_ctrl_c(*args):
        calls.append(args)
        if len(calls) == 100:
            _thread.interrupt_main()
        progress.report(*args)

    monkeypatch.setattr(reaction_wheel, "report", report_then_press_ctrl_c)
    out = tmp_path / "out"
    code = main(["simulate", str(PROBLEMS / "guo2011_adaptive.yaml"), "--quiet", "--out", str(out),
                 "--summary-json", str(tmp_path / "s.json")])
    assert code == 130
    assert _one_line_error(capsys) == "convexguid: interrupted"
    assert not out.exists() and not (tmp_path / "s.json").exists()
    assert len(calls) < 26001  # stopped long before the 2600 s / 0.1 s steps


def _slow_run(marker_dir: str) -> dict:
    """A stand-in Monte Carlo run for the pool test: leaves a file, takes a moment."""
    Path(marker_dir, f"{os.getpid()}-{time.monotonic_ns()}").touch()
    time.sleep(0.1)
    return {}


def test_ctrl_c_cancels_the_queued_monte_carlo_runs(monkeypatch, tmp_path, ctrl_c_reaches_python):
    from convexguid.families.lpmpc import solve as lpmpc_solve

    monkeypatch.setattr(lpmpc_solve, "_run_star", _slow_run)

    pressed = []

    def report_then_press_ctrl_c(stage, done=None, total=None):
        if done is not None and done >= 2 and not pressed:
            pressed.append(done)
            _thread.interrupt_main()
        progress.report(stage, done, total)

    monkeypatch.setattr(lpmpc_solve, "report", report_then_press_ctrl_c)
    runs = 100
    with pytest.raises(KeyboardInterrupt):
        progress.run(lambda: lpmpc_solve._fly_on_pool([str(tmp_path)] * runs, 2), "monte carlo", io.StringIO())
    deadline = time.monotonic() + 60  # a safety net only: the workers end once the runs in flight are done
    while multiprocessing.active_children() and time.monotonic() < deadline:
        time.sleep(0.05)
    started = len(list(tmp_path.iterdir()))  # final: no worker is left to start another run
    assert started < runs / 2, f"{started} of {runs} runs ran after Ctrl-C: the queue was not cancelled"
