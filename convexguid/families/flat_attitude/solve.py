"""Plan, verify and summarise a ``flat_attitude`` problem (Cai, Zhu, Zeng 2018).

The SCP solves :class:`~convexguid.families.flat_attitude.program.FlatAttitudeProgram` inside the
engine's check-repair loop: the planned torque is integrated with SciPy and every constraint
checked on a dense grid; where the plan breaks a bound between the path points,
:class:`FlatAttitudeChecker` adds check points or tightens the node constraints, and the problem is
solved again from the last plan.
"""

from __future__ import annotations

import time
from bisect import bisect_left
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from convexguid.dynamics.torque import TorqueCommand
from convexguid.families.flat_attitude.figures import FlatAttitudeFigures
from convexguid.families.flat_attitude.program import (
    FlatAttitudeProblem,
    FlatAttitudeProgram,
    build_problem,
    cone_cosine,
)
from convexguid.rotations import euler321_to_quat, quat_to_euler321
from convexguid.scp.check_repair import Check, PlanningSetup, Repair, grown_margin
from convexguid.scp.problem import SCPSettings
from convexguid.scp.state import IterationRecord
from convexguid.solution import Solution, Trajectory, planned_solution
from convexguid.verification import Verification, propagate_attitude, torque_checks, verify_attitude_track


class BarycentricTorque(TorqueCommand):
    """The planned torque: barycentric interpolation of the node torques ``u_nodes`` (eq. 21), smooth in time.

    At one time it is evaluated from the grid's nodes and weights kept at construction (no
    interpolation matrix built per call); :meth:`sample` uses the grid's interpolation matrix.
    A time on a node gets that node's torque exactly, as the matrix does.
    """

    def __init__(self, problem: FlatAttitudeProblem, u_nodes: np.ndarray) -> None:
        super().__init__(self._at)
        self.grid, self.t0, self.scale = problem.grid, problem.t0, problem.time_scale
        self.u_nodes = np.asarray(u_nodes, dtype=float)
        self._lam = np.asarray(self.grid.nodes, dtype=float)
        self._lam_list = self._lam.tolist()
        self._weights = np.asarray(self.grid.barycentric_weights, dtype=float)
        # [u, 1]: one product gives the numerator (three axes) and the denominator
        self._table = np.column_stack([self.u_nodes, np.ones(len(self.u_nodes))])

    def _at(self, t: float) -> np.ndarray:
        lam = self.scale * (t - self.t0) - 1.0
        k = bisect_left(self._lam_list, lam)
        if k < len(self._lam_list) and self._lam_list[k] == lam:
            return self.u_nodes[k].copy()
        sums = (self._weights / (lam - self._lam)) @ self._table
        return sums[:3] / sums[3]

    def sample(self, times: np.ndarray) -> np.ndarray:
        lam = self.scale * (np.atleast_1d(np.asarray(times, dtype=float)) - self.t0) - 1.0
        return self.grid.interpolation_matrix(lam) @ self.u_nodes


def torque_command(problem: FlatAttitudeProblem, x: np.ndarray) -> BarycentricTorque:
    """The planned torque as a function of time: barycentric interpolation of the node torques (eq. 21)."""
    return BarycentricTorque(problem, problem.torques(x))


def verify_plan(problem: FlatAttitudeProblem, x: np.ndarray, settings) -> tuple[Verification, Trajectory]:
    """Propagate the planned torque with SciPy and check torque, cones and the final state on a dense grid.

    The barycentric torque is smooth on the whole interval: one integration, step set by the tolerances.
    """
    t_grid = np.linspace(problem.t0, problem.tf, settings.grid_points)
    q0 = euler321_to_quat(problem.rpy0)
    track = propagate_attitude(problem.inertia, torque_command(problem, x), q0, problem.rate0, t_grid,
                               settings.rtol, settings.atol)
    verification = verify_attitude_track(track, problem.torque_max, problem.cones, euler321_to_quat(problem.rpyf),
                                         problem.ratef, settings.constraint_tol, settings.final_attitude_tol_rad,
                                         settings.final_rate_tol_radps)
    lam = problem.time_scale * (t_grid - problem.t0) - 1.0
    planned = problem.grid.interpolation_matrix(lam) @ x.reshape(-1, 3)
    columns = {}
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        columns[f"{axis}_planned_deg"] = np.degrees(planned[:, i])
    propagated = quat_to_euler321(track.q)
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        columns[f"{axis}_propagated_deg"] = np.degrees(propagated[:, i])
    for i in range(3):
        columns[f"omega{i + 1}_degps"] = np.degrees(track.omega[:, i])
    for i in range(3):
        columns[f"u{i + 1}_Nm"] = track.torque[:, i]
    for c in problem.cones:
        columns[c.column] = c.angles_deg(track.q)
    return verification, Trajectory(track.t, columns)


def node_table(problem: FlatAttitudeProblem, x: np.ndarray) -> Trajectory:
    """Euler angles, body rates and torques at the mapped CGL nodes (the circles of the paper's Figs. 1-3)."""
    z, rates, u = x.reshape(-1, 3), problem.body_rates(x), problem.torques(x)
    columns = {}
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        columns[f"{axis}_deg"] = np.degrees(z[:, i])
    for i in range(3):
        columns[f"omega{i + 1}_degps"] = np.degrees(rates[:, i])
    for i in range(3):
        columns[f"u{i + 1}_Nm"] = u[:, i]
    return Trajectory(problem.node_times, columns)


