"""Family ``rendezvous``: finite-thrust minimum-burn-time rendezvous in Clohessy-Wiltshire dynamics (Wang & Tang 2003).

Modules: ``spec`` (problem file), ``case`` (problem data, thrust plans, propagation, verification),
``arcs`` (the paper's burn/coast NLP for the SCP), ``lcvx`` (lossless convexification, one SOCP),
``solve`` (either method, verification, certificate, summary), ``plots``, ``reference``
(CasADi/IPOPT on the arcs NLP) and ``bench`` (lcvx vs scp_arcs vs IPOPT).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.rendezvous.spec import RendezvousProblem


def _solve(spec, log=None):
    from convexguid.families.rendezvous.solve import solve_rendezvous

    return solve_rendezvous(spec, log=log)


def _plot(solution, out_dir):
    from convexguid.families.rendezvous.plots import plot_rendezvous
    from convexguid.report.plots import save_figure

    return plot_rendezvous(solution, out_dir, save_figure)


def _bench(problem_path, args):
    from convexguid.families.rendezvous.bench import bench_command

    return bench_command(problem_path, args)


FAMILY = Family(
    name="rendezvous",
    spec_model=RendezvousProblem,
    solve=_solve,
    plot=_plot,
    verification_method="SciPy DOP853 re-propagation of the plan",
    key_figures=(
        ("burn_time_s", "total burn time, s"),
        ("burn_arcs_s", "burns [start, end], s"),
        ("lcvx_burn_time_s", "lcvx global optimum on the fixed grid, s"),
        ("lcvx_burn_arcs_s", "lcvx burns [start, end], s"),
        ("lcvx_gap_rel", "(scp_arcs - lcvx) / lcvx"),
        ("planned_direction_norm_min", "smallest norm of the interpolated direction on burns (1 at nodes)"),
    ),
    bench=_bench,
)
