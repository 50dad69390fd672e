"""The rendezvous plan judged against the lossless-convexification optimum, written independently in cvxpy
(:func:`convexguid.families.rendezvous.lcvx_reference.solve_lcvx_cvxpy`): the robustness benchmark's reference
(:mod:`convexguid.robustness`). Being convex, one start is all it needs; when it is infeasible, no thrust history
on its grid reaches the target, a certificate the benchmark accepts for an ``infeasible`` plan."""

from __future__ import annotations

from convexguid.families.rendezvous.case import build_case
from convexguid.families.rendezvous.lcvx_reference import solve_lcvx_cvxpy
from convexguid.reference import IndependentOptimum


def independent_optimum(spec, solution, starts: int = 1) -> IndependentOptimum:
    """The global minimum burn time on the spec's ``grid_steps`` zero-order-hold steps (``starts`` is ignored)."""
    result = solve_lcvx_cvxpy(build_case(spec), spec.discretization.grid_steps)
    method = f"LCvx SOCP in cvxpy + Clarabel on {spec.discretization.grid_steps} steps"
    return IndependentOptimum(result.burn_time_s if result.optimal else None, method, int(result.optimal), 1,
                              infeasible=result.status == "infeasible")
