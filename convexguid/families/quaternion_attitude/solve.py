"""Plan, verify and summarise a ``quaternion_attitude`` problem: SCP (minimum time or energy) or path transfer.

The SCP plans on the nodes of the slew's Hermite-Simpson program
(:func:`~convexguid.families.quaternion_attitude.program.transcribe_slew`);
the plan's torque (linear between nodes) is then integrated with SciPy, node to node, and every cone,
the forbidden attitudes, the rate and torque boxes are checked on a dense grid. Where
the path cuts a constraint between nodes, the node constraints are tightened by the
amount seen (cone and forbidden-attitude margin, rate bound) and the problem is solved
again from the current plan, at most :data:`MAX_TIGHTENINGS` times.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from convexguid.dynamics.torque import TorqueCommand
from convexguid.families.quaternion_attitude.figures import ConeGeometry, QuaternionAttitudeFigures
from convexguid.families.quaternion_attitude.path_transfer import PathTransferProblem, plan_path_transfer
from convexguid.families.quaternion_attitude.program import (
    AttitudeCase,
    Forbidden,
    Slew,
    eigenaxis_guess,
    eigenaxis_start,
    tightened,
    transcribe_slew,
)
from convexguid.geometry import PointingCone
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.rotations import quat_angle_between, quat_sign_continuous
from convexguid.scp.check_repair import Check, PlanningSetup, Repair, grown_margin
from convexguid.scp.problem import ProgramSize, SCPSettings
from convexguid.scp.state import IterationRecord
from convexguid.solution import Solution, Trajectory, make_solution, planned_solution
from convexguid.verification import (
    AttitudeTrack,
    ConstraintCheck,
    Verification,
    propagate_attitude,
    verify_attitude_track,
)

MAX_TIGHTENINGS = 6
"""Rounds of tightening the node constraints after a failed dense check."""


def build_case(spec) -> AttitudeCase:
    """SI arrays from a validated spec; the final quaternion's sign is chosen on the initial one's side."""
    b, sc = spec.boundary, spec.spacecraft
    q0, qf = np.array(b.initial.q), np.array(b.final.q)
    if q0 @ qf < 0:
        qf = -qf
    cones = tuple(c.pointing_cone() for c in (*spec.keep_out, *spec.keep_in))
    forbidden = tuple(Forbidden(f.name, np.array(f.quaternion), np.radians(f.min_angle_deg)) for f in spec.forbidden)
    rate_max = None if sc.rate_max_degps is None else float(np.radians(sc.rate_max_degps))
    return AttitudeCase(spec.name, sc.inertia_matrix, sc.torque_max_vector, rate_max, b.t0_s, q0,
                        np.array(b.initial.rate_radps), qf, np.array(b.final.rate_radps), cones, forbidden, b.tf_s)


def path_transfer_problem(case: AttitudeCase) -> PathTransferProblem:
    """The planner's view of the case (keep-out cones of one boresight; keep-in and forbidden attitudes unsupported).

    The planner takes one torque bound for every axis: the smallest of the case's three.
    """
    keep_out = [c for c in case.cones if c.keep_out]
    boresight = keep_out[0].body_axis if keep_out else np.array([0.0, 0.0, 1.0])
    return PathTransferProblem(case.inertia, boresight, case.q0, case.qf,
                               tuple(PointingCone(c.name, c.body_axis, c.inertial_dir, c.half_angle_rad)
                                     for c in keep_out),  # re-normalised, as the planner always did
                               float(np.min(case.torque_max)), case.rate_max if case.rate_max is not None else math.inf)


def verify_plan(case: AttitudeCase, t_end: float, torque: TorqueCommand | Callable[[float], np.ndarray], settings,
                max_step: float = np.inf) -> tuple[Verification, AttitudeTrack]:
    """Integrate the planned torque and check every constraint of the case on a dense grid.

    The torque is integrated piece by piece between its breakpoints (see
    :func:`~convexguid.verification.propagate_attitude`); ``max_step`` is only for a torque without them.
    """
    t_grid = np.linspace(case.t0, t_end, settings.grid_points)
    track = propagate_attitude(case.inertia, torque, case.q0, case.w0, t_grid, settings.rtol, settings.atol,
                               max_step=max_step)
    keep_out = [c for c in case.cones if c.keep_out]
    base = verify_attitude_track(track, case.torque_max, keep_out, case.qf, case.wf, settings.constraint_tol,
                                 settings.final_attitude_tol_rad, settings.final_rate_tol_radps,
                                 rate_max=case.rate_max)
    extra = [ConstraintCheck(c.column, float(c.angles_deg(track.q).max()), c.half_angle_deg, "max")
             for c in case.cones if not c.keep_out]
    extra += [ConstraintCheck(f"forbidden_{f.name}_deg", float(np.degrees(quat_angle_between(track.q, f.q)).min()),
                              float(np.degrees(f.min_angle)), "min") for f in case.forbidden]
    checks = base.checks + tuple(extra)
    path_ok = all(c.violation <= settings.constraint_tol * max(1.0, abs(c.bound)) for c in checks)
    finals_ok = (base.final_errors["final_attitude_error_rad"] <= settings.final_attitude_tol_rad
                 and base.final_errors["final_rate_error_radps"] <= settings.final_rate_tol_radps)
    return replace(base, checks=checks, passed=path_ok and finals_ok), track


class QuaternionChecker:
    """The family's side of the engine's check-repair loop (:mod:`convexguid.scp.check_repair`).

    ``check`` integrates the planned torque (linear between nodes, integrated node to node) and checks
    every cone, the forbidden attitudes, the rate and torque boxes and the final state on a dense grid, all as the
    first slew's case states them. ``repair`` tightens the node constraints by what the check saw between nodes: the
    cone and forbidden-attitude margin, and the rate bound, each by a margin that grows every round that does not
    clear it (:func:`~convexguid.scp.check_repair.grown_margin`). The tightened program starts from the last plan;
    the engine moves that start into the tightened (hard) rate box.

    The loop hands back programs only; the checker knows their slews (case and margin): the first, and the last
    repair's, the only one the loop goes on with (earlier repairs' programs, about 13 MB each on the 50-interval
    multi-cone slew, are not kept).
    """

    def __init__(self, first: Slew, settings) -> None:
        self.case, self.settings = first.case, settings
        self.first = self.latest = first

    def slew(self, program: HermiteSimpsonProgram) -> Slew:
        """The slew whose program ``program`` is: the first or the last repair's."""
        for slew in (self.latest, self.first):
            if slew.program is program:
                return slew
        raise ValueError(f"{self.case.name}: the program is neither this checker's first nor its last repair's")

    def check(self, program: HermiteSimpsonProgram, x: np.ndarray) -> Check:
        tf = program.final_time(x)
        torque = self.slew(program).torque_command(x)
        verification, track = verify_plan(self.case, self.case.t0 + tf, torque, self.settings)
        return Check(verification, track)

    def repair(self, program: HermiteSimpsonProgram, x: np.ndarray, check: Check, attempt: int) -> Repair | None:
        by_name = {c.name: c for c in check.verification.checks}
        geometric = [c.violation for c in check.verification.checks
                     if c.name.startswith(("keep_out_", "keep_in_", "forbidden_")) and c.violation > 0]
        rate = by_name.get("rate_degps")
        rate_excess = rate.violation if rate is not None else 0.0
        if not geometric and rate_excess <= 0:
            return None
        slew = self.slew(program)
        margin, tight_case, done = slew.margin, slew.case, []
        if geometric:
            step = np.radians(grown_margin(max(geometric), attempt, CONE_MARGIN_FLOOR_DEG))
            margin += step
            done.append(f"cone and forbidden-attitude margins +{np.degrees(step):.3g} deg")
        if rate_excess > 0:
            step = np.radians(grown_margin(1.5 * rate_excess, attempt, 0.0))
            tight_case = replace(tight_case, rate_max=tight_case.rate_max - step)
            done.append(f"rate bound -{np.degrees(step):.3g} deg/s")
        self.latest = tightened(self.first, tight_case, margin)
        return Repair(self.latest.program, x, "; ".join(done))


