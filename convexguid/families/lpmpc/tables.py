"""The ``lpmpc`` case in the validation report: the paper's Tables 2-4 beside ours (rendering only).

The paper's figures come from the problem file's ``paper`` section; ours from the solution's figures.
The scenarios differ (the paper's initial errors and equations were lost in extraction), so the text
invites comparing ratios and orders of magnitude, not digits. :func:`report_section` renders what is the
same on every run; :func:`timing_section` the compute times (Table 4, the Monte Carlo's throughput), which go
to the validation timings file.
"""

from __future__ import annotations

from convexguid.families.lpmpc.figures import LpmpcFigures, MonteCarloFigures
from convexguid.solution import Solution

ITEMS = ("roll [deg]", "pitch [deg]", "yaw [deg]", "omega1 [deg/s]", "omega2 [deg/s]", "omega3 [deg/s]")

READING = ("Readings of the paper's N(0, x): the disturbance torque and the sensor noise take x as a standard "
           "deviation (in the units given); the Monte Carlo initial errors N(0, 10) and N(0, 5) take x as a "
           "variance in deg^2 and (deg/s)^2 (standard deviations 3.16 deg and 2.24 deg/s), this project's reading "
           "(docs/parameters.md).")


def _vec(values) -> str:
    return "[" + ", ".join(f"{v:.3g}" for v in values) + "]"


def report_section(spec, solution: Solution) -> list[str]:
    """Markdown lines of the case's tables (empty if the run did not fly)."""
    fig: LpmpcFigures = solution.figures
    if fig is None or not fig.runs:
        return []
    paper = spec.paper
    lines = ["", f"Nominal `{fig.nominal_problem}` ({fig.nominal_status}): energy {fig.nominal_energy_N2m2s:.4g} "
             "N^2 m^2 s. " + READING]
    lines += _table2(fig, paper)
    if fig.update_time_ms:
        lines += _table4_paper(paper)
    if fig.monte_carlo is not None:
        lines += _table3(fig.monte_carlo, paper)
    return lines


def timing_section(spec, solution: Solution) -> list[str]:
    """Markdown lines of the case's compute times: correction medians, Table 4, the Monte Carlo's throughput."""
    fig: LpmpcFigures = solution.figures
    if fig is None or not fig.runs:
        return []
    lines = []
    if fig.correction_time_median_ms is not None:
        lines += ["", f"Median LPMPC correction time in the flight (prediction + KKT): "
                  f"{fig.correction_time_median_ms:.3g} ms."]
    if fig.update_time_ms:
        lines += _table4(fig, spec.paper)
    mc = fig.monte_carlo
    if mc is not None:
        lines += ["", f"Monte Carlo, {mc.runs} seeded runs on {mc.workers} processes: {mc.wall_time_s:.1f} s "
                  f"({mc.runs_per_s:.2f} runs/s). Whole run: LPMPC {mc.lpmpc_run_time_s.mean:.3g} s, LQR tracking "
                  f"{mc.lqr_run_time_s.mean:.3g} s (mean per run)."]
    return lines


def _table2(fig: LpmpcFigures, paper) -> list[str]:
    published = {row.controller: row for row in (paper.table2 if paper else [])}
    lines = ["", "Single case (the paper's Table 2 layout; paper values from its own scenario):", "",
             "| law | final 3-2-1 angles [deg] | paper | final rates [deg/s] | paper | energy [N^2 m^2 s] | paper | "
             "energy / LPMPC's | paper |", "|---|---|---|---|---|---|---|---|---|"]
    base = fig.runs[0].energy_N2m2s
    paper_base = published["lpmpc"].energy_N2m2s if "lpmpc" in published else None
    for run in fig.runs:
        p = published.get(run.controller)
        cells = [_vec(run.final_euler_deg), _vec(p.final_euler_deg) if p else "-", _vec(run.final_rate_degps),
                 _vec(p.final_rate_degps) if p else "-", f"{run.energy_N2m2s:.4g}",
                 f"{p.energy_N2m2s:.5g}" if p else "-", f"{run.energy_N2m2s / base:.3f}",
                 f"{p.energy_N2m2s / paper_base:.3f}" if p and paper_base else "-"]
        lines.append(f"| {run.controller} | " + " | ".join(cells) + " |")
    lines += ["", f"LPMPC fired {fig.corrections} corrections in {fig.update_checks} update checks; "
              f"{fig.closed_form_leaves_box} of them would have left the torque box in closed form. The rate "
              "threshold (0.005 deg/s) lies below the rate noise (0.01 deg/s), so nearly every check fires."]
    return lines


