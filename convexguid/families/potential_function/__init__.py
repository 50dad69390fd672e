"""Family ``potential_function``: closed-loop slew with forbidden-attitude avoidance (Guo, Li, Ma 2011).

Simulated, not planned: ``convexguid simulate`` runs the controller (``controller``) on the reaction-wheel plant
(``plant``) through ``runner`` (the problem file's simulation, checks and summary). Also here: ``spec`` (problem
file), ``figures`` (summary figures of the simulation), ``console`` (what the command line prints) and ``plots``.
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.potential_function.console import header, sweep_lines
from convexguid.families.potential_function.figures import PotentialFunctionFigures
from convexguid.families.potential_function.spec import PotentialFunctionProblem, estimate_size

# The hooks below import their modules when first called, so that reading a problem file loads neither the
# SCP engine nor matplotlib nor CasADi (each import inside a function here is for that reason only).


def _solve(spec, log, planner):
    """Simulate the closed loop (``log`` and ``planner`` are unused: no SCP iterations, no other problem's plan)."""
    from convexguid.families.potential_function.runner import simulate_problem

    return simulate_problem(spec)


def _plot(solution, out_dir, save):
    from convexguid.families.potential_function.plots import plot_potential_function

    return plot_potential_function(solution, out_dir, save)


FAMILY = Family(
    name="potential_function",
    spec_model=PotentialFunctionProblem,
    solve=_solve,
    plot=_plot,
    verification_method="closed-loop simulation",
    figures=PotentialFunctionFigures,
    simulated=True,
    console_header=header,
    console_details=sweep_lines,
    estimate_size=estimate_size,
    key_figures=(
        ("maneuver_time_1deg_s", "time to within 1 deg of the command, s"),
        ("maneuver_time_01deg_s", "time to within 0.1 deg of the command, s"),
        ("min_theta_b_deg", "smallest angle to the forbidden attitude, deg"),
        ("theta_m_deg", "forbidden half-angle theta_m, deg"),
        ("max_abs_torque_Nm", "largest torque component, N m"),
        ("energy_N2m2s", "energy integral of squared torque, N^2 m^2 s"),
        ("final_error_deg", "final attitude error, deg"),
    ),
)
