"""Simulate an ``lpmpc`` problem: plan and verify the nominal, fly it with LPMPC and the LQR baselines.

Steps: the nominal's problem file is solved through the registry (status ``converged`` means its dense
check passed; anything else ends here with the nominal's status); the single case flies every law from
the file's initial error with one seed; the Monte Carlo (if any) flies LPMPC and LQR tracking from
seeded random initial errors on a process pool, run ``i`` always from child ``i`` of the file's seed, so
a run's result does not depend on the number of workers. The verification is the nominal's dense check
plus LPMPC's terminal errors against the file's ``checks``.
"""

from __future__ import annotations

import multiprocessing
import os
import time

import numpy as np

from convexguid.dynamics.mrp_attitude import shortest_mrp
from convexguid.errors import SpecError
from convexguid.families.base import Planner
from convexguid.families.lpmpc.figures import ControllerRun, LpmpcFigures, MonteCarloFigures, Spread
from convexguid.families.lpmpc.scenario import (
    Scenario,
    attitude_error_deg,
    fly_all,
    fly_monte_carlo_run,
    nominal_from_solution,
    rate_error_degps,
    resolve_nominal_path,
)
from convexguid.families.lpmpc.timing import update_times_ms
from convexguid.families.lpmpc.tracker import LpmpcSettings
from convexguid.families.lpmpc.tracking import DisturbanceTorque, Sensors
from convexguid.progress import report
from convexguid.rotations import mrp_to_quat, quat_angle_between, quat_to_euler321, quat_to_mrp
from convexguid.scp.problem import ProgramSize
from convexguid.sizes import PROCESS_BYTES, SizeEstimate
from convexguid.solution import Solution, Trajectory, make_solution
from convexguid.spec.loader import apply_overrides, read_yaml_mapping, value_at, with_values
from convexguid.threads import pool_worker_init
from convexguid.verification import ConstraintCheck, Verification

ENVELOPE_STRIDE = 10
"""Monte Carlo histories are kept every this many steps (for the envelope plots)."""


NOMINAL_FAMILIES = ("quaternion_attitude",)
"""Families whose plan LPMPC can fly: a dense trajectory with the quaternion, the body rates and the torque."""


def load_nominal_spec(spec, planner: Planner):
    """The nominal's problem (loaded by ``planner``), with ``set`` applied and the final time from ``nominal.tf_s``
    if given.

    Raises
    ------
    SpecError
        If the file is not a problem of :data:`NOMINAL_FAMILIES` (or is invalid).
    """
    path = resolve_nominal_path(spec)
    nominal_spec = planner.load(path, spec.nominal.set)
    if nominal_spec.family not in NOMINAL_FAMILIES:
        raise SpecError(f"{spec.source}: nominal.problem: {path} is a {nominal_spec.family} problem (got "
                        f"{spec.nominal.problem!r}); give a problem file of the family "
                        f"{' or '.join(NOMINAL_FAMILIES)}, whose plan LPMPC can fly")
    if spec.nominal.tf_s is None:
        return nominal_spec
    timed: dict[str, float | None] = {"boundary.tf_s": spec.nominal.tf_s}
    if getattr(nominal_spec.boundary, "tf_from", None) is not None:
        timed["boundary.tf_from"] = None
    return with_values(nominal_spec, timed)


BYTES_PER_LAW_STEP = 250
"""Memory kept per step of one law's single-case flight (measured about 220 B at 800 and 8000 steps)."""

BYTES_PER_RUN = 4_000
"""Memory of one Monte Carlo run's figures, besides its histories (the per-run dictionaries)."""


