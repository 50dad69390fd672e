"""Family ``quaternion_attitude``: minimum-time or minimum-energy slews under keep-out/keep-in cones and forbidden
attitudes (Wang, Xu, Li; Guo, Li, Ma 2011), planned by SCP or by the path-transfer planner.

Modules: ``spec`` (problem file), ``figures`` (summary figures), ``program`` (Hermite-Simpson NLP: maps,
Jacobians, guesses), ``solve`` (SCP or path transfer, dense check, tightening, summary), ``plots`` (celestial
sphere and histories), ``reference`` (CasADi/IPOPT on the same NLP) and ``bench`` (SCP vs IPOPT against the
grid size).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.quaternion_attitude.figures import QuaternionAttitudeFigures
from convexguid.families.quaternion_attitude.spec import QuaternionAttitudeProblem, estimate_size

# The hooks below import their modules when first called, so that reading a problem file loads neither the
# SCP engine nor matplotlib nor CasADi (each import inside a function here is for that reason only).


def _solve(spec, log, planner):
    from convexguid.families.quaternion_attitude.solve import solve_quaternion_attitude

    return solve_quaternion_attitude(spec, log, planner)


def _plot(solution, out_dir, save):
    from convexguid.families.quaternion_attitude.plots import plot_quaternion_attitude

    return plot_quaternion_attitude(solution, out_dir, save)


def _planning_setup(spec):
    from convexguid.families.quaternion_attitude.solve import planning_setup

    return planning_setup(spec)


def _bench(spec, args, planner):
    from convexguid.families.quaternion_attitude.bench import bench_command

    return bench_command(spec, args, planner)


def _independent_optimum(spec, solution, starts):
    from convexguid.families.quaternion_attitude.crosscheck import independent_optimum

    return independent_optimum(spec, solution, starts)


FAMILY = Family(
    name="quaternion_attitude",
    spec_model=QuaternionAttitudeProblem,
    solve=_solve,
    plot=_plot,
    planning_setup=_planning_setup,
    verification_method="SciPy DOP853 re-propagation of the plan",
    figures=QuaternionAttitudeFigures,
    bench=_bench,
    independent_optimum=_independent_optimum,
    estimate_size=estimate_size,
)
