"""The family registry: one entry per family, consistent with its spec model, and the places that dispatch on it."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
import typing
from pathlib import Path

import pytest

import convexguid
from convexguid.errors import SpecError
from convexguid.families import FAMILIES, family_names, get_family
from convexguid.scp.problem import ProgramSize
from convexguid.solution import Figures, Solution, optional
from convexguid.spec.common import ProblemBase

PROBLEMS = "problems"


@pytest.mark.parametrize("name", list(FAMILIES))
def test_family_matches_its_spec_model(name):
    family = FAMILIES[name]
    assert family.name == name
    assert issubclass(family.spec_model, ProblemBase)
    assert typing.get_args(family.spec_model.model_fields["family"].annotation) == (name,)
    assert callable(family.solve) and callable(family.plot) and family.verification_method


@pytest.mark.parametrize("name", list(FAMILIES))
def test_key_figures_are_fields_of_the_family_figures(name):
    family = FAMILIES[name]
    assert issubclass(family.figures, Figures) and dataclasses.is_dataclass(family.figures)
    fields = {f.name for f in dataclasses.fields(family.figures)}
    assert family.figures.names() == tuple(f.name for f in dataclasses.fields(family.figures))
    missing = [key for key, _ in family.key_figures if key not in fields]
    assert not missing, f"{name}: key figures that are not fields of {family.figures.__name__}: {missing}"


@dataclasses.dataclass(frozen=True)
class _Inner:
    a: float
    b: tuple[float, ...]


@dataclasses.dataclass(frozen=True)
class _Figures(Figures):
    x: float
    n: int
    nested: tuple[tuple[float, float], ...]
    inner: _Inner
    by_name: dict[str, float]
    maybe: float | None = None
    status: str | None = optional()
    with_status: float | None = optional(along="status")
    later: float | None = optional()


def test_figures_to_dict_keeps_order_and_makes_json_ready_data():
    figures = _Figures(x=math.inf, n=3, nested=((1.0, math.nan), (2.0, 3.0)), inner=_Inner(0.5, (1.0,)),
                       by_name={"a": 1.5})
    assert list(figures.to_dict().items()) == [
        ("x", None), ("n", 3), ("nested", [[1.0, None], [2.0, 3.0]]), ("inner", {"a": 0.5, "b": [1.0]}),
        ("by_name", {"a": 1.5}), ("maybe", None)]
    full = dataclasses.replace(figures, status="infeasible", later=2.0).to_dict()
    assert list(full)[-3:] == ["status", "with_status", "later"] and full["with_status"] is None


def test_solution_figure_by_summary_key():
    figures = _Figures(x=1.0, n=3, nested=(), inner=_Inner(0.5, ()), by_name={})
    sol = Solution(problem="p", family="f", method="m", status="converged", objective=1.0, iterations=1,
                   size=ProgramSize(1, 0, 0), wall_time_s=0.0, solver="s", figures=figures)
    assert sol.figure("n") == 3 and sol.figure("inner") == {"a": 0.5, "b": []}
    assert list(sol.summary())[-6:] == list(figures.to_dict()) == list(sol.figure_names())
    with pytest.raises(KeyError, match=r"'energy' is not one of .*available: x, n, nested, inner, by_name, maybe"):
        sol.figure("energy")
    with pytest.raises(KeyError, match=r"'later' is not set in"):
        sol.figure("later")


def test_names_in_registry_order():
    assert family_names() == ("flat_attitude", "rendezvous", "quaternion_attitude", "potential_function", "lpmpc")
    assert [n for n, f in FAMILIES.items() if f.simulated] == ["potential_function", "lpmpc"]


def test_unknown_family_lists_the_known_ones():
    with pytest.raises(SpecError, match="known families: flat_attitude, rendezvous, quaternion_attitude, "
                                        "potential_function, lpmpc"):
        get_family("orbit_raising")


def test_simulating_a_planned_family_names_the_simulated_ones():
    with pytest.raises(SpecError, match=r"simulate handles: potential_function, lpmpc\)"):
        convexguid.simulate(f"{PROBLEMS}/cai2018_flat_attitude.yaml")


def test_bench_of_a_family_without_one_is_a_one_line_error():
    res = subprocess.run([sys.executable, "-m", "convexguid.cli", "bench", f"{PROBLEMS}/guo2011_adaptive.yaml"],
                         capture_output=True, text=True)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "'potential_function' has no benchmark" in lines[0] and "rendezvous" in lines[0]


def test_import_is_light():
    """``import convexguid`` and reaching ``convexguid.solve`` import neither matplotlib nor any family's solver."""
    code = ("import sys, convexguid; convexguid.solve; "
            "print(sorted(m for m in sys.modules if m.startswith('matplotlib') or m.endswith(('.solve', '.plots'))))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip() == "[]"


def test_registry_with_figures_types_is_light():
    """The families' figures modules load with the registry, without the SCP engine, matplotlib or CasADi."""
    code = ("import sys, convexguid.families; print(sorted(m for m in sys.modules if m.startswith(("
            "'convexguid.scp', 'matplotlib', 'casadi'))))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip() == "[]"


PLANNED_CASES = {
    "flat_attitude": ("cai2018_flat_attitude.yaml", []),
    "rendezvous": ("wang2003_rendezvous.yaml", []),
    "quaternion_attitude": ("guo2011_scp_time.yaml", ["discretization.intervals=12"]),
}
"""One small committed case per planned family, for the contract test below."""


def test_every_planned_family_has_a_contract_case():
    planned = {name for name, family in FAMILIES.items() if not family.simulated}
    assert planned == set(PLANNED_CASES)
    assert all(FAMILIES[name].planning_setup is not None for name in planned)


@pytest.mark.parametrize("name", sorted(PLANNED_CASES))
def test_planning_setup_runs_through_the_engine_loop_to_a_verified_plan(name):
    """The Family contract alone (program, settings, checker) gives a plan the family's own check passes."""
    from convexguid.problem_files import load_problem

    file, overrides = PLANNED_CASES[name]
    spec = load_problem(Path(__file__).resolve().parents[1] / "problems" / file, overrides)
    setup = get_family(name).planning_setup(spec)
    outcome = setup.solve()
    assert outcome.status == "converged", outcome.message
    assert outcome.check.verification.passed
    assert setup.checker.check(outcome.program, outcome.x).verification.passed  # the check is repeatable
    assert outcome.rounds[-1].passed and outcome.rounds[0].repair == "first solve"
