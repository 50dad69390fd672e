"""Family ``quaternion_attitude``: minimum-time or minimum-energy slews under keep-out/keep-in cones and forbidden
attitudes (Wang, Xu, Li; Guo, Li, Ma 2011), planned by SCP or by the path-transfer planner.

Modules: ``spec`` (problem file), ``program`` (Hermite-Simpson NLP: maps, Jacobians, guesses),
``solve`` (SCP or path transfer, dense check, tightening, summary), ``plots`` (celestial sphere and
histories), ``reference`` (CasADi/IPOPT on the same NLP) and ``bench`` (SCP vs IPOPT against the grid size).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.quaternion_attitude.spec import QuaternionAttitudeProblem


def _solve(spec, log=None):
    from convexguid.families.quaternion_attitude.solve import solve_quaternion_attitude

    return solve_quaternion_attitude(spec, log=log)


def _plot(solution, out_dir):
    from convexguid.families.quaternion_attitude.plots import plot_quaternion_attitude
    from convexguid.report.plots import save_figure

    return plot_quaternion_attitude(solution, out_dir, save_figure)


def _bench(problem_path, args):
    from convexguid.families.quaternion_attitude.bench import bench_command

    return bench_command(problem_path, args)


FAMILY = Family(
    name="quaternion_attitude",
    spec_model=QuaternionAttitudeProblem,
    solve=_solve,
    plot=_plot,
    verification_method="SciPy DOP853 re-propagation of the plan",
    bench=_bench,
)