def estimate_size(spec) -> SizeEstimate:
    """Peak memory: the single case's flights (every law) and dense table, and the Monte Carlo's runs.

    The step count needs the nominal's final time (``nominal.tf_s``, or ``boundary.tf_s`` in the nominal's file
    with ``nominal.set`` applied, read without validating it: the solve does that); a minimum-time nominal's is
    known only after its solve, and then the estimate counts the runs alone.
    """
    tf = spec.nominal.tf_s
    if tf is None:
        path = resolve_nominal_path(spec)
        data = apply_overrides(read_yaml_mapping(path, "a problem file is a mapping"), spec.nominal.set, str(path))
        written = value_at(data, "boundary.tf_s")
        tf = written if isinstance(written, (int, float)) and not isinstance(written, bool) else None
    steps = 0 if tf is None else round(tf / spec.simulation.dt_s) + 1
    laws = 1 + 2 * len(spec.lqr.r)
    single = steps * laws * BYTES_PER_LAW_STEP
    runs = spec.monte_carlo.runs if spec.monte_carlo is not None else 0
    # per run: its figures and the two laws' angle and rate histories (3 + 3 numbers) every ENVELOPE_STRIDE steps
    monte_carlo = runs * (BYTES_PER_RUN + 2 * 6 * 8 * steps / ENVELOPE_STRIDE)
    key, value = ("simulation.dt_s", spec.simulation.dt_s) if single >= monte_carlo else ("monte_carlo.runs", runs)
    return SizeEstimate(PROCESS_BYTES + single + monte_carlo, key, value,
                        f"{steps} steps x {laws} laws, {runs} Monte Carlo runs")


def forbidden_angles_deg(scenario: Scenario, x: np.ndarray) -> dict[str, tuple[float, float]]:
    """Smallest Euler-axis angle (deg) of the MRP history ``x`` to each forbidden attitude of the nominal's
    problem, with its bound: ``{name: (smallest, min_angle_deg)}`` (empty if the problem has none)."""
    return {name: (float(np.degrees(quat_angle_between(mrp_to_quat(x[:, :3]), q)).min()), bound)
            for name, q, bound in scenario.forbidden}


def build_scenario(spec, planner: Planner) -> tuple[Scenario | None, Solution]:
    """The scenario of ``spec`` and the nominal's solution, planned by ``planner`` (scenario None if the nominal is
    not verified)."""
    nominal_spec = load_nominal_spec(spec, planner)
    nominal_solution = planner.solve(nominal_spec)
    if not nominal_solution.ok:
        return None, nominal_solution
    sc = nominal_spec.spacecraft
    final = nominal_spec.boundary.final
    target_sigma = short_mrp_of_quat(final.q)
    s = spec.lpmpc
    written = _written_limits(spec, planner)
    scenario = Scenario(
        nominal=nominal_from_solution(nominal_solution, spec.simulation.dt_s),
        inertia=np.array(sc.inertia_matrix, dtype=float),
        u_max=np.broadcast_to(np.asarray(sc.torque_max_Nm, dtype=float), 3).copy(),
        target=np.concatenate([target_sigma, final.rate_radps]),
        sensors=Sensors(np.radians(spec.sensors.euler_std_deg), np.radians(spec.sensors.rate_std_degps)),
        disturbance=DisturbanceTorque(spec.disturbance.model, spec.disturbance.torque_std_Nm),
        lpmpc=LpmpcSettings(s.nodes, s.check_interval_s, s.threshold_mrp, np.radians(s.threshold_rate_degps),
                            box_constrained=s.correction == "box_qp", backend=s.backend,
                            least_change=s.correction == "least_change"),
        lqr_q=spec.lqr.q, lqr_r=tuple(spec.lqr.r),
        forbidden=tuple((f.name, np.asarray(f.quaternion, dtype=float),
                         written.get(f.name, float(f.min_angle_deg)))
                        for f in getattr(nominal_spec, "forbidden", ())))
    return scenario, nominal_solution


def _written_limits(spec, planner: Planner) -> dict[str, float]:
    """The least angle (deg) to each forbidden attitude of the nominal's problem file as written, by name, before
    ``nominal.set``: a plan may be padded away from a limit (room for the closed loop), but the flight is held to
    the limit itself."""
    written = planner.load(resolve_nominal_path(spec))
    return {f.name: float(f.min_angle_deg) for f in getattr(written, "forbidden", ())}


def short_mrp_of_quat(q: np.ndarray) -> np.ndarray:
    """Short MRPs (:math:`|\\sigma| \\le 1`) of a scalar-last quaternion."""
    q = np.asarray(q, dtype=float)
    return shortest_mrp(quat_to_mrp(q if q[3] >= 0 else -q))


