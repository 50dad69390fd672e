"""The family registry: one entry per family, consistent with its spec model, and the places that dispatch on it."""

from __future__ import annotations

import subprocess
import sys
import typing

import pytest

import convexguid
from convexguid.errors import SpecError
from convexguid.families import FAMILIES, family_names, get_family
from convexguid.spec.common import ProblemBase

PROBLEMS = "problems"


@pytest.mark.parametrize("name", list(FAMILIES))
def test_family_matches_its_spec_model(name):
    family = FAMILIES[name]
    assert family.name == name
    assert issubclass(family.spec_model, ProblemBase)
    assert typing.get_args(family.spec_model.model_fields["family"].annotation) == (name,)
    assert callable(family.solve) and callable(family.plot) and family.verification_method


def test_names_in_registry_order():
    assert family_names() == ("flat_attitude", "rendezvous", "quaternion_attitude", "potential_function")
    assert [n for n, f in FAMILIES.items() if f.simulated] == ["potential_function"]


def test_unknown_family_lists_the_known_ones():
    with pytest.raises(SpecError, match="known families: flat_attitude, rendezvous, quaternion_attitude, "
                                        "potential_function"):
        get_family("orbit_raising")


def test_simulating_a_planned_family_names_the_simulated_ones():
    with pytest.raises(SpecError, match=r"simulate handles: potential_function\)"):
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
