"""Family ``quaternion_attitude``: minimum-time or minimum-energy slews under keep-out/keep-in cones and forbidden
attitudes (Wang, Xu, Li; Guo, Li, Ma 2011), planned by SCP or by the path-transfer planner.

Modules: ``spec`` (problem file), ``figures`` (summary figures), ``program`` (Hermite-Simpson NLP: maps,
Jacobians, guesses), ``solve`` (SCP or path transfer, dense check, tightening, summary), ``plots`` (celestial
sphere and histories), ``reference`` (CasADi/IPOPT on the same NLP) and ``bench`` (SCP vs IPOPT against the
grid size).
"""

from __future__ import annotations

from convexguid.families.base import Family, lazy
from convexguid.families.quaternion_attitude.figures import QuaternionAttitudeFigures
from convexguid.families.quaternion_attitude.spec import QuaternionAttitudeProblem, estimate_size

FAMILY = Family(
    name="quaternion_attitude",
    spec_model=QuaternionAttitudeProblem,
    solve=lazy("convexguid.families.quaternion_attitude.solve:solve_quaternion_attitude"),
    plot=lazy("convexguid.families.quaternion_attitude.plots:plot_quaternion_attitude"),
    planning_setup=lazy("convexguid.families.quaternion_attitude.solve:planning_setup"),
    verification_method="SciPy DOP853 re-propagation of the plan",
    figures=QuaternionAttitudeFigures,
    bench=lazy("convexguid.families.quaternion_attitude.bench:bench_command"),
    independent_optimum=lazy("convexguid.families.quaternion_attitude.crosscheck:independent_optimum"),
    estimate_size=estimate_size,
)
