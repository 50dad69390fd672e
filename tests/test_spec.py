"""Tests of convexguid.spec: the real problem file, one-line errors for bad input, --set overrides."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from convexguid.errors import SpecError
from convexguid.families import get_family
from convexguid.problem_files import load_problem, parse_problem
from convexguid.spec import ProblemSpec, apply_overrides

PROBLEM = Path(__file__).resolve().parents[1] / "problems" / "cai2018_flat_attitude.yaml"
_DELETE = object()


def raw() -> dict[str, Any]:
    """The real problem file as a plain dict."""
    return yaml.safe_load(PROBLEM.read_text(encoding="utf-8"))


def bad_file(tmp_path: Path, path: str, value: Any = _DELETE) -> Path:
    """Write the real problem with ``path`` (dotted, list indices as numbers) set to ``value`` or deleted."""
    data = raw()
    *parents, last = path.split(".")
    node: Any = data
    for part in parents:
        node = node[int(part)] if isinstance(node, list) else node[part]
    key: Any = int(last) if isinstance(node, list) else last
    if value is _DELETE:
        del node[key]
    else:
        node[key] = value
    out = tmp_path / "bad.yaml"
    out.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return out


def error_of(path: Path, overrides: tuple[str, ...] = ()) -> str:
    """The one-line SpecError message of loading ``path``."""
    with pytest.raises(SpecError) as info:
        load_problem(path, overrides)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message


def test_real_problem_in_si_units() -> None:
    spec = load_problem(PROBLEM)
    assert isinstance(spec, ProblemSpec) and isinstance(spec, get_family("flat_attitude").spec_model)
    assert spec.source == str(PROBLEM)
    assert (spec.name, spec.family, spec.method, spec.objective) == (
        "cai2018-flat-attitude", "flat_attitude", "scp", "energy")
    inertia = spec.spacecraft.inertia_matrix
    np.testing.assert_array_equal(inertia, np.diag([66.36, 61.80, 50.16]))
    assert not inertia.flags.writeable
    assert spec.spacecraft.torque_max_Nm == 1.0
    assert spec.boundary.duration_s == 100.0
    third, quarter = math.pi / 3, math.pi / 4
    np.testing.assert_allclose(spec.boundary.initial.rpy_rad, [third, quarter, -third], rtol=1e-15)
    np.testing.assert_allclose(spec.boundary.final.rpy_rad, [-third, -quarter, quarter], rtol=1e-15)
    np.testing.assert_array_equal(spec.boundary.final.rate_radps, np.zeros(3))
    (sun,) = spec.keep_out
    assert sun.name == "sun" and sun.half_angle_rad == pytest.approx(math.pi / 4, rel=1e-15)
    np.testing.assert_allclose(sun.body_axis_unit, [0, -math.sqrt(0.5), math.sqrt(0.5)], rtol=1e-15)
    np.testing.assert_array_equal(sun.inertial_dir_unit, [0.0, -1.0, 0.0])
    assert not sun.body_axis_unit.flags.writeable
    disc = spec.discretization
    assert (disc.method, disc.nodes, disc.map_epsilon, disc.check_points_per_interval) == (
        "mapped_chebyshev", 32, 1e-6, 2)
    assert (spec.solver.backend, spec.solver.max_iterations, spec.solver.tolerance) == ("auto", 50, 1e-6)
    assert spec.verification.grid_points == 2001
    ref = spec.reference
    assert ref is not None and ref.table == "Table 1" and "10.6052/1672-6553-2018-005" in ref.citation
    assert ref.values == {"objective": 0.2607, "num_variables": 99, "map_alpha": 0.9135}
    assert ref.tolerance_for("objective") == 5e-4 and ref.tolerance_for("num_variables") == 0
    assert ref.tolerance_for("other") == ref.rel_tol == 1e-3
    assert ref.max_values == {"iterations": 20}


def test_models_are_frozen() -> None:
    spec = load_problem(PROBLEM)
    with pytest.raises(ValueError):
        spec.boundary.tf_s = 5.0  # type: ignore[misc]


def test_parse_problem_from_dict_and_full_inertia_matrix() -> None:
    data = raw()
    data["spacecraft"]["inertia_kgm2"] = [[10, 1, 0], [1, 12, 0], [0, 0, 15]]
    spec = parse_problem(data)
    assert spec.source == "<dict>"
    np.testing.assert_array_equal(spec.spacecraft.inertia_matrix, [[10, 1, 0], [1, 12, 0], [0, 0, 15]])


@pytest.mark.parametrize(("path", "value", "expected"), [
    ("spacecraft.inertia_kgm2", _DELETE, "spacecraft.inertia_kgm2: missing required key"),
    ("colour", "red", "colour: unknown key (got 'red'); valid keys: name, family, method"),
    ("boundary.initial.colour", "red",
     "boundary.initial.colour: unknown key (got 'red'); valid keys: roll_pitch_yaw_deg, rate_degps"),
    ("keep_out.0.colour", "red", "keep_out.0.colour: unknown key (got 'red'); valid keys: name, body_axis"),
    ("boundary.tf_s", "100", "boundary.tf_s: wrong type (got '100')"),
    ("boundary.initial.roll_pitch_yaw_deg", [60, 45], "boundary.initial.roll_pitch_yaw_deg: has 2 entries"),
    ("keep_out.0.body_axis", [0, 0, 0],
     "keep_out.0.body_axis: zero-length direction vector (got [0, 0, 0]); give a nonzero 3-vector"),
    ("discretization.nodes", 3, "discretization.nodes: out of range (got 3)"),
    ("discretization.map_epsilon", 0, "discretization.map_epsilon: out of range (got 0)"),
    ("discretization.map_epsilon", 1.5, "discretization.map_epsilon: out of range (got 1.5)"),
    ("boundary.initial.roll_pitch_yaw_deg", [60, 90, -60], "initial.roll_pitch_yaw_deg.1: the 3-2-1 flat"),
    ("boundary.final.roll_pitch_yaw_deg", [0, -90, 0], "boundary.final.roll_pitch_yaw_deg.1: the 3-2-1"),
    ("boundary.tf_s", -5.0, "boundary.tf_s: must be greater than boundary.t0_s = 0.0 (got -5.0)"),
    ("boundary.tf_s", 0, "boundary.tf_s: must be greater than boundary.t0_s = 0.0 (got 0.0)"),
    ("spacecraft.inertia_kgm2", [[10, 1, 0], [0, 12, 0], [0, 0, 15]],
     "spacecraft.inertia_kgm2: inertia matrix is not symmetric (got [[10, 1, 0], [0, 12, 0], [0, 0, 15]])"),
    ("spacecraft.inertia_kgm2", [-66.36, 61.8, 50.16], "spacecraft.inertia_kgm2.0: principal moment"),
    ("spacecraft.inertia_kgm2", [[1, 2, 0], [2, 1, 0], [0, 0, 1]],
     "spacecraft.inertia_kgm2: inertia matrix is not positive definite"),
])
def test_bad_value(tmp_path: Path, path: str, value: Any, expected: str) -> None:
    message = error_of(bad_file(tmp_path, path, value))
    assert expected in message
    assert "Input should" not in message and "Value error" not in message


def test_messages_carry_value_and_hint(tmp_path: Path) -> None:
    pitch = error_of(bad_file(tmp_path, "boundary.initial.roll_pitch_yaw_deg", [60, -90, -60]))
    assert "singular at pitch = +-90 deg (got -90.0)" in pitch and "89.9" in pitch
    negative = error_of(bad_file(tmp_path, "spacecraft.inertia_kgm2", [-66.36, 61.8, 50.16]))
    assert "(got -66.36)" in negative
    torque = error_of(bad_file(tmp_path, "spacecraft.torque_max_Nm", 0))
    assert "spacecraft.torque_max_Nm: out of range (got 0); input should be greater than 0" in torque


def test_unknown_backend_lists_installed(tmp_path: Path) -> None:
    message = error_of(bad_file(tmp_path, "solver.backend", "gurobi"))
    assert "solver.backend: unknown backend (got 'gurobi')" in message
    assert "clarabel" in message and "osqp" in message


def test_family_errors(tmp_path: Path) -> None:
    message = error_of(bad_file(tmp_path, "family", "orbit_raising"))
    assert "family: unknown family (got 'orbit_raising'); known families: flat_attitude" in message
    assert "family: missing required key" in error_of(bad_file(tmp_path, "family"))


def test_duplicate_cone_names(tmp_path: Path) -> None:
    data = raw()
    data["keep_out"].append(copy.deepcopy(data["keep_out"][0]))
    expected = r"^<dict>: keep_out\.1\.name: duplicate name \(got 'sun'\)"
    with pytest.raises(SpecError, match=expected):
        parse_problem(data)


def test_only_first_error_is_reported(tmp_path: Path) -> None:
    message = error_of(bad_file(tmp_path, "boundary", {"tf_s": "x"}))
    assert message.endswith("(and 2 more problems)")


def test_yaml_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("name: x\nboundary: {tf_s: 100\nfamily: flat_attitude\n", encoding="utf-8")
    message = error_of(path)
    assert "YAML syntax error" in message and "line " in message


def test_duplicate_yaml_key(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("name: x\nname: y\n", encoding="utf-8")
    assert "line 2, column 1: YAML syntax error: duplicate key 'name'" in error_of(path)


def test_non_mapping_top_level(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("- 1\n- 2\n", encoding="utf-8")
    assert "top level is not a mapping (got [1, 2])" in error_of(path)
    with pytest.raises(SpecError, match="^<dict>: top level is not a mapping"):
        parse_problem([1, 2])  # type: ignore[arg-type]


def test_missing_file(tmp_path: Path) -> None:
    assert "file not found" in error_of(tmp_path / "nope.yaml")


def test_numeric_override() -> None:
    spec = load_problem(PROBLEM, ["boundary.tf_s=25", "solver.verbose=false"])
    assert spec.boundary.tf_s == 25.0 and spec.solver.verbose is False


def test_list_index_override() -> None:
    overrides = ["keep_out.0.half_angle_deg=30", "boundary.initial.roll_pitch_yaw_deg=[1, 2, 3]"]
    spec = load_problem(PROBLEM, overrides)
    assert spec.keep_out[0].half_angle_deg == 30.0
    assert spec.boundary.initial.roll_pitch_yaw_deg == (1.0, 2.0, 3.0)


def test_override_adds_key_that_validation_judges() -> None:
    message = error_of(PROBLEM, ("boundary.colour=red",))
    assert "boundary.colour: unknown key (got 'red')" in message


@pytest.mark.parametrize(("override", "expected"), [
    ("boundary.tff.x=3", "boundary.tff: key does not exist (got override 'boundary.tff.x=3')"),
    ("keep_out.3.name=moon", "keep_out.3: list index does not exist (got override 'keep_out.3.name=moon')"),
    ("name.x=1", "name.x: key does not exist"),
])
def test_override_unknown_path(override: str, expected: str) -> None:
    assert expected in error_of(PROBLEM, (override,))


@pytest.mark.parametrize("override", ["boundary.tf_s", "=3", "boundary..tf_s=3"])
def test_malformed_override(override: str) -> None:
    assert f"malformed override (got {override!r})" in error_of(PROBLEM, (override,))


def test_override_does_not_mutate_input() -> None:
    data = raw()
    before = copy.deepcopy(data)
    out = apply_overrides(data, ["boundary.tf_s=25", "keep_out.0.half_angle_deg=30"], "x.yaml")
    assert data == before
    assert out["boundary"]["tf_s"] == 25 and out["keep_out"][0]["half_angle_deg"] == 30


def test_bad_matrix_entry_names_row_and_column(tmp_path: Path) -> None:
    message = error_of(bad_file(tmp_path, "spacecraft.inertia_kgm2", [[1, 0, 0], [0, "a", 0], [0, 0, 1]]))
    assert "spacecraft.inertia_kgm2.1.1: not a number (got 'a')" in message


def test_overrides_on_a_spec_built_in_python_apply_to_its_own_data(tmp_path):
    """A spec made from a dict (no file behind it) takes overrides from the data it was made from; a spec read
    from a file does not read the file again (it may have changed or moved since)."""
    import convexguid
    from convexguid.problem_files import parse_problem
    from convexguid.spec.loader import with_overrides

    data = yaml.safe_load(Path("problems/cai2018_flat_attitude.yaml").read_text())
    built = parse_problem(data)
    changed = with_overrides(built, ["discretization.nodes=12"])
    assert (changed.source, changed.discretization.nodes, built.discretization.nodes) == ("<dict>", 12, 32)
    sol = convexguid.solve(built, ["discretization.nodes=16"])
    assert sol.size.num_variables == 3 * 17  # solved at the overridden size

    moved = tmp_path / "problem.yaml"
    moved.write_text(Path("problems/cai2018_flat_attitude.yaml").read_text())
    loaded = convexguid.load_problem(moved)
    moved.unlink()
    assert with_overrides(loaded, ["discretization.nodes=10"]).discretization.nodes == 10
    with pytest.raises(SpecError, match="discretization.nodez"):
        with_overrides(built, ["discretization.nodez=10"])
