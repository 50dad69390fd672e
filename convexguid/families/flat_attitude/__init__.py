"""Family ``flat_attitude``: energy-optimal attitude slew in flat outputs (Cai, Zhu, Zeng 2018).

Modules: ``spec`` (problem file), ``program`` (flat maps, Jacobians, the SCP's program), ``solve``
(SCP, path-point refinement, dense verification, summary), ``plots``, ``reference`` (CasADi/IPOPT)
and ``bench`` (SCP vs IPOPT against the polynomial degree).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.flat_attitude.spec import FlatAttitudeProblem


def _solve(spec, log=None):
    from convexguid.families.flat_attitude.solve import solve_flat_attitude

    return solve_flat_attitude(spec, log=log)


def _plot(solution, out_dir):
    from convexguid.families.flat_attitude.plots import plot_flat_attitude
    from convexguid.report.plots import save_figure

    return plot_flat_attitude(solution, out_dir, save_figure)


def _bench(problem_path, args):
    from convexguid.families.flat_attitude.bench import bench_command

    return bench_command(problem_path, args)


FAMILY = Family(
    name="flat_attitude",
    spec_model=FlatAttitudeProblem,
    solve=_solve,
    plot=_plot,
    verification_method="SciPy DOP853 re-propagation of the plan",
    bench=_bench,
)
