"""Family ``flat_attitude``: energy-optimal attitude slew in flat outputs (Cai, Zhu, Zeng 2018).

Modules: ``spec`` (problem file), ``figures`` (summary figures), ``program`` (flat maps, Jacobians, the
SCP's program), ``solve`` (SCP, path-point refinement, dense verification, summary), ``plots``,
``reference`` (CasADi/IPOPT) and ``bench`` (SCP vs IPOPT against the polynomial degree).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.flat_attitude.figures import FlatAttitudeFigures
from convexguid.families.flat_attitude.spec import FlatAttitudeProblem, estimate_size

# The hooks below import their modules when first called, so that reading a problem file loads neither the
# SCP engine nor matplotlib nor CasADi (each import inside a function here is for that reason only).


def _solve(spec, log, planner):
    from convexguid.families.flat_attitude.solve import solve_flat_attitude

    return solve_flat_attitude(spec, log, planner)


def _plot(solution, out_dir, save):
    from convexguid.families.flat_attitude.plots import plot_flat_attitude

    return plot_flat_attitude(solution, out_dir, save)


def _planning_setup(spec):
    from convexguid.families.flat_attitude.solve import planning_setup

    return planning_setup(spec)


def _bench(spec, args, planner):
    from convexguid.families.flat_attitude.bench import bench_command

    return bench_command(spec, args, planner)


def _independent_optimum(spec, solution, starts):
    from convexguid.families.flat_attitude.crosscheck import independent_optimum

    return independent_optimum(spec, solution, starts)


FAMILY = Family(
    name="flat_attitude",
    spec_model=FlatAttitudeProblem,
    solve=_solve,
    plot=_plot,
    planning_setup=_planning_setup,
    verification_method="SciPy DOP853 re-propagation of the plan",
    figures=FlatAttitudeFigures,
    bench=_bench,
    independent_optimum=_independent_optimum,
    estimate_size=estimate_size,
)