CONE_MARGIN_FLOOR_DEG = 0.02
"""Least extra clearance a tightening round adds to the cones and forbidden attitudes, deg."""

PENALTY_RANGE = 1e4
"""How far the SCP may raise its penalty weight above the starting one when iterates stall infeasible."""


def scp_settings(solver, minimum_time: bool = False) -> SCPSettings:
    """The spec's SCP settings, with the penalty weight counted in units of the objective at the start.

    A weight of 30 then means "30 times the start's maneuver time (or energy) per unit of
    scaled constraint violation" for every case, however its torque, inertia or time scale.

    For minimum time (linear programs as subproblems) Clarabel skips the iterative refinement of its
    KKT solves. Measured on guo2011 (16 and 50 intervals) and the multi-cone case (24 and 50), each
    under torque limits perturbed by 1e-9 to 1e-2: the same statuses, objectives to eight digits and
    iteration counts no higher, at about half the time (multi-cone 1.38-1.64 s -> 0.73-0.97 s). For
    minimum energy the refinement stays: without it, 3 of 7 final times of a 16-interval guo2011 solve
    ended at the iteration limit, against none with it.
    """
    return SCPSettings.from_spec(solver, penalty_unit="objective", penalty_max=PENALTY_RANGE * solver.penalty,
                                 iterative_refinement=not minimum_time)


