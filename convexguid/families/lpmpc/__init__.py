"""Family ``lpmpc``: a planned attitude nominal flown by linear pseudospectral MPC and LQR (Feng, Chen, Yang 2018).

Simulated, not planned: ``convexguid simulate`` solves and verifies the nominal (another problem file),
then flies it closed loop. Modules: ``spec`` (problem file), ``scenario`` (nominal in MRPs, laws, runs),
``solve`` (single case, Monte Carlo on a process pool, verification, summary), ``figures``, ``plots``,
``tables`` (the paper's Tables 2-4 beside ours) and ``bench`` (update times of LPMPC and LQR); the control laws
``controller`` (LPMPC's terminal map and corrections), ``tracker`` (LPMPC in closed loop) and ``lqr``, and
``tracking`` (the MRP plant, sensors and the fixed-step closed loop they fly in).
"""

from __future__ import annotations

from convexguid.families.base import Family
from convexguid.families.lpmpc.figures import LpmpcFigures
from convexguid.families.lpmpc.spec import LpmpcProblem

# The hooks below import their modules when first called, so that reading a problem file loads neither the
# SCP engine nor matplotlib nor CasADi (each import inside a function here is for that reason only).


def _solve(spec, log, planner):
    """Simulate, the nominal planned by ``planner`` (``log`` is unused: the nominal's SCP iterations are not shown)."""
    from convexguid.families.lpmpc.solve import simulate_lpmpc

    return simulate_lpmpc(spec, planner)


def _plot(solution, out_dir, save):
    from convexguid.families.lpmpc.plots import plot_lpmpc

    return plot_lpmpc(solution, out_dir, save)


def _report_section(spec, solution):
    from convexguid.families.lpmpc.tables import report_section

    return report_section(spec, solution)


def _timing_section(spec, solution):
    from convexguid.families.lpmpc.tables import timing_section

    return timing_section(spec, solution)


def _bench(spec, args, planner):
    from convexguid.families.lpmpc.bench import bench_command

    return bench_command(spec, args, planner)


def _estimate_size(spec):
    from convexguid.families.lpmpc.solve import estimate_size

    return estimate_size(spec)


FAMILY = Family(
    name="lpmpc",
    spec_model=LpmpcProblem,
    solve=_solve,
    plot=_plot,
    verification_method="the nominal's dense re-propagation and the closed-loop LPMPC flight",
    figures=LpmpcFigures,
    simulated=True,
    report_section=_report_section,
    timing_section=_timing_section,
    bench=_bench,
    estimate_size=_estimate_size,
    key_figures=(
        ("nominal_energy_N2m2s", "nominal plan: energy integral of squared torque, N^2 m^2 s"),
        ("lpmpc_energy_N2m2s", "LPMPC closed loop: energy, N^2 m^2 s"),
        ("lpmpc_final_angle_error_deg", "LPMPC: final attitude error, deg"),
        ("lpmpc_final_rate_error_degps", "LPMPC: final rate error, deg/s"),
        ("corrections", "LPMPC corrections fired"),
        ("update_checks", "LPMPC update checks"),
        ("closed_form_leaves_box", "closed-form corrections that would leave the torque box"),
    ),
)
