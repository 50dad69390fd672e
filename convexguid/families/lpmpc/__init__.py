"""Family ``lpmpc``: a planned attitude nominal flown by linear pseudospectral MPC and LQR (Feng, Chen, Yang 2018).

Simulated, not planned: ``convexguid simulate`` solves and verifies the nominal (another problem file),
then flies it closed loop. Modules: ``spec`` (problem file), ``scenario`` (nominal in MRPs, laws, runs),
``solve`` (single case, Monte Carlo on a process pool, verification, summary), ``figures``, ``plots``,
``tables`` (the paper's Tables 2-4 beside ours) and ``bench`` (update times of LPMPC and LQR); the control laws
``controller`` (LPMPC's terminal map and corrections), ``tracker`` (LPMPC in closed loop) and ``lqr``, and
``tracking`` (the MRP plant, sensors and the fixed-step closed loop they fly in).
"""

from __future__ import annotations

from convexguid.families.base import Family, lazy
from convexguid.families.lpmpc.figures import LpmpcFigures
from convexguid.families.lpmpc.spec import LpmpcProblem


def _solve(spec, log, planner):
    """Simulate, the nominal planned by ``planner`` (``log`` is unused: the nominal's SCP iterations are not shown).

    The simulation modules are imported here, at the first run: loading a problem file stays light.
    """
    from convexguid.families.lpmpc.solve import simulate_lpmpc

    return simulate_lpmpc(spec, planner)


FAMILY = Family(
    name="lpmpc",
    spec_model=LpmpcProblem,
    solve=_solve,
    plot=lazy("convexguid.families.lpmpc.plots:plot_lpmpc"),
    verification_method="the nominal's dense re-propagation and the closed-loop LPMPC flight",
    figures=LpmpcFigures,
    simulated=True,
    report_section=lazy("convexguid.families.lpmpc.tables:report_section"),
    timing_section=lazy("convexguid.families.lpmpc.tables:timing_section"),
    bench=lazy("convexguid.families.lpmpc.bench:bench_command"),
    estimate_size=lazy("convexguid.families.lpmpc.solve:estimate_size"),
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
