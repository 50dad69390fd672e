"""Family ``rendezvous``: finite-thrust minimum-burn-time rendezvous in Clohessy-Wiltshire dynamics (Wang & Tang 2003).

Modules: ``spec`` (problem file), ``figures`` (summary figures), ``case`` (problem data, thrust plans,
propagation, verification), ``arcs`` (the paper's burn/coast NLP for the SCP), ``lcvx`` (lossless
convexification, one SOCP), ``solve`` (either method, verification, certificate, summary), ``plots``,
``reference`` (CasADi/IPOPT on the arcs NLP) and ``bench`` (lcvx vs scp_arcs vs IPOPT).
"""

from __future__ import annotations

from convexguid.families.base import Family, lazy
from convexguid.families.rendezvous.figures import RendezvousFigures
from convexguid.families.rendezvous.spec import RendezvousProblem, estimate_size

FAMILY = Family(
    name="rendezvous",
    spec_model=RendezvousProblem,
    solve=lazy("convexguid.families.rendezvous.solve:solve_rendezvous"),
    plot=lazy("convexguid.families.rendezvous.plots:plot_rendezvous"),
    planning_setup=lazy("convexguid.families.rendezvous.solve:planning_setup"),
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
    bench=lazy("convexguid.families.rendezvous.bench:bench_command"),
    independent_optimum=lazy("convexguid.families.rendezvous.crosscheck:independent_optimum"),
    estimate_size=estimate_size,
)
