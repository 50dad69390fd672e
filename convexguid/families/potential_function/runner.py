r"""Run a ``potential_function`` problem: closed-loop simulation, figures and checks as a :class:`Solution`.

The base case (the ``gains`` section) is simulated with :func:`~convexguid.families.potential_function.plant.simulate`;
with a ``sweep`` section every ``theta_m`` of the sweep is simulated too (a case equal to the base case reuses its
run). The result is packed into the :class:`~convexguid.solution.Solution` of the summary-JSON contract
(docs/cli.md):

* ``status``: ``converged`` when every run reaches the command, i.e. ends with an attitude error below
  :data:`ARRIVAL_TOL_DEG` (then :func:`~convexguid.families.potential_function.plant.settling_time` for that band
  exists);
  ``max_iterations`` when a run is still outside the band at ``t_final_s`` (the simulated time ran out, the
  analogue of an iteration limit).
* ``objective``: the control energy :math:`\int \|u\|^2 dt` (N^2 m^2 s) of the base run; ``iterations``: its
  number of integration steps; ``size``: zero (no program is solved); ``solver``: ``rk4``.
* ``verification``: the checks ``torque_Nm`` (if ``spacecraft.torque_max_Nm`` is set), ``rate_degps`` (if
  ``gains.w_max_degps`` is set; largest body-rate component) and ``forbidden_angle_deg`` (smallest
  :math:`\theta_b`, bound :math:`\theta_m`; with a forbidden attitude), each also for every sweep case under
  the prefix ``sweep_theta_m_<angle>_``. ``passed`` when no check is violated by more than
  :data:`CONSTRAINT_TOL` times its bound and every run reaches the command.
* ``figures``: a :class:`~convexguid.families.potential_function.figures.PotentialFunctionFigures` with
  ``maneuver_time_1deg_s``, ``maneuver_time_01deg_s``, ``min_theta_b_deg``, ``theta_m_deg``,
  ``max_abs_torque_Nm``, ``energy_N2m2s``, ``final_error_deg`` and a few more (see :func:`_figures`) of the
  base run, and ``sweep`` (with a ``sweep`` section): the same figures per sweep case, with ``reached`` and
  ``passed``.

References
----------
Guo Yanning, Li Chuanjiang, Ma Guangfu, "Spacecraft autonomous attitude maneuver control by potential function
method", Acta Aeronautica et Astronautica Sinica 32(3), 457-464, 2011 (Sec. 4, Figs. 2-5).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from convexguid.dynamics.disturbance import guo2011_disturbance, no_disturbance
from convexguid.errors import SpecError
from convexguid.families.potential_function.controller import PotentialFunctionController
from convexguid.families.potential_function.figures import PotentialFunctionFigures, SweepCaseFigures
from convexguid.families.potential_function.plant import ManeuverMetrics, SimulationResult, maneuver_metrics, simulate
from convexguid.families.potential_function.spec import PotentialFunctionProblem
from convexguid.rotations import quat_angle_between
from convexguid.scp.problem import ProgramSize
from convexguid.solution import Solution, Trajectory, _finite, make_solution
from convexguid.verification import ConstraintCheck, Verification

ARRIVAL_TOL_DEG = 0.1
"""A run has reached the command when its final attitude error is below this (deg)."""

CONSTRAINT_TOL = 1e-6
"""Allowed violation of a check, relative to its bound."""

DISTURBANCES = {"guo2011": guo2011_disturbance, "none": no_disturbance}
"""Disturbance torque of each ``simulation.disturbance`` value."""

_AXES = (1, 2, 3)


@dataclass(frozen=True)
class CaseRun:
    """One simulated case: its angles, the trajectory, its figures and its checks."""

    theta_m_deg: float
    theta_0_deg: float
    result: SimulationResult
    metrics: ManeuverMetrics
    checks: tuple[ConstraintCheck, ...]

    @property
    def reached(self) -> bool:
        """Whether the final attitude error is below :data:`ARRIVAL_TOL_DEG`."""
        return self.metrics.final_error_deg < ARRIVAL_TOL_DEG

    @property
    def passed(self) -> bool:
        """Command reached and every check within :data:`CONSTRAINT_TOL`."""
        return self.reached and all(c.violation <= CONSTRAINT_TOL * max(1.0, abs(c.bound)) for c in self.checks)


def run_case(spec: PotentialFunctionProblem, theta_m_deg: float, theta_0_deg: float) -> CaseRun:
    """Simulate ``spec`` with the forbidden-zone and influence angles replaced by the given ones (deg).

    Parameters
    ----------
    spec : PotentialFunctionProblem
        Validated problem.
    theta_m_deg, theta_0_deg : float
        Forbidden-zone angle and influence angle of this case, deg.

    Returns
    -------
    CaseRun
    """
    boundary, sim = spec.boundary, spec.simulation
    inertia = spec.spacecraft.inertia_matrix
    forbidden = None if boundary.forbidden is None else boundary.forbidden.quaternion
    controller = PotentialFunctionController(inertia, boundary.command.quaternion,
                                             spec.controller_gains(theta_m_deg, theta_0_deg), forbidden)
    result = simulate(controller, inertia, boundary.initial.quaternion, boundary.initial.rate_radps,
                      boundary.command.quaternion, sim.t_final_s, sim.dt_s, DISTURBANCES[sim.disturbance])
    metrics = maneuver_metrics(result)
    checks = []
    if spec.spacecraft.torque_max_Nm is not None:
        checks.append(ConstraintCheck("torque_Nm", metrics.max_abs_u, spec.spacecraft.torque_max_Nm, "max"))
    if spec.gains.w_max_degps is not None:
        checks.append(ConstraintCheck("rate_degps", _max_rate_degps(result), spec.gains.w_max_degps, "max"))
    if forbidden is not None:
        checks.append(ConstraintCheck("forbidden_angle_deg", metrics.min_theta_b_deg, theta_m_deg, "min"))
    return CaseRun(theta_m_deg, theta_0_deg, result, metrics, tuple(checks))


def _max_rate_degps(result: SimulationResult) -> float:
    return float(np.degrees(np.abs(result.omega).max()))


def _figures(run: CaseRun) -> dict[str, float | None]:
    """Summary figures of one run, by field of :class:`~convexguid.families.potential_function.figures.RunFigures`."""
    m, r = run.metrics, run.result
    return {
        "theta_m_deg": run.theta_m_deg,
        "theta_0_deg": run.theta_0_deg,
        "maneuver_time_1deg_s": _finite(m.t_1deg),
        "maneuver_time_01deg_s": _finite(m.t_01deg),
        "min_theta_b_deg": _finite(m.min_theta_b_deg),
        "t_min_theta_b_s": _finite(m.t_min_theta_b),
        "max_abs_torque_Nm": m.max_abs_u,
        "max_abs_torque_unclipped_Nm": float(np.abs(r.u_unclipped[:-1]).max()),
        "max_rate_degps": _max_rate_degps(r),
        "max_wheel_momentum_Nms": m.max_abs_h_w,
        "energy_N2m2s": m.energy,
        "final_error_deg": m.final_error_deg,
        "final_rate_degps": math.degrees(m.final_rate),
        "escape_time_s": float(np.count_nonzero(r.escape_active[:-1]) * r.dt),
        "repulsion_time_s": float(np.count_nonzero(r.potential_active[:-1]) * r.dt),
    }


def sweep_column(theta_m_deg: float) -> str:
    """Dense-trajectory column of the theta_b curve (deg) of the sweep case ``theta_m_deg``."""
    return f"sweep_theta_m_{theta_m_deg:g}_theta_b_deg"


def _dense(base: CaseRun, sweep: list[CaseRun]) -> Trajectory:
    """Dense trajectory of the base run, plus the theta_b curve of every sweep case."""
    r = base.result
    columns: dict[str, np.ndarray] = {f"q{i}": r.q[:, i - 1] for i in (1, 2, 3, 4)}
    columns.update({f"omega{i}_degps": np.degrees(r.omega[:, i - 1]) for i in _AXES})
    columns.update({f"u{i}_Nm": r.u[:, i - 1] for i in _AXES})
    columns.update({f"hw{i}_Nms": r.h_w[:, i - 1] for i in _AXES})
    columns["theta_e_deg"] = np.degrees(r.theta_e)
    if not np.all(np.isnan(r.theta_b)):
        columns["theta_b_deg"] = np.degrees(r.theta_b)
    columns.update({"gain_mu": r.mu, "gain_s": r.s, "gain_g": r.g})
    columns.update({flag: getattr(r, flag).astype(float) for flag in ("potential_active", "escape_active",
                                                                     "saturated")})
    for case in sweep:
        columns[sweep_column(case.theta_m_deg)] = np.degrees(case.result.theta_b)
    return Trajectory(r.t, columns)


def _verification(spec: PotentialFunctionProblem, base: CaseRun, sweep: list[CaseRun]) -> Verification:
    r = base.result
    checks = list(base.checks)
    for case in sweep:
        checks += [ConstraintCheck(f"sweep_theta_m_{case.theta_m_deg:g}_{c.name}", c.worst, c.bound, c.sense)
                   for c in case.checks]
    attitude_error = float(quat_angle_between(r.q[-1], spec.boundary.command.quaternion))
    rate_error = float(np.linalg.norm(r.omega[-1]))
    return Verification(
        grid_points=int(r.t.size), checks=tuple(checks), final_state_error=float(np.hypot(attitude_error, rate_error)),
        final_errors={"final_attitude_error_rad": attitude_error, "final_rate_error_radps": rate_error},
        passed=base.passed and all(case.passed for case in sweep),
        tolerances={"constraint_rel": CONSTRAINT_TOL, "attitude_rad": math.radians(ARRIVAL_TOL_DEG)})


def _message(spec: PotentialFunctionProblem, base: CaseRun, sweep: list[CaseRun]) -> str:
    t_final = spec.simulation.t_final_s
    if base.reached:
        text = f"command reached: error below {ARRIVAL_TOL_DEG:g} deg from t = {base.metrics.t_01deg:g} s"
    else:
        text = (f"command not reached within t_final_s = {t_final:g} s "
                f"(final error {base.metrics.final_error_deg:.4g} deg)")
    if sweep:
        missed = [f"{case.theta_m_deg:g}" for case in sweep if not case.reached]
        text += (f"; sweep: {len(sweep) - len(missed)}/{len(sweep)} cases reached the command"
                 + (f" (not: theta_m = {', '.join(missed)} deg)" if missed else ""))
    return text


def simulate_problem(spec: PotentialFunctionProblem) -> Solution:
    """Simulate a ``potential_function`` problem (and its sweep) and summarise it as a :class:`Solution`.

    Parameters
    ----------
    spec : PotentialFunctionProblem
        Validated problem (see :func:`convexguid.problem_files.load_problem`).

    Returns
    -------
    Solution
        Family and method ``potential_function``; status, verification and figures as described in the module
        docstring.

    Raises
    ------
    SpecError
        If ``spec`` is not a ``potential_function`` problem.
    """
    if not isinstance(spec, PotentialFunctionProblem):
        raise SpecError(f"{getattr(spec, 'source', '<spec>')}: family: simulate handles family potential_function "
                        f"(got {getattr(spec, 'family', type(spec).__name__)!r}); use convexguid solve")
    start = time.perf_counter()
    (theta_m, theta_0), *sweep_cases = spec.cases()
    base = run_case(spec, theta_m, theta_0)
    sweep = [base if math.isclose(m, theta_m) and math.isclose(o, theta_0) else run_case(spec, m, o)
             for m, o in sweep_cases]
    wall = time.perf_counter() - start
    cases = None
    if spec.sweep is not None:
        cases = tuple(SweepCaseFigures(**_figures(case), reached=case.reached, passed=case.passed) for case in sweep)
    reached = base.reached and all(case.reached for case in sweep)
    return make_solution(
        spec, status="converged" if reached else "max_iterations", message=_message(spec, base, sweep),
        started=start, objective=base.metrics.energy, iterations=int(base.result.t.size - 1),
        size=ProgramSize(0, 0, 0), solver="rk4", verification=_verification(spec, base, sweep),
        dense=_dense(base, sweep), figures=PotentialFunctionFigures(**_figures(base), sweep=cases),
        timing={"simulate_s": wall})
