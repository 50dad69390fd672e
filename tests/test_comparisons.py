"""Cross-method tables of the validation report: groups declared in the problem files, inputs linked between cases.

No solves here: the tables are rendered from synthetic results (the end-to-end Guo comparison is in
``test_quaternion_attitude.py``), and the run order and link overrides are checked on loaded specs.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from convexguid.api import solve
from convexguid.cli import main
from convexguid.errors import SpecError
from convexguid.families import get_family
from convexguid.families.quaternion_attitude.figures import ConeGeometry
from convexguid.problem_files import load_problem
from convexguid.scp.problem import ProgramSize
from convexguid.solution import Solution
from convexguid.validation import comparisons
from convexguid.validation.comparisons import TABLES, check_comparisons, comparison_sections, comparison_timings
from convexguid.validation.links import link_values, linked_cases, run_order
from convexguid.validation.run import CaseResult
from convexguid.verification import ConstraintCheck, Verification

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MULTICONE = [PROBLEMS / f"wang_multicone_{n}.yaml" for n in ("path_transfer", "time", "energy")]
GUO = [PROBLEMS / f"guo2011_{n}.yaml" for n in ("adaptive", "scp_time", "scp_energy")]
GUO_ENERGY = GUO[2]


def _solution(spec, wall_time_s=1.0, checks=(), **figures) -> Solution:
    """A synthetic result carrying ``figures`` (figures of the family's type not given are None)."""
    verification = Verification(grid_points=100, checks=tuple(checks), final_state_error=0.0, final_errors={},
                                passed=True)
    kind = get_family(spec.family).figures
    unset = {f.name: None for f in dataclasses.fields(kind) if f.default is dataclasses.MISSING}
    return Solution(problem=spec.name, family=spec.family, method=spec.method, status="converged", objective=0.0,
                    iterations=1, size=ProgramSize(1, 0, 0), wall_time_s=wall_time_s, solver="test",
                    verification=verification, figures=kind(**{**unset, **figures}))


def _result(spec, sol) -> CaseResult:
    return CaseResult(spec, sol, (), ())


def _rows(lines: list[str]) -> list[list[str]]:
    return [line.strip("| ").split(" | ") for line in lines if line.startswith("| ") and "| method |" not in line]


def _write(tmp_path: Path, source: Path, old: str, new: str) -> Path:
    text = source.read_text()
    assert old in text
    path = tmp_path / source.name
    path.write_text(text.replace(old, new))
    return path


# --- the problem files ------------------------------------------------------------------------------------


def test_the_problem_files_declare_both_groups():
    groups = {}
    for path in MULTICONE + GUO:
        entry = load_problem(path).reference.comparison
        groups.setdefault(entry.table, []).append((entry.role, entry.label))
    assert groups == {
        "multicone": [("baseline", "path transfer (paper's planner)"), ("min_time", "SCP, minimum time"),
                      ("min_energy", "SCP, minimum energy (t_f = 1.3 x minimum time)")],
        "forbidden_attitude": [("baseline", "potential-function controller (Fig. 3 case, closed loop, disturbed)"),
                               ("min_time", "SCP, minimum time"),
                               ("min_energy", "SCP, minimum energy at the controller's maneuver time")]}
    check_comparisons([load_problem(p) for p in MULTICONE + GUO])


@pytest.mark.parametrize("old,new,needle", [
    ("role: min_time}", "role: min_time, colour: red}", "reference.comparison.colour: unknown key"),
    ("role: min_time}", "role: fastest}", "reference.comparison.role"),
    ('label: "SCP, minimum time"', 'label: ""', "reference.comparison.label"),
])
def test_bad_comparison_block_is_a_one_line_error(tmp_path, old, new, needle):
    path = _write(tmp_path, GUO[1], old, new)
    with pytest.raises(SpecError, match="^[^\n]*$") as err:
        load_problem(path)
    assert needle in str(err.value)


def test_unknown_table_column_or_figure_and_duplicate_roles_are_refused_before_solving(tmp_path):
    specs = [load_problem(p) for p in GUO]
    bad_table = load_problem(_write(tmp_path, GUO[1], "table: forbidden_attitude", "table: forbidden"))
    with pytest.raises(SpecError, match=r"comparison\.table: unknown table .*known tables: multicone"):
        check_comparisons([bad_table])
    bad_column = load_problem(_write(tmp_path, GUO[0], "forbidden_angle: min_theta_b_deg", "theta: min_theta_b_deg"))
    with pytest.raises(SpecError, match=r"figures\.theta: not a column of table 'forbidden_attitude'"):
        check_comparisons([bad_column])
    bad_figure = load_problem(_write(tmp_path, GUO[0], "energy: energy_N2m2s", "energy: energy_J"))
    with pytest.raises(SpecError, match=r"figures\.energy: not a figure of family 'potential_function'"):
        check_comparisons([bad_figure])
    twin = load_problem(_write(tmp_path, GUO[1], "name: guo2011-scp-time", "name: guo2011-scp-time-2"))
    with pytest.raises(SpecError, match="'guo2011-scp-time' already has this role"):
        check_comparisons([*specs, twin])


# --- boundary.tf_from -------------------------------------------------------------------------------------


def test_tf_from_is_an_unresolved_input_link():
    spec = load_problem(GUO_ENERGY)
    assert spec.boundary.tf_s is None
    [(key, link_key, link)] = spec.input_links()
    assert (key, link_key, link.problem, link.figure) == ("boundary.tf_s", "boundary.tf_from", "guo2011-adaptive",
                                                          "maneuver_time_01deg_s")
    resolved = load_problem(GUO_ENERGY, ["boundary.tf_from=null", "boundary.tf_s=196.8"])
    assert resolved.boundary.tf_s == 196.8 and resolved.input_links() == ()


@pytest.mark.parametrize("overrides,needle", [
    (["boundary.tf_s=100"], "boundary.tf_from: boundary.tf_from and boundary.tf_s are both set"),
    (["boundary.tf_min_time_factor=1.3"], "boundary.tf_from and boundary.tf_min_time_factor are both set"),
    (["objective=time"], "boundary.tf_from: minimum time has a free final time"),
    (["boundary.tf_from={problem: guo2011-adaptive}"], "boundary.tf_from.figure: missing required key"),
])
def test_bad_tf_from_is_a_one_line_error(overrides, needle):
    with pytest.raises(SpecError) as err:
        load_problem(GUO_ENERGY, overrides)
    assert "\n" not in str(err.value) and needle in str(err.value)


def test_the_api_refuses_an_unresolved_link_and_the_command_checks_it_before_solving(capsys):
    with pytest.raises(SpecError, match="the Python API does not solve; resolve it first.*set boundary.tf_s"):
        solve(GUO_ENERGY)
    assert main(["solve", str(GUO_ENERGY), "--quiet", "--set", "boundary.tf_from.figure=maneuver_time_s"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "boundary.tf_from.figure: not a figure of 'guo2011-adaptive'" in err


def test_linked_cases_are_read_from_the_files_beside_the_problem():
    cases = linked_cases(load_problem(GUO_ENERGY))
    assert [(case.name, Path(case.source).name) for case in cases] == [("guo2011-adaptive", GUO[0].name)]
    assert linked_cases(load_problem(GUO[1])) == []


def test_linked_cases_run_after_the_case_they_name():
    specs = [load_problem(p) for p in (GUO_ENERGY, MULTICONE[0], GUO[1], GUO[0])]
    order = run_order(specs)
    assert [specs[i].name for i in order] == ["wang-multicone-path-transfer", "guo2011-scp-time",
                                              "guo2011-adaptive", "guo2011-scp-energy"]
    assert run_order(specs[1:]) == [0, 1, 2]


def test_a_link_to_a_missing_case_or_figure_is_refused_before_solving(tmp_path):
    with pytest.raises(SpecError, match=r"boundary\.tf_from\.problem: not another case .*'guo2011-adaptive'"):
        run_order([load_problem(GUO_ENERGY), load_problem(GUO[1])])
    wrong = load_problem(GUO_ENERGY, ["boundary.tf_from.figure=maneuver_time_s"])
    with pytest.raises(SpecError, match=r"tf_from\.figure: not a figure of 'guo2011-adaptive'"):
        run_order([wrong, load_problem(GUO[0])])
    self_link = load_problem(GUO_ENERGY, ["boundary.tf_from.problem=guo2011-scp-energy"])
    with pytest.raises(SpecError, match="not another case"):
        run_order([self_link])


def test_link_overrides_pass_the_figure_in():
    spec, controller = load_problem(GUO_ENERGY), load_problem(GUO[0])
    sol = _solution(controller, maneuver_time_01deg_s=196.8)
    assert link_values(spec, {controller.name: sol}) == {"boundary.tf_from": None, "boundary.tf_s": 196.8}
    assert link_values(load_problem(GUO[1]), {}) == {}
    with pytest.raises(SpecError, match="has no finite maneuver_time_01deg_s"):
        link_values(spec, {controller.name: _solution(controller, maneuver_time_01deg_s=None)})


# --- rendering --------------------------------------------------------------------------------------------


def _multicone_results(order=(0, 1, 2)):
    pt, tm, en = (load_problem(p) for p in MULTICONE)
    clearance = {"eigenaxis_min_angle_deg": {"body1": 0.093, "body2": 0.02, "body3": 21.191, "body4": 42.602},
                 "cones": tuple(ConeGeometry(name, (0.0, 0.0, 1.0), (1.0, 0.0, 0.0), half_angle, True)
                                for name, half_angle in (("body1", 20.0), ("body2", 15.0), ("body3", 12.0),
                                                         ("body4", 20.0)))}
    results = [_result(pt, _solution(pt, wall_time_s=9.0, maneuver_time_s=113.0, planning_time_s=0.2,
                                     min_cone_margin_deg=4.562, energy=0.6043, **clearance)),
               _result(tm, _solution(tm, wall_time_s=4.0, maneuver_time_s=43.152, min_cone_margin_deg=0.022,
                                     energy=0.5685, **clearance)),
               _result(en, _solution(en, wall_time_s=7.5, maneuver_time_s=56.098, min_cone_margin_deg=0.02,
                                     energy=0.08114, **clearance))]
    return [results[i] for i in order]


def test_multicone_table_is_rendered_from_the_results_alone(monkeypatch):
    def no_solve(*args, **kwargs):
        raise AssertionError("the report must not solve")

    monkeypatch.setattr("convexguid.api.solve", no_solve)
    lines = comparison_sections(_multicone_results())
    assert lines[1] == f"## {TABLES['multicone'].title}"
    assert _rows(lines) == [  # no compute times: they change from run to run (timings file)
        ["path transfer (paper's planner)", "113.000", "4.562", "0.6043", "yes"],
        ["SCP, minimum time", "43.152", "0.022", "0.5685", "yes"],
        ["SCP, minimum energy (t_f = 1.3 x minimum time)", "56.098", "0.020", "0.08114", "yes"]]
    text = "\n".join(lines)
    assert "is 61.8% shorter than the path-transfer plan (the paper reports" in text
    assert "planning time [s]" not in text and "x the path-transfer planning time" not in text
    assert ("body1 0.093 deg, body2 0.020 deg, body3 21.191 deg, body4 42.602 deg; cones 1 and 2 "
            "(20 and 15 deg half-angles) are broken.") in text


def test_compute_times_go_to_the_timings_lines_only():
    """The timed columns (a row's ``figures`` may name one, as path transfer's planning time) and the ratio
    sentence are rendered by comparison_timings, for the timings file."""
    lines = comparison_timings(_multicone_results())
    assert lines[1] == f"## {TABLES['multicone'].title}"
    assert _rows(lines) == [["path transfer (paper's planner)", "0.200"], ["SCP, minimum time", "4.000"],
                            ["SCP, minimum energy (t_f = 1.3 x minimum time)", "7.500"]]
    assert "The SCP's minimum-time plan takes 20.00x the path-transfer planning time." in "\n".join(lines)
    assert comparison_timings(_multicone_results((1,))) == []


def test_rows_follow_their_roles_and_sentences_need_them():
    lines = comparison_sections(_multicone_results((2, 0)))
    assert [r[0] for r in _rows(lines)] == ["path transfer (paper's planner)",
                                            "SCP, minimum energy (t_f = 1.3 x minimum time)"]
    assert "% shorter" not in "\n".join(lines)
    assert comparison_sections(_multicone_results((1,))) == []


def test_forbidden_attitude_table_uses_the_rows_figures():
    ctrl, tm = (load_problem(p) for p in GUO[:2])
    en = load_problem(GUO_ENERGY, ["boundary.tf_from=null", "boundary.tf_s=196.8"])
    forbidden = ConstraintCheck("forbidden_guo_forbidden_deg", 10.04, 10.0, "min")
    results = [
        _result(ctrl, _solution(ctrl, wall_time_s=0.77, maneuver_time_01deg_s=196.8, energy_N2m2s=11.52,
                                min_theta_b_deg=23.52)),
        _result(en, _solution(en, wall_time_s=6.5, checks=[forbidden], maneuver_time_s=196.8, energy=1.818)),
        _result(tm, _solution(tm, wall_time_s=6.0, checks=[forbidden], maneuver_time_s=85.32, energy=60.61))]
    lines = comparison_sections(results)
    assert _rows(lines) == [
        ["potential-function controller (Fig. 3 case, closed loop, disturbed)", "196.80", "11.52", "23.52", "yes"],
        ["SCP, minimum time", "85.32", "60.61", "10.04", "yes"],
        ["SCP, minimum energy at the controller's maneuver time", "196.80", "1.818", "10.04", "yes"]]
    assert [row[1] for row in _rows(comparison_timings(results))] == ["0.770", "6.000", "6.500"]
    assert ("uses 84.2% less energy (1.818 against 11.52 N^2 m^2 s); the minimum-time plan finishes in 85.3 s."
            in "\n".join(lines))


def test_report_code_names_no_problem():
    source = Path(comparisons.__file__).read_text()
    for path in MULTICONE + GUO:
        assert load_problem(path).name not in source


def test_a_tracked_plan_is_a_row_with_its_own_sentence():
    """The LPMPC-flown plan (role ``tracked``) comes last and is set against the controller in the text."""
    ctrl = load_problem(GUO[0])
    track = load_problem(PROBLEMS / "guo2011_lpmpc_track.yaml", ["nominal.tf_from=null", "nominal.tf_s=196.8"])
    results = [_result(track, _solution(track, wall_time_s=5.0, maneuver_time_s=196.8, lpmpc_energy_N2m2s=1.866,
                                        min_forbidden_angle_deg=10.69, nominal_problem="n", nominal_status="ok")),
               _result(ctrl, _solution(ctrl, wall_time_s=0.4, maneuver_time_01deg_s=196.8, energy_N2m2s=11.52,
                                       min_theta_b_deg=23.52))]
    lines = comparison_sections(results)
    rows = _rows(lines)
    assert [r[0] for r in rows][-1].startswith("SCP minimum-energy plan flown by LPMPC")
    assert rows[-1][1:4] == ["196.80", "1.866", "10.69"]
    text = "\n".join(lines)
    assert "uses 1.866 N^2 m^2 s, 83.8% less than the controller, and keeps theta_b at 10.69 deg" in text
    assert "would need a tracking loop" not in text