def _table4_paper(paper) -> list[str]:
    """Where the Table 4 comparison is, and the paper's side of it."""
    published = paper.table4_command_ms if paper else {}
    theirs = ", ".join(f"{key} {value:g} ms" for key, value in published.items())
    return ["", "Command generation per update (the paper's Table 4): our medians depend on the machine and are in "
            "the timings file `convexguid validate` writes beside this report (not committed)"
            + (f"; the paper's, in MATLAB on a 2013 laptop: {theirs}." if theirs else ".")]


def _table4(fig: LpmpcFigures, paper) -> list[str]:
    times = fig.update_time_ms
    published = paper.table4_command_ms if paper else {}
    lines = ["", "Command generation per update (Table 4 layout; medians on this machine, the paper's on a 2013 "
             "laptop in MATLAB):", "", "| law | ours [ms] | paper [ms] |", "|---|---|---|"]
    for key, value in times.items():
        if key == "integration":
            continue
        paper_value = published.get(key)
        lines.append(f"| {key} | {value:.3g} | {paper_value:g} |" if paper_value else f"| {key} | {value:.3g} | - |")
    lines += ["", f"The method-2 integration over the whole horizon (re-nominalizing) takes "
              f"{times['integration']:.3g} ms and is not part of the update above."]
    return lines


def _table3(mc: MonteCarloFigures, paper) -> list[str]:
    lines = ["", f"Monte Carlo, {mc.runs} seeded runs. Terminal values (the paper's Table 3 layout):", "",
             "| item | LPMPC mean (std) | paper | LQR tracking mean (std) | paper |", "|---|---|---|---|---|"]
    for i, item in enumerate(ITEMS):
        ours_l, ours_q = mc.lpmpc_terminal[i], mc.lqr_terminal[i]
        pl = paper.table3_lpmpc[i] if paper and paper.table3_lpmpc else None
        pq = paper.table3_lqr[i] if paper and paper.table3_lqr else None
        lines.append(f"| {item} | {ours_l.mean:.4g} ({ours_l.std:.3g}) | "
                     f"{f'{pl.mean:g} ({pl.std:g})' if pl else '-'} | {ours_q.mean:.4g} ({ours_q.std:.3g}) | "
                     f"{f'{pq.mean:g} ({pq.std:g})' if pq else '-'} |")
    saving = mc.saving
    paper_saving = f"about {100 * paper.energy_saving:.0f}%" if paper and paper.energy_saving is not None else "n/a"
    lines += ["", f"Final attitude error: LPMPC {mc.lpmpc_angle_error_deg.mean:.3g} deg "
              f"(std {mc.lpmpc_angle_error_deg.std:.3g}), LQR tracking {mc.lqr_angle_error_deg.mean:.3g} deg "
              f"(std {mc.lqr_angle_error_deg.std:.3g}).",
              f"Energy: LPMPC {mc.lpmpc_energy_N2m2s.mean:.4g} N^2 m^2 s (std {mc.lpmpc_energy_N2m2s.std:.3g}), "
              f"LQR tracking {mc.lqr_energy_N2m2s.mean:.4g} (std {mc.lqr_energy_N2m2s.std:.3g}). Saving of LPMPC "
              f"against LQR tracking run by run: mean {100 * saving.mean:.1f}% (std {100 * saving.std:.1f}%, "
              f"from {100 * mc.saving_range[0]:.1f}% to {100 * mc.saving_range[1]:.1f}%); LPMPC uses less energy in "
              f"{mc.runs_lpmpc_saves_energy} of {mc.runs} runs (paper: {paper_saving} on its scenario). The two "
              "laws do not end equally close to the target, so the saving is not at equal terminal accuracy.",
              f"Corrections per run: mean {mc.corrections_per_run.mean:.2f}, from {mc.corrections_range[0]} to "
              f"{mc.corrections_range[1]} (the paper reports 1 to 3); runs in which a closed-form correction "
              f"would leave the torque box: {mc.closed_form_leaves_box_runs}."]
    return lines