def planning_setup(spec, case: AttitudeCase | None = None) -> PlanningSetup:
    """The first SCP program of ``spec`` (from its initial guess), the settings and the family's checker.

    ``case`` defaults to the spec's own; a minimum-energy solve at a multiple of the minimum time
    passes the case with that final time. A path-transfer guess that ends at :math:`-q_f` (the same
    attitude, reached the other way round) takes that sign for the target.
    """
    case = build_case(spec) if case is None else case
    K = spec.discretization.intervals
    if spec.initial_guess == "path_transfer":
        plan = plan_path_transfer(path_transfer_problem(case))
        tf_guess = case.tf or plan.maneuver_time_s
        q, w, u = plan.sample(np.linspace(0.0, 1.0, K + 1) * plan.maneuver_time_s)
        q = quat_sign_continuous(q)
        if q[-1] @ case.qf < 0:
            case = replace(case, qf=-case.qf)
        scale = plan.maneuver_time_s / tf_guess
        guess = np.hstack([q, w * scale, u * scale**2])
    else:
        guess, tf_guess = eigenaxis_start(case, K)
    settings = scp_settings(spec.solver, minimum_time=case.tf is None)
    slew = transcribe_slew(case, K, guess, tf_guess)
    return PlanningSetup(slew.program, settings, QuaternionChecker(slew, spec.verification), budget=MAX_TIGHTENINGS)


def _state_columns(q: np.ndarray, omega: np.ndarray, torque: np.ndarray) -> dict[str, np.ndarray]:
    """CSV columns of quaternion, body rate (deg/s) and torque (N m)."""
    cols = {f"q{i + 1}": q[:, i] for i in range(4)}
    cols.update({f"omega{i + 1}_degps": np.degrees(omega[:, i]) for i in range(3)})
    cols.update({f"u{i + 1}_Nm": torque[:, i] for i in range(3)})
    return cols


def _energy(track: AttitudeTrack) -> float:
    """:math:`\\int |u|^2 dt` on the dense track (trapezoidal rule), N^2 m^2 s."""
    return float(np.sum(np.trapezoid(track.torque**2, track.t, axis=0)))


def _dense_columns(case: AttitudeCase, track: AttitudeTrack) -> dict[str, np.ndarray]:
    cols = _state_columns(track.q, track.omega, track.torque)
    for c in case.cones:
        cols[c.column] = c.angles_deg(track.q)
    for f in case.forbidden:
        cols[f"forbidden_{f.name}_deg"] = np.degrees(quat_angle_between(track.q, f.q))
    return cols


def cone_margin_deg(case: AttitudeCase, track: AttitudeTrack) -> float | None:
    """Smallest angular clearance to any cone edge along the track, deg (negative inside a keep-out cone)."""
    margins = [c.margin_deg(track.q).min() for c in case.cones]
    return float(min(margins)) if margins else None


