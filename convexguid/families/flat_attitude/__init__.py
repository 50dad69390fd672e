"""Family ``flat_attitude``: energy-optimal attitude slew in flat outputs (Cai, Zhu, Zeng 2018).

Modules: ``spec`` (problem file), ``figures`` (summary figures), ``program`` (flat maps, Jacobians, the
SCP's program), ``solve`` (SCP, path-point refinement, dense verification, summary), ``plots``,
``reference`` (CasADi/IPOPT) and ``bench`` (SCP vs IPOPT against the polynomial degree).
"""

from __future__ import annotations

from convexguid.families.base import Family, lazy
from convexguid.families.flat_attitude.figures import FlatAttitudeFigures
from convexguid.families.flat_attitude.spec import FlatAttitudeProblem, estimate_size

FAMILY = Family(
    name="flat_attitude",
    spec_model=FlatAttitudeProblem,
    solve=lazy("convexguid.families.flat_attitude.solve:solve_flat_attitude"),
    plot=lazy("convexguid.families.flat_attitude.plots:plot_flat_attitude"),
    planning_setup=lazy("convexguid.families.flat_attitude.solve:planning_setup"),
    verification_method="SciPy DOP853 re-propagation of the plan",
    figures=FlatAttitudeFigures,
    bench=lazy("convexguid.families.flat_attitude.bench:bench_command"),
    independent_optimum=lazy("convexguid.families.flat_attitude.crosscheck:independent_optimum"),
    estimate_size=estimate_size,
)
