"""The ``lcvx`` SOCP as stated on ``convexguid.ocp`` against its plain cvxpy statement
(``rendezvous/lcvx_reference.py``).

Same problem, two independent writings: a closed-form flow transcribed by ``convexguid.ocp`` and solved by the SCP
engine, or the exact zero-order-hold pair from a matrix exponential in cvxpy. On the paper case (Wang & Tang 2003)
they must give the same burn time and the same burn arcs; with too little thrust both must say infeasible.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from convexguid.dynamics.clohessy_wiltshire import cw_zoh
from convexguid.families.rendezvous.case import build_case
from convexguid.families.rendezvous.lcvx import burn_structure, solve_lcvx
from convexguid.families.rendezvous.lcvx_reference import solve_lcvx_cvxpy
from convexguid.problem_files import load_problem

PAPER = Path(__file__).resolve().parents[1] / "problems" / "wang2003_rendezvous.yaml"


def _solve_both(overrides: list[str]):
    spec = load_problem(PAPER, overrides)
    case, steps = build_case(spec), spec.discretization.grid_steps
    return case, steps, solve_lcvx(case, steps, spec.solver.backend), solve_lcvx_cvxpy(case, steps)


@pytest.fixture(scope="module")
def paper():
    return _solve_both([])


def test_same_burn_time(paper):
    _, _, plan, ref = paper
    print(f"ocp statement {plan.objective:.12g} s, cvxpy {ref.burn_time_s:.12g} s")
    assert plan.status == "converged"
    assert ref.optimal, ref.status
    assert ref.burn_time_s == pytest.approx(plan.objective, rel=1e-6)


def test_same_burn_arcs_within_one_step(paper):
    case, steps, plan, ref = paper
    grid, dt = np.linspace(case.t0, case.tf, steps + 1), case.duration / steps
    arcs = burn_structure(grid, ref.throttle)
    assert len(arcs) == len(plan.burns) == 2  # burn - coast - burn
    for mine, theirs in zip(arcs, plan.burns, strict=True):
        assert abs(mine.start_s - theirs.start_s) <= dt
        assert abs(mine.end_s - theirs.end_s) <= dt


def test_cvxpy_solution_meets_its_constraints(paper):
    """The controls reach the target through the same ZOH map, with |u| <= Gamma <= 1."""
    case, steps, _, ref = paper
    phi, gam = cw_zoh(case.mean_motion, case.accel, case.duration / steps, case.dim)
    x = case.x0.copy()
    for u in ref.controls:
        x = phi @ x + gam @ u
    assert np.linalg.norm(x[: case.dim] - case.xf[: case.dim]) < 1e-3  # m
    assert np.linalg.norm(x[case.dim:] - case.xf[case.dim:]) < 1e-6  # m/s
    assert np.all(np.linalg.norm(ref.controls, axis=1) <= ref.throttle + 1e-7)
    assert np.all(ref.throttle <= 1 + 1e-7)
    assert ref.solve_time_s > 0 and ref.compile_time_s > 0


def test_too_little_thrust_is_infeasible_for_both():
    _, _, plan, ref = _solve_both(["spacecraft.accel_mps2=0.1"])
    assert plan.status == "infeasible", plan.message
    assert ref.status == "infeasible"
    assert np.isnan(ref.burn_time_s)