def eigenaxis_cone_clearance(case: AttitudeCase, samples: int = 721) -> dict[str, float]:
    """Smallest angle (deg) between each keep-out cone's direction and its body axis along the eigenaxis slew."""
    q = eigenaxis_guess(case, np.linspace(0.0, 1.0, samples))[:, :4]
    return {c.name: float(c.angles_deg(q).min()) for c in case.cones if c.keep_out}


def cone_geometry(case: AttitudeCase) -> tuple[ConeGeometry, ...]:
    """The cones as plain data for the summary and the sky plots."""
    return tuple(ConeGeometry.of(c) for c in case.cones)


def solve_quaternion_attitude(spec, log: Callable[[IterationRecord], None] | None = None,
                              planner: object = None) -> Solution:
    """Plan with ``spec.method`` (``scp`` or ``path_transfer``), verify, and summarise.

    ``planner`` is unused (the family hook's signature: this family plans no other problem file)."""
    start = time.perf_counter()
    case = build_case(spec)
    figures = QuaternionAttitudeFigures(eigenaxis_min_angle_deg=eigenaxis_cone_clearance(case),
                                        cones=cone_geometry(case))
    if spec.method == "path_transfer":
        return _solve_path_transfer(case, spec, start, figures)
    if spec.objective == "energy" and case.tf is None:
        setup = planning_setup(spec, case)
        timed = setup.solve()
        if timed.result.status != "converged":
            timed.message = "minimum time (which sets the energy problem's final time) did not converge: " \
                + timed.message
            return planned_solution(spec, timed, start, setup.checker.slew(timed.program).size(), figures=figures)
        figures = replace(figures, min_time_s=timed.program.final_time(timed.x))
        case = replace(case, tf=spec.boundary.tf_min_time_factor * figures.min_time_s)
    setup = planning_setup(spec, case)
    outcome = setup.solve(log)
    slew, x = setup.checker.slew(outcome.program), outcome.x
    tf = slew.program.final_time(x)
    nodes = slew.nodes(x)
    node_cols = _state_columns(nodes[:, :4], nodes[:, 4:7], nodes[:, 7:])
    figures = replace(figures, maneuver_time_s=tf, node_constraint_margin_deg=float(np.degrees(slew.margin)),
                      max_quaternion_norm_error=float(np.abs(np.linalg.norm(nodes[:, :4], axis=1) - 1).max()),
                      interval_s=tf / slew.intervals, initial_guess=spec.initial_guess, objective_kind=spec.objective)
    dense = None
    if outcome.check is not None:
        track = outcome.check.track
        figures = replace(figures, energy=_energy(track), min_cone_margin_deg=cone_margin_deg(case, track))
        dense = Trajectory(track.t, _dense_columns(case, track))
    return planned_solution(spec, outcome, start, slew.size(), nodes=Trajectory(slew.times(x), node_cols),
                            dense=dense, figures=figures)


def _solve_path_transfer(case: AttitudeCase, spec, start: float, figures: QuaternionAttitudeFigures) -> Solution:
    plan = plan_path_transfer(path_transfer_problem(case))
    verification, track = verify_plan(case, case.t0 + plan.maneuver_time_s, plan.torque_command(),
                                      spec.verification)
    figures = replace(figures, maneuver_time_s=plan.maneuver_time_s, planning_time_s=plan.planning_time_s,
                      energy=_energy(track), min_cone_margin_deg=cone_margin_deg(case, track),
                      actions=tuple(f"{case.cones[i].name}: {a}" for i, a in enumerate(plan.actions)))
    return make_solution(spec, status="converged", message=f"{len(plan.waypoints)} way-points", started=start,
                         objective=plan.maneuver_time_s, iterations=0, size=ProgramSize(0, 0, 0),
                         solver="path_transfer", verification=verification,
                         dense=Trajectory(track.t, _dense_columns(case, track)), figures=figures,
                         timing={"planning_s": plan.planning_time_s})
