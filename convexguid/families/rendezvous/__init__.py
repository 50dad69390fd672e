"""Family ``rendezvous``: finite-thrust minimum-burn-time rendezvous in Clohessy-Wiltshire dynamics (Wang & Tang 2003).

Modules: ``spec`` (problem file), ``figures`` (summary figures), ``case`` (problem data, thrust plans, propagation,
verification), ``arc_layout`` (the arcs' design vector, their starts and readings), ``arc_phases`` (the paper's
burn/coast NLP for the SCP, a maneuver in phases on ``convexguid.ocp``), ``lcvx`` (lossless convexification, one
SOCP), ``solve`` (either method, verification, certificate, summary), ``plots``, ``reference`` (CasADi/IPOPT on the
arcs NLP) and ``bench`` (lcvx vs scp_arcs vs IPOPT).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.rendezvous.figures import RendezvousFigures
from convexguid.families.rendezvous.spec import RendezvousProblem, estimate_size

# The hooks below import their modules when first called, so that reading a problem file loads neither the
# SCP engine nor matplotlib nor CasADi (each import inside a function here is for that reason only).


def _solve(spec, log, planner):
    from convexguid.families.rendezvous.solve import solve_rendezvous

    return solve_rendezvous(spec, log, planner)


def _plot(solution, out_dir, save):
    from convexguid.families.rendezvous.plots import plot_rendezvous

    return plot_rendezvous(solution, out_dir, save)


def _planning_setup(spec):
    from convexguid.families.rendezvous.solve import planning_setup

    return planning_setup(spec)


def _bench(spec, args, planner):
    from convexguid.families.rendezvous.bench import bench_command

    return bench_command(spec, args, planner)


def _independent_optimum(spec, solution, starts):
    from convexguid.families.rendezvous.crosscheck import independent_optimum

    return independent_optimum(spec, solution, starts)


FAMILY = Family(
    name="rendezvous",
    spec_model=RendezvousProblem,
    solve=_solve,
    plot=_plot,
    planning_setup=_planning_setup,
    verification_method="SciPy DOP853 re-propagation of the plan",
    figures=RendezvousFigures,
    key_figures=(
        ("burn_time_s", "total burn time, s"),
        ("burn_arcs_s", "burns [start, end], s"),
        ("lcvx_burn_time_s", "lcvx global optimum on the fixed grid, s"),
        ("lcvx_burn_arcs_s", "lcvx burns [start, end], s"),
        ("lcvx_gap_rel", "(scp_arcs - lcvx) / lcvx"),
        ("planned_direction_norm_min", "smallest norm of the interpolated direction on burns (1 at nodes)"),
    ),
    bench=_bench,
    independent_optimum=_independent_optimum,
    estimate_size=estimate_size,
)
