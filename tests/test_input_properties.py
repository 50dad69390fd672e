"""Property-based: whatever problem file or ``--set`` override a user gives, the command line ends with exit 0, 1 or
2 and never a traceback; exit 2 is one line on stderr and writes nothing (docs/cli.md, exit codes).

Inputs are generated from each family's problem file in ``problems/`` (:data:`BASE_FILES`): overrides of its keys
with values of every YAML kind (numbers in every notation, lists, mappings, null, text, broken YAML, unknown keys,
malformed ``key=value``), and files derived from it (keys changed, removed or added; the top level replaced;
undecodable bytes). Two tests:

* :func:`test_any_input_is_answered_cleanly` judges input handling only, so the family's ``solve`` is stubbed: an
  input that passes every check reaches the stub (:class:`Accepted`) instead of a solver.
* :func:`test_perturbed_problems_really_solve_cleanly` really solves: small grids, numbers of the file scaled by
  up to 25% and written in scientific notation. LPMPC is left out there: each of its runs plans a nominal first
  (seconds), which the stubbed test covers up to the solve.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import tempfile
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from convexguid.cli import main
from convexguid.families import FAMILIES

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

BASE_FILES = {
    "flat_attitude": "cai2018_flat_attitude.yaml",
    "rendezvous": "wang2003_rendezvous.yaml",
    "quaternion_attitude": "wang_multicone_energy.yaml",
    "potential_function": "guo2011_sweep.yaml",
    "lpmpc": "feng2018_lpmpc_montecarlo.yaml",
}
"""The file every family's inputs are made from (a family missing here fails :func:`test_every_family_has_a_base`)."""

SMALL = {
    "flat_attitude": ["discretization.nodes=16"],
    "rendezvous": ["method=lcvx", "discretization.grid_steps=60"],
    "quaternion_attitude": ["discretization.intervals=8", "keep_out=[]"],
    "potential_function": ["sweep=null", "simulation.dt_s=0.5"],
}
"""Overrides that make a real solve take well under a second (the really-solved test)."""

INPUT_EXAMPLES = 60
"""Examples per family of the input-handling test (stubbed solve: a few ms each)."""

SOLVE_EXAMPLES = 8
"""Examples per family of the real-solve test."""


class Accepted(Exception):  # noqa: N818 - a signal, not an error
    """Raised by the stubbed solve: the input passed every check."""


def _accepted(spec, log=None, planner=None):
    raise Accepted


def _command(family: str) -> str:
    return "simulate" if FAMILIES[family].simulated else "solve"


def _base_data(family: str) -> dict:
    return yaml.safe_load((PROBLEMS / BASE_FILES[family]).read_text())


def _paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key path of a YAML tree (mappings by key, lists by index), containers included."""
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for key, value in node.items():
            out += _paths(value, (*prefix, str(key)))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += _paths(value, (*prefix, str(i)))
    return out


def _numeric_paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    return [p for p in _paths(node, prefix) if _is_number(_get(node, p))]


def _get(node: Any, path: tuple) -> Any:
    for part in path:
        node = node[int(part)] if isinstance(node, list) else node[part]
    return node


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


# --- values as a user may type them ------------------------------------------------------------------------------

NUMBER_FORMATS = ("{!r}", "{:e}", "{:E}", "{:g}", "{:.2e}", "{:+.3E}")
YAML_WORDS = [
    "null", "~", "true", "no", "[]", "{}", "[1, 2]", "[1, 2, 3]", "[1, 0, 0, 0]", "[[1, 0, 0], [0, 1, 0], [0, 0, 1]]",
    "abc", "'1e3'", "1e3", "-3.5E-2", "1e-6", "1e400", "-1e400", ".nan", ".inf", "{a: 1}", "[", "]", "*x", "&a [*a]",
    ":", "'", '"', "- 1", "1_000", "0x1F", "0o17", "1:30", "2024-01-01", "!!float 1", "!!python/object:os.system ls",
    "1e3e3", "1.2.3", "e5", "5e", *sorted(p.name for p in PROBLEMS.glob("*.yaml")),
]
numbers = st.one_of(st.floats(), st.integers(-10**15, 10**15)).flatmap(
    lambda x: st.sampled_from(NUMBER_FORMATS).map(lambda f: f.format(x)))
yaml_texts = st.one_of(numbers, st.sampled_from(YAML_WORDS), st.text(max_size=30),
                       st.lists(st.one_of(st.floats(-1e3, 1e3), st.integers(-5, 5)), max_size=5).map(str))
python_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(), st.text(max_size=12)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=3)),
    max_leaves=8)


def _perturbed(draw, base: dict, path: tuple) -> str:
    """``path=value`` with the file's number at ``path`` scaled by 0.8 to 1.25, in scientific notation."""
    value = _get(base, path)
    scaled = value * draw(st.floats(0.8, 1.25))
    if isinstance(value, int):
        scaled = max(1, round(scaled))  # counts stay whole; written as 1.2e+01 they still read as integers
    return f"{'.'.join(path)}={draw(st.sampled_from(NUMBER_FORMATS[1:])).format(scaled)}"