def worst_interpolated_points(problem: FlatAttitudeProblem, x: np.ndarray, settings) -> np.ndarray:
    """Grid points (in :math:`\\lambda`) where the interpolated plan breaks the torque box or a cone.

    The plan is interpolated on the verification grid (no integration needed); of every
    run of consecutive violating points the worst one is returned.
    """
    lam = np.linspace(-1.0, 1.0, settings.grid_points)
    interp = problem.grid.interpolation_matrix(lam)
    excess = np.max(np.abs(interp @ problem.torques(x)), axis=1) / problem.torque_max - 1.0
    z = interp @ x.reshape(-1, 3)
    for cone in problem.cones:
        excess = np.maximum(excess, cone_cosine(cone, z) - np.cos(cone.half_angle_rad))
    return _worst_of_runs(lam, excess, REFINEMENT_TOLERANCE * settings.constraint_tol)


def _worst_of_runs(points: np.ndarray, excess: np.ndarray, tolerance: float) -> np.ndarray:
    """Of every run of consecutive ``points`` whose ``excess`` is above ``tolerance``, the worst one."""
    bad = np.flatnonzero(excess > tolerance)
    if bad.size == 0:
        return np.empty(0)
    runs = np.split(bad, np.flatnonzero(np.diff(bad) > 1) + 1)
    return np.array([points[run[np.argmax(excess[run])]] for run in runs])


REFINEMENT_TOLERANCE = 0.1
"""Refine until the interpolated plan meets its bounds to a tenth of the verification tolerance."""


class FlatAttitudeChecker:
    """The family's side of the engine's check-repair loop (:mod:`convexguid.scp.check_repair`).

    ``check`` propagates the planned torque and checks every constraint densely. ``repair`` adds check
    points where the interpolated plan breaks a bound between the path points and where the propagated
    path enters a cone; and since the flat-output interpolation and the true dynamics differ slightly,
    it tightens the node constraints by the excess the propagated path showed, with a margin that
    grows each round that does not clear it (:func:`~convexguid.scp.check_repair.grown_margin`). Doing both
    in one round costs a little objective (about 0.1% on a saturated case) and saves the rounds that
    adding points alone needs to close a gap of 1e-5 deg.
    """

    def __init__(self, settings) -> None:
        self.settings = settings

    def check(self, program: FlatAttitudeProgram, x: np.ndarray) -> Check:
        verification, dense = verify_plan(program.problem, x, self.settings)
        return Check(verification, dense)

    def repair(self, program: FlatAttitudeProgram, x: np.ndarray, check: Check, attempt: int) -> Repair | None:
        problem, done = program.problem, []
        between = worst_interpolated_points(problem, x, self.settings)
        if between.size:
            problem = replace(problem, extra_points=problem.extra_points + tuple(between))
            done.append(f"{between.size} check points added where the interpolated plan breaks a bound")
        points, cone_excess = [], 0.0
        by_name = {c.name: c for c in check.verification.checks}
        tol = self.settings.constraint_tol
        lam = problem.time_scale * (check.track.t - problem.t0) - 1.0
        for cone in problem.cones:
            c = by_name[cone.column]
            if c.violation > 0:
                points.append(_worst_of_runs(lam, c.bound - check.track.columns[c.name], 0.0))
                cone_excess = max(cone_excess, c.violation)
        if points:
            added = np.concatenate(points)
            problem = replace(problem, extra_points=problem.extra_points + tuple(added))
            done.append(f"{added.size} check points added where the propagated path enters a cone")
        if cone_excess > 0:
            margin = np.radians(grown_margin(cone_excess, attempt, tol * 10))
            problem = replace(problem, cone_margin_rad=problem.cone_margin_rad + margin)
            done.append(f"cones tightened by {np.degrees(margin):.3g} deg")
        torque_excess = max((c.violation for c in torque_checks(check.verification.checks)), default=0.0)
        # the flown torque is the interpolated one: check points alone repair it, unless none were found
        if torque_excess > 0 and between.size == 0:
            margin = grown_margin(torque_excess, attempt, tol * problem.torque_max)
            problem = replace(problem, torque_margin=problem.torque_margin + margin)
            done.append(f"torque box tightened by {margin:.3g} N m")
        if not done:
            return None
        return Repair(FlatAttitudeProgram(problem), x, "; ".join(done))


def planning_setup(spec) -> PlanningSetup:
    """The program of the spec, its SCP settings and the family's checker."""
    return PlanningSetup(FlatAttitudeProgram(build_problem(spec)), SCPSettings.from_spec(spec.solver),
                         FlatAttitudeChecker(spec.verification))


def solve_flat_attitude(spec, log: Callable[[IterationRecord], None] | None = None,
                        planner: object = None) -> Solution:
    """Plan, verify and summarise a ``flat_attitude`` problem (see the module docstring).

    ``planner`` is unused (the family hook's signature: this family plans no other problem file)."""
    start = time.perf_counter()
    outcome = planning_setup(spec).solve(log)
    problem, x = outcome.program.problem, outcome.x
    dense = outcome.check.track if outcome.check is not None else None
    separation = None
    if dense is not None and problem.cones:
        separation = min(float(dense.columns[f"keep_out_{c.name}_deg"].min()) for c in problem.cones)
    figures = FlatAttitudeFigures(
        energy=outcome.result.objective, max_torque_Nm=float(np.abs(problem.torques(x)).max()),
        map_alpha=problem.grid.alpha, max_constraint_violation_nodes=outcome.result.max_violation,
        min_separation_deg=separation)
    return planned_solution(spec, outcome, start, outcome.program.size(), nodes=node_table(problem, x), dense=dense,
                            figures=figures)
