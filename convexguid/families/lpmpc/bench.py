"""``convexguid bench`` on an ``lpmpc`` file: update times of LQR and LPMPC, and the box-constrained correction.

Two tables, measured in the same run on this machine:

1. one command update (median of ``--repeat`` x 20 calls): LQR (one Riccati solve), LPMPC with N = 8, 10, 12
   (error matrices, :math:`K_x, K_u`, eq. 42 prediction, closed-form correction), LPMPC N = 8 with the
   box-constrained QP instead (Clarabel), and the method-2 integration over the whole horizon;
2. a short Monte Carlo (``--runs``, default 20, the file's error distribution and seed) flown by LPMPC
   with the closed-form correction and with the box QP, with the file's box and with a tighter one: how
   many runs had a closed-form correction leave the torque box, and the energies, terminal errors and
   run times of both.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from convexguid.bench_common import bench_document, markdown_grid
from convexguid.dynamics.mrp_attitude import mrp_error_matrices
from convexguid.errors import SpecError
from convexguid.families.base import Planner
from convexguid.families.lpmpc.controller import box_constrained_correction, terminal_map
from convexguid.families.lpmpc.scenario import fly_monte_carlo_run
from convexguid.families.lpmpc.solve import build_scenario
from convexguid.families.lpmpc.timing import median_ms, update_times_ms
from convexguid.solution import write_text_atomic
from convexguid.transcription.lgr import RadauGrid

BENCH_NODES = (8, 10, 12)

CAPTION = ("Update times are medians of 20 x `--repeat` calls on this machine; the Monte Carlo pair flies the same "
           "seeded runs with both corrections.")
"""The benchmark document's caption (the module docstring says what each table measures)."""


def _box_update_ms(scenario, repeat: int) -> float:
    """Median ms of one LPMPC update (N = 8) with the box-constrained QP as the correction."""
    nominal, inertia_inv = scenario.nominal, np.linalg.inv(scenario.inertia)

    def update():
        grid = RadauGrid(8, float(nominal.t[0]), float(nominal.t[-1]))
        A, B = mrp_error_matrices(nominal.state(grid.times), scenario.inertia, inertia_inv)
        box_constrained_correction(terminal_map(grid, A, B), nominal.control(grid.times[1:]), 1e-3 * np.ones(6),
                                   scenario.u_max)

    return median_ms(update, repeat)


TIGHT_BOX = 0.75
"""The stress case of table 2: the same nominal with the actuator box scaled by this (the nominal peaks at 0.74 of it
on the z axis), so that corrections meet the box."""


def _monte_carlo_pair(spec, scenario, runs: int) -> list[list[str]]:
    mc = spec.monte_carlo
    euler_std = float(np.sqrt(mc.euler_var_deg2)) if mc else 3.16
    rate_std = float(np.sqrt(mc.rate_var_degps2)) if mc else 2.24
    seeds = np.random.SeedSequence(spec.simulation.seed).spawn(runs)
    rows = []
    for box, scale in (("file's box", 1.0), (f"box x {TIGHT_BOX}", TIGHT_BOX)):
        for label, boxed in (("closed form (eqs. 45-56)", False), ("box-constrained QP", True)):
            sc = replace(scenario, u_max=scale * scenario.u_max,
                         lpmpc=replace(scenario.lpmpc, box_constrained=boxed))
            rows.append(_pair_row(f"{box}, {label}", sc, seeds, euler_std, rate_std))
    return rows


def _pair_row(label: str, sc, seeds, euler_std: float, rate_std: float) -> list[str]:
    results = [fly_monte_carlo_run(sc, seed, euler_std, rate_std, 1000)["lpmpc"] for seed in seeds]
    return [label, str(len(seeds)), str(sum(r["leaves_box"] > 0 for r in results)),
            f"{np.mean([r['energy_N2m2s'] for r in results]):.4g}",
            f"{np.mean([r['angle_error_deg'] for r in results]):.3g}",
            f"{np.mean([r['rate_error_degps'] for r in results]):.3g}",
            f"{np.mean([r['run_time_s'] for r in results]):.3f}"]


def run_lpmpc_bench(spec, planner: Planner, repeat: int, runs: int, output: Path | None) -> int:
    """Time the updates and compare the corrections on the loaded ``lpmpc`` problem ``spec`` (its nominal planned
    by ``planner``); print the markdown and write it to ``output`` if given."""
    scenario, nominal = build_scenario(spec, planner)
    if scenario is None:
        raise SpecError(f"{spec.source}: the nominal plan is {nominal.status}: {nominal.message}")
    times = update_times_ms(scenario, list(BENCH_NODES), repeat=20 * repeat)
    times["lpmpc_n8_box_qp"] = _box_update_ms(scenario, 20 * repeat)
    update = markdown_grid(["update", "median [ms]"], ["---", "---:"], [[k, f"{v:.3g}"] for k, v in times.items()])
    pair = markdown_grid(["LPMPC correction", "runs", "runs leaving the box (closed form)", "mean energy [N^2 m^2 s]",
                          "mean final angle error [deg]", "mean final rate error [deg/s]", "mean run time [s]"],
                         ["---"] + ["---:"] * 6, _monte_carlo_pair(spec, scenario, runs))
    tables = "\n".join(["## One command update", "", update, "",
                         "## Closed-form against box-constrained correction (same seeds)", "", pair])
    text = bench_document(f"LPMPC benchmark: {spec.name}", ["numpy", "scipy", "clarabel"],
                          f"convexguid bench {spec.source} --repeat {repeat} --runs {runs}", CAPTION, tables)
    print(text)
    if output is not None:
        write_text_atomic(output, text)
    return 0


def bench_command(spec, args: argparse.Namespace, planner: Planner) -> int:
    """``convexguid bench`` on an ``lpmpc`` file (``--nodes`` and ``--backends`` do not apply).

    Raises
    ------
    SpecError
        If the file flies no LQR law (``lqr.r`` empty): the update table times LQR with its first weight and the
        Monte Carlo pair flies LQR tracking beside LPMPC.
    """
    if not spec.lqr.r:
        raise SpecError(f"{spec.source}: lqr.r: is empty, but the benchmark times LQR with its first weight and "
                        "flies it beside LPMPC (got []); give at least one r in the file, e.g. [0.01]")
    return run_lpmpc_bench(spec, planner, args.repeat, getattr(args, "runs", 20), args.output)