def simulate_lpmpc(spec, planner: Planner) -> Solution:
    """Run the ``lpmpc`` problem ``spec``, its nominal planned by ``planner`` (see the module docstring)."""
    started = time.perf_counter()
    scenario, nominal = build_scenario(spec, planner)
    base = {"nominal_problem": nominal.problem, "nominal_status": nominal.status,
            "nominal_energy_N2m2s": _nominal_energy(nominal)}
    if scenario is None:
        return make_solution(spec, status=nominal.status, message=f"nominal plan {nominal.problem}: {nominal.message}",
                             started=started, objective=float("nan"), iterations=0, size=ProgramSize(0, 0, 0),
                             solver=spec.lpmpc.backend, verification=nominal.verification,
                             figures=LpmpcFigures(**base))
    x0 = scenario.initial_state(np.array(spec.initial_error.euler_deg), np.array(spec.initial_error.rate_degps))
    flights = fly_all(scenario, x0, spec.simulation.seed)
    runs = tuple(_controller_run(f, law, scenario.target) for f, law in flights)
    lpmpc_flight, tracker = flights[0]
    forbidden = forbidden_angles_deg(scenario, lpmpc_flight.x)
    checks = tracker.checks
    monte_carlo, envelopes = _monte_carlo(spec, scenario) if spec.monte_carlo is not None else (None, {})
    update_times = update_times_ms(scenario, spec.timing_nodes) if spec.timing_nodes else None
    figures = LpmpcFigures(
        **base, runs=runs, lpmpc_energy_N2m2s=runs[0].energy_N2m2s,
        lpmpc_final_angle_error_deg=runs[0].final_angle_error_deg,
        lpmpc_final_rate_error_degps=runs[0].final_rate_error_degps, corrections=tracker.corrections,
        update_checks=len(checks), closed_form_leaves_box=int(sum(c.leaves_box for c in checks)),
        prediction_time_median_ms=_median_ms([c.prediction_time_s for c in checks]),
        correction_time_median_ms=_median_ms([c.correction_time_s for c in checks if c.corrected]),
        integration_time_median_ms=_median_ms([c.integration_time_s for c in checks if c.miss is not None]),
        update_time_ms=update_times, monte_carlo=monte_carlo,
        maneuver_time_s=float(scenario.nominal.t[-1] - scenario.nominal.t[0]),
        min_forbidden_angle_deg=min((a for a, _ in forbidden.values()), default=None))
    verification = _verification(spec, nominal, runs[0], lpmpc_flight.t.size, forbidden)
    status = "converged" if verification.passed else "unverified"
    message = (f"{tracker.corrections} LPMPC corrections in {len(checks)} checks; final attitude error "
               f"{runs[0].final_angle_error_deg:.3g} deg, rate error {runs[0].final_rate_error_degps:.3g} deg/s")
    return make_solution(spec, status=status, message=message, started=started, objective=runs[0].energy_N2m2s,
                         iterations=tracker.corrections, size=ProgramSize(0, 0, 0), solver=spec.lpmpc.backend,
                         verification=verification, dense=_dense(flights, scenario, envelopes),
                         figures=figures, timing={"simulate_s": time.perf_counter() - started})


def _nominal_energy(nominal: Solution) -> float | None:
    figures = nominal.figures
    return getattr(figures, "energy", None) if figures is not None else None


def _median_ms(values: list[float]) -> float | None:
    return float(1e3 * np.median(values)) if values else None


def _controller_run(flight, law, target: np.ndarray) -> ControllerRun:
    corrections = getattr(law, "corrections", None)
    return ControllerRun(flight.controller, tuple(flight.final_euler_deg.tolist()),
                         tuple(flight.final_rate_degps.tolist()), attitude_error_deg(flight.x[-1], target),
                         rate_error_degps(flight.x[-1], target), flight.energy, flight.command_time_s,
                         flight.wall_time_s, corrections,
                         len(law.checks) if corrections is not None else None)