@st.composite
def overrides(draw, family: str) -> list[str]:
    """Zero to three ``--set`` strings: a number of the file scaled a little (mostly valid), any YAML value at an
    existing key path, an unknown key path, or malformed text."""
    base = _base_data(family)
    paths, numeric = _paths(base), _numeric_paths(base)
    out = []
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.sampled_from(["scaled", "scaled", "value", "value", "unknown key", "malformed"]))
        if kind == "scaled":
            out.append(_perturbed(draw, base, draw(st.sampled_from(numeric))))
            continue
        if kind == "malformed":
            out.append(draw(st.text(max_size=20)))
            continue
        path = ".".join(draw(st.sampled_from(paths)))
        if kind == "unknown key":
            path += "." + draw(st.sampled_from(["nope", "0", "x.y"]))
        out.append(f"{path}={draw(yaml_texts)}")
    return out


@st.composite
def problem_files(draw, family: str) -> bytes:
    """The base file with one to three keys changed, removed or added, or its top level replaced, or raw bytes."""
    kind = draw(st.sampled_from(["mutated"] * 6 + ["top level", "bytes"]))
    if kind == "bytes":
        return draw(st.binary(max_size=200))
    if kind == "top level":
        return yaml.safe_dump(draw(python_values)).encode()
    data = _base_data(family)
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        path = draw(st.sampled_from(paths))
        parent = _get(data, path[:-1])
        key = int(path[-1]) if isinstance(parent, list) else path[-1]
        action = draw(st.sampled_from(["set", "set", "delete", "add"]))
        if action == "delete":
            del parent[key]
        elif action == "add" and isinstance(parent, dict):
            parent[draw(st.text(min_size=1, max_size=8))] = draw(python_values)
        else:
            parent[key] = draw(python_values)
    return yaml.safe_dump(data, allow_unicode=True).encode()


# --- the property ------------------------------------------------------------------------------------------------

def _run(argv: list[str]) -> tuple[int | type[Accepted], str, str]:
    """``main(argv)`` in process: (exit code or :class:`Accepted`, stdout, stderr). Any other exception fails."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code: int | type[Accepted] = main(argv)
        except Accepted:
            code = Accepted
    return code, out.getvalue(), err.getvalue()


def _check_answer(family: str, problem: Path, sets: list[str], folder: Path) -> int | type[Accepted]:
    out_dir, summary = folder / "out", folder / "summary.json"
    argv = [_command(family), str(problem), "--quiet", "--out", str(out_dir), "--summary-json", str(summary)]
    code, stdout, stderr = _run([*argv, *(f"--set={s}" for s in sets)])  # "=": a value may start with "-"
    assert "Traceback" not in stdout + stderr
    assert code in (0, 1, 2, Accepted), code
    event(f"exit {code}" if code is not Accepted else "accepted (reached the stubbed solve)")
    if code == 2:
        assert stderr.startswith("convexguid: ") and stderr.count("\n") == 1 and stderr.endswith("\n"), stderr
        assert not out_dir.exists() and not summary.exists(), "exit 2 wrote outputs"
    if code in (0, 1):
        assert summary.exists(), "a finished run must leave its summary"
    if code == 1:
        assert stderr.splitlines()[-1].startswith("convexguid: "), stderr
    return code


@contextlib.contextmanager
def _stubbed_solves():
    with pytest.MonkeyPatch.context() as patch:
        for name, family in list(FAMILIES.items()):
            patch.setitem(FAMILIES, name, dataclasses.replace(family, solve=_accepted))
        yield


def test_every_family_has_a_base():
    assert set(BASE_FILES) == set(FAMILIES)
    assert set(SMALL) | {"lpmpc"} == set(FAMILIES)


@pytest.mark.parametrize("family", sorted(BASE_FILES))
@settings(max_examples=INPUT_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_any_input_is_answered_cleanly(family, data):
    source = data.draw(st.sampled_from(["file", "overrides", "both"]))
    sets = data.draw(overrides(family)) if source != "file" else []
    with tempfile.TemporaryDirectory() as tmp, _stubbed_solves():
        folder = Path(tmp)
        problem = PROBLEMS / BASE_FILES[family]
        if source != "overrides":
            problem = folder / BASE_FILES[family]  # same name and folder layout as the original: relative paths
            problem.write_bytes(data.draw(problem_files(family)))
            if family == "lpmpc":  # its nominal file is found beside it
                (folder / "feng2018_nominal.yaml").write_bytes((PROBLEMS / "feng2018_nominal.yaml").read_bytes())
        _check_answer(family, problem, sets, folder)


@pytest.mark.parametrize("family", sorted(SMALL))
@settings(max_examples=SOLVE_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_perturbed_problems_really_solve_cleanly(family, data):
    base = _base_data(family)
    small = SMALL[family]
    fixed = {s.partition("=")[0] for s in small}
    candidates = [p for p in _numeric_paths(base) if p[0] not in ("reference", "notes")
                  and not any(".".join(p).startswith(k) for k in fixed)]
    sets = list(small)
    for path in data.draw(st.lists(st.sampled_from(candidates), max_size=2, unique=True)):
        sets.append(_perturbed(data.draw, base, path))
    with tempfile.TemporaryDirectory() as tmp:
        assert _check_answer(family, PROBLEMS / BASE_FILES[family], sets, Path(tmp)) in (0, 1, 2)
