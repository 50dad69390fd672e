"""What ``convexguid simulate`` prints for a ``potential_function`` run besides the result block."""

from __future__ import annotations

from convexguid.families.potential_function.figures import PotentialFunctionFigures
from convexguid.families.potential_function.spec import PotentialFunctionProblem
from convexguid.solution import Solution


def header(spec: PotentialFunctionProblem) -> str:
    """``simulating <name>: 260 s in steps of 0.1 s; sweep theta_m = 5, 10 deg``."""
    sweep = f"; sweep theta_m = {', '.join(map(str, spec.sweep.theta_m_deg))} deg" if spec.sweep else ""
    return f"simulating {spec.name}: {spec.simulation.t_final_s:g} s in steps of {spec.simulation.dt_s:g} s{sweep}"


def sweep_lines(solution: Solution) -> list[str]:
    """A table with one line per sweep case (nothing without a sweep)."""
    figures = solution.figures
    cases = (figures.sweep or ()) if isinstance(figures, PotentialFunctionFigures) else ()
    if not cases:
        return []
    lines = [f"{'theta_m deg':>11} {'t 1deg s':>9} {'t 0.1deg s':>10} {'min theta_b deg':>15} "
             f"{'max |u| N m':>11} {'passed':>6}"]
    for c in cases:
        times = [f"{t:.1f}" if t is not None else "-" for t in (c.maneuver_time_1deg_s, c.maneuver_time_01deg_s)]
        lines.append(f"{c.theta_m_deg:>11g} {times[0]:>9} {times[1]:>10} {c.min_theta_b_deg:>15.3f} "
                     f"{c.max_abs_torque_Nm:>11.4g} {'yes' if c.passed else 'NO':>6}")
    return lines