def _verification(spec, nominal: Solution, lpmpc: ControllerRun, grid_points: int,
                  forbidden: dict[str, tuple[float, float]]) -> Verification:
    """The nominal's dense checks (prefixed ``nominal_``); LPMPC's terminal errors against ``checks`` and its
    flight's distance to each forbidden attitude of the nominal's problem."""
    nominal_checks = tuple(ConstraintCheck(f"nominal_{c.name}", c.worst, c.bound, c.sense)
                           for c in nominal.verification.checks)
    flight_checks = (ConstraintCheck("lpmpc_final_angle_error_deg", lpmpc.final_angle_error_deg,
                                     spec.checks.final_angle_deg, "max"),
                     ConstraintCheck("lpmpc_final_rate_error_degps", lpmpc.final_rate_error_degps,
                                     spec.checks.final_rate_degps, "max"))
    flight_checks += tuple(ConstraintCheck(f"lpmpc_forbidden_{name}_deg", smallest, bound, "min")
                           for name, (smallest, bound) in forbidden.items())
    checks = nominal_checks + flight_checks
    passed = nominal.verification.passed and all(c.violation == 0 for c in flight_checks)
    return Verification(grid_points=grid_points, checks=checks,
                        final_state_error=float(np.hypot(np.radians(lpmpc.final_angle_error_deg),
                                                         np.radians(lpmpc.final_rate_error_degps))),
                        final_errors={"final_attitude_error_deg": lpmpc.final_angle_error_deg,
                                      "final_rate_error_degps": lpmpc.final_rate_error_degps},
                        passed=passed,
                        tolerances={"attitude_deg": spec.checks.final_angle_deg,
                                    "rate_degps": spec.checks.final_rate_degps})


def _workers(requested: int) -> int:
    return requested or os.cpu_count() or 1


def _monte_carlo(spec, scenario: Scenario) -> tuple[MonteCarloFigures, dict[str, np.ndarray]]:
    """The runs' figures, and the envelopes (least and largest over the runs) of their angle and rate histories."""
    mc = spec.monte_carlo
    seeds = np.random.SeedSequence(spec.simulation.seed).spawn(mc.runs)
    euler_std, rate_std = float(np.sqrt(mc.euler_var_deg2)), float(np.sqrt(mc.rate_var_degps2))
    workers = min(_workers(mc.workers), mc.runs)
    started = time.perf_counter()
    args = [(scenario, seed, euler_std, rate_std, ENVELOPE_STRIDE) for seed in seeds]
    if workers == 1:
        results = []
        for i, a in enumerate(args):
            report("Monte Carlo run", i, len(args))
            results.append(fly_monte_carlo_run(*a))
    else:
        results = _fly_on_pool(args, workers)
    wall = time.perf_counter() - started
    t = scenario.nominal.t[::ENVELOPE_STRIDE]
    envelopes = {}
    for key in ("lpmpc", "lqr"):
        for label, field, names in (("euler_deg", "euler_deg", AXES), ("rate_degps", "rate_degps", ("1", "2", "3"))):
            stack = np.stack([r[key][field] for r in results])
            for i, axis in enumerate(names):
                column = f"mc_{key}_{axis}_deg" if label == "euler_deg" else f"mc_{key}_omega{axis}_degps"
                envelopes[column + "_min"] = np.interp(scenario.nominal.t, t, stack[:, :, i].min(axis=0))
                envelopes[column + "_max"] = np.interp(scenario.nominal.t, t, stack[:, :, i].max(axis=0))
    return _monte_carlo_figures(results, workers, wall), envelopes


def _fly_on_pool(args: list[tuple], workers: int) -> list[dict]:
    """The Monte Carlo runs on a pool of ``workers`` processes, in order, reporting each finished run.

    The workers run one BLAS/OpenMP thread each (:mod:`convexguid.threads`) and ignore Ctrl-C (it reaches the whole
    process group): this process decides. On an interrupt (or any
    error) leaving the ``with`` block terminates the pool: no queued run starts and the runs in flight are dropped,
    so the command exits at once instead of after them (a ``ProcessPoolExecutor`` shut down with ``cancel_futures``
    still finishes the runs in flight: 3 s measured).
    """
    with multiprocessing.Pool(workers, initializer=pool_worker_init) as pool:
        arriving = pool.imap(_run_star, args)
        results: list[dict] = []
        while len(results) < len(args):
            report("Monte Carlo run", len(results), len(args))
            try:
                results.append(arriving.next(timeout=0.2))
            except multiprocessing.TimeoutError:
                pass
    return results


def _run_star(args: tuple) -> dict:
    return fly_monte_carlo_run(*args)


def _spread(values) -> Spread:
    v = np.asarray(values, dtype=float)
    return Spread(float(v.mean()), float(v.std()))


def _monte_carlo_figures(results: list[dict], workers: int, wall: float) -> MonteCarloFigures:
    def terminal(key: str) -> tuple[Spread, ...]:
        finals = np.array([r[key]["final_euler_deg"] + r[key]["final_rate_degps"] for r in results])
        return tuple(_spread(finals[:, i]) for i in range(6))

    e_lpmpc = np.array([r["lpmpc"]["energy_N2m2s"] for r in results])
    e_lqr = np.array([r["lqr"]["energy_N2m2s"] for r in results])
    saving = (e_lqr - e_lpmpc) / e_lqr
    corrections = np.array([r["lpmpc"]["corrections"] for r in results])
    per_run = tuple({"euler_error_deg": r["euler_error_deg"], "rate_error_degps": r["rate_error_degps"],
                     **{f"{k}_{f}": r[k][f] for k in ("lpmpc", "lqr")
                        for f in ("final_euler_deg", "final_rate_degps", "angle_error_deg", "rate_error_degps",
                                  "energy_N2m2s")},
                     "lpmpc_corrections": r["lpmpc"]["corrections"]} for r in results)
    return MonteCarloFigures(
        runs=len(results), workers=workers, wall_time_s=wall, runs_per_s=len(results) / wall,
        lpmpc_terminal=terminal("lpmpc"), lqr_terminal=terminal("lqr"),
        lpmpc_angle_error_deg=_spread([r["lpmpc"]["angle_error_deg"] for r in results]),
        lqr_angle_error_deg=_spread([r["lqr"]["angle_error_deg"] for r in results]),
        lpmpc_energy_N2m2s=_spread(e_lpmpc), lqr_energy_N2m2s=_spread(e_lqr), saving=_spread(saving),
        saving_range=(float(saving.min()), float(saving.max())), runs_lpmpc_saves_energy=int((saving > 0).sum()),
        corrections_per_run=_spread(corrections), corrections_range=(int(corrections.min()), int(corrections.max())),
        lpmpc_run_time_s=_spread([r["lpmpc"]["run_time_s"] for r in results]),
        lqr_run_time_s=_spread([r["lqr"]["run_time_s"] for r in results]),
        closed_form_leaves_box_runs=int(sum(r["lpmpc"]["leaves_box"] > 0 for r in results)), per_run=per_run)


AXES = ("roll", "pitch", "yaw")


def _dense(flights, scenario: Scenario, envelopes: dict[str, np.ndarray]) -> Trajectory:
    """Histories of the nominal and of every law: 3-2-1 Euler angles (deg), rates (deg/s), torques (N m); then the
    Monte Carlo envelopes, if any."""
    t = scenario.nominal.t
    columns: dict[str, np.ndarray] = {}
    series = [("nominal", scenario.nominal.x, scenario.nominal.u)] + [(f.controller, f.x, f.u) for f, _ in flights]
    for name, x, u in series:
        euler = np.degrees(quat_to_euler321(mrp_to_quat(x[:, :3])))
        for i, axis in enumerate(AXES):
            columns[f"{name}_{axis}_deg"] = euler[:, i]
        for i in range(3):
            columns[f"{name}_omega{i + 1}_degps"] = np.degrees(x[:, 3 + i])
        for i in range(3):
            columns[f"{name}_u{i + 1}_Nm"] = u[:, i]
    columns.update(envelopes)
    return Trajectory(t, columns)
