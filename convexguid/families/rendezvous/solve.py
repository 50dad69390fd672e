"""Plan a ``rendezvous`` problem with ``scp_arcs`` or ``lcvx``, verify it by propagation, certify ``scp_arcs``.

See :mod:`convexguid.families.rendezvous.case` for the problem, the two methods and the verification.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import fields, replace

import numpy as np

from convexguid.families.rendezvous.arc_phases import PhasedArcsProgram
from convexguid.families.rendezvous.case import (
    BurnArc,
    Rendezvous,
    RendezvousPlan,
    ThrustPlan,
    build_case,
    propagate_thrust,
    state_columns,
    verify_track,
)
from convexguid.families.rendezvous.figures import ArcsPlanFigures, LcvxCertificate, RendezvousFigures
from convexguid.families.rendezvous.lcvx import solve_lcvx
from convexguid.scp.check_repair import Check, PlanningSetup, Repair
from convexguid.scp.problem import SCPSettings
from convexguid.scp.state import IterationRecord
from convexguid.solution import Solution, Trajectory, make_solution

DEFAULT_BURNS = 2
"""Burns of ``burns: auto`` when ``lcvx`` has none to give (it failed): the paper's burn - coast - burn."""
GAP_TOLERANCE = 1e-3
"""An ``scp_arcs`` plan more than this far (relative) above the ``lcvx`` optimum says so in its message."""


def solve_rendezvous(spec, log: Callable[[IterationRecord], None] | None = None,
                     planner: object = None) -> Solution:
    """Plan with ``spec.method``, verify by propagation, and (``scp_arcs``) certify against ``lcvx``.

    ``planner`` is unused (the family hook's signature: this family plans no other problem file).

    ``scp_arcs`` with the ``lcvx`` solution at hand (``certify``, or ``burns: auto``) starts from its burn
    structure when the numbers of burns agree (:meth:`PhasedArcsProgram.following`): the convex optimum on the grid
    is global, so the arcs then polish it instead of searching from the boundary conditions alone.
    """
    start = time.perf_counter()
    case = build_case(spec)
    disc = spec.discretization
    lcvx = solve_lcvx(case, disc.grid_steps, spec.solver.backend) if (
        spec.method == "lcvx" or spec.certify or disc.auto_burns) else None
    rounds, kkt = [], None
    if spec.method == "lcvx":
        plan = lcvx
    elif lcvx is not None and lcvx.status == "infeasible":
        # the convex relaxation admits every thrust history the arcs could fly: no need to search
        plan = replace(lcvx, message=f"certified by lcvx on {disc.grid_steps} steps: {lcvx.message}",
                       size=planning_setup(spec, lcvx).program.size(), iterations=0)
    else:
        plan, rounds, kkt = _solve_arcs(case, spec, lcvx, log)
    track = propagate_thrust(case, plan.thrust, spec.verification.grid_points, spec.verification.rtol,
                             spec.verification.atol)
    verification = verify_track(case, track, spec.verification) if plan.status in ("converged", "unverified") \
        else None
    certificate = _certificate(plan, lcvx) if spec.method == "scp_arcs" and lcvx is not None else None
    message = plan.message
    if certificate is not None and certificate.lcvx_gap_rel is not None and certificate.lcvx_gap_rel > GAP_TOLERANCE:
        why = (f"{len(plan.burns)} burns where the lcvx optimum has {len(lcvx.burns)}"
               if len(plan.burns) != len(lcvx.burns) else "a local minimum of the arcs")
        message += (f"; {certificate.lcvx_gap_rel:.2%} above the lcvx optimum on {disc.grid_steps} steps "
                    f"({certificate.lcvx_burn_time_s:.6g} s): {why}")
    figures = RendezvousFigures(
        burn_time_s=plan.objective if plan.status == "converged" else None, num_burns=len(plan.burns),
        burn_arcs_s=_arcs(plan.burns), accel_mps2=case.accel, mean_motion_radps=case.mean_motion,
        **_field_values(plan.figures), **(_field_values(certificate) if certificate is not None else {}))
    return make_solution(
        spec, status=plan.status, message=message, started=start, objective=plan.objective,
        iterations=plan.iterations, size=plan.size, verification=verification, history=plan.history,
        nodes=plan.nodes, dense=Trajectory(track.t, state_columns(case.dim, track.states, track.u, case.accel)),
        figures=figures, timing=plan.timing, repair_rounds=rounds, solver=plan.solver or None, kkt=kkt)


def _arcs(burns: tuple[BurnArc, ...]) -> tuple[tuple[float, float], ...]:
    """The burns as ``(start, end)`` pairs, s."""
    return tuple((b.start_s, b.end_s) for b in burns)


def _field_values(figures) -> dict:
    """The fields of a plan's figures or of the certificate, by name (they are fields of RendezvousFigures)."""
    return {f.name: getattr(figures, f.name) for f in fields(figures)}


class ArcsChecker:
    """The family's side of the engine's check-repair loop for ``scp_arcs``.

    ``check`` flies the plan (full thrust along the normalised interpolated direction) with SciPy
    and checks the thrust bound and the final state. ``repair`` refines the mesh when the final
    state misses the target. The engine flies the normalised linear interpolation of the node
    directions, whose error falls as :math:`h^2` (measured: 2.74 m at 12 sub-intervals per burn,
    1.20 m at 19), so the sub-intervals per burn grow by :math:`1.2 (e/e_{tol})^{1/2}` (1.5x to 4x),
    with the last plan interpolated onto the new mesh as the start.
    """

    def __init__(self, case: Rendezvous, settings) -> None:
        self.case, self.settings = case, settings

    def check(self, program: PhasedArcsProgram, x: np.ndarray) -> Check:
        s = self.settings
        track = propagate_thrust(self.case, program.thrust_plan(x), s.grid_points, s.rtol, s.atol)
        return Check(verify_track(self.case, track, s), track)

    def repair(self, program: PhasedArcsProgram, x: np.ndarray, check: Check, attempt: int) -> Repair | None:
        errors, s = check.verification.final_errors, self.settings
        excess = max(errors["final_position_error_m"] / s.final_position_tol_m,
                     errors["final_velocity_error_mps"] / s.final_velocity_tol_mps)
        if excess <= 1.0:
            return None  # the final state is met; a thrust-bound violation is not the mesh's to repair
        old = program.layout.subintervals
        factor = min(max(1.2 * excess**0.5, 1.5), 4.0)
        new = int(np.ceil(old * factor))
        finer, x0 = program.refined(x, new)
        return Repair(finer, x0, f"mesh refined from {old} to {new} sub-intervals per burn "
                                 f"(final-state error {excess:.3g} x tolerance)")


def planning_setup(spec, lcvx: RendezvousPlan | None = None) -> PlanningSetup:
    """The ``scp_arcs`` program of the spec, its SCP settings and the family's checker.

    With the ``lcvx`` plan (solved here when ``burns: auto`` needs it and none is given), ``auto`` takes its
    number of burns (2 if it has none to give) and the program starts from its burn structure when the
    numbers agree.
    """
    case = build_case(spec)
    disc = spec.discretization
    if lcvx is None and disc.auto_burns:
        lcvx = solve_lcvx(case, disc.grid_steps, spec.solver.backend)
    usable = lcvx is not None and lcvx.status == "converged" and lcvx.burns
    burns = (len(lcvx.burns) if usable else DEFAULT_BURNS) if disc.auto_burns else disc.burns
    if usable and len(lcvx.burns) == burns:
        flown = propagate_thrust(case, lcvx.thrust, spec.verification.grid_points, spec.verification.rtol,
                                 spec.verification.atol)
        program = PhasedArcsProgram.following(case, disc.subintervals_per_burn, lcvx.burns, lcvx.thrust,
                                              lambda times: np.column_stack([np.interp(times, flown.t, column)
                                                                             for column in flown.states.T]))
    else:
        program = PhasedArcsProgram(case, burns, disc.subintervals_per_burn)
    return PlanningSetup(program, SCPSettings.from_spec(spec.solver), ArcsChecker(case, spec.verification))


def _solve_arcs(case: Rendezvous, spec, lcvx: RendezvousPlan | None, log) -> tuple[RendezvousPlan, list, object]:
    outcome = planning_setup(spec, lcvx).solve(log)
    program, result = outcome.program, outcome.result
    states, dirs, durations = program.split(result.x)
    times = program.node_times(durations)
    nodes = Trajectory(times, state_columns(case.dim, states, dirs, case.accel))
    burns = program.burn_arcs(result.x)
    figures = ArcsPlanFigures(arc_durations_s=tuple(durations.tolist()),
                              subintervals_per_burn=program.layout.subintervals,
                              planned_direction_norm_min=_interpolated_norm_min(times, dirs, burns))
    plan = RendezvousPlan(outcome.status, outcome.message, result.objective, result.iterations, program.size(),
                          burns, program.thrust_plan(result.x), nodes, result.timing(), figures, result.history,
                          result.solver)
    return plan, outcome.rounds, result.kkt


def _interpolated_norm_min(times: np.ndarray, dirs: np.ndarray, burns: tuple[BurnArc, ...]) -> float:
    """Smallest norm of the linearly interpolated direction on the burns (1 at the nodes)."""
    plan = ThrustPlan.from_nodes(times, dirs, burns, normalize=False)
    samples = [seg.command(t) for seg in plan.segments for t in np.linspace(seg.start, seg.end, 21)]
    return float(min((np.linalg.norm(u) for u in samples), default=1.0))


def _certificate(arcs: RendezvousPlan, lcvx: RendezvousPlan) -> LcvxCertificate:
    """Gap of the ``scp_arcs`` burn time to the ``lcvx`` global optimum on the fixed grid."""
    if lcvx.status != "converged" or arcs.status != "converged":
        return LcvxCertificate(lcvx_status=lcvx.status)
    return LcvxCertificate(lcvx_status=lcvx.status, lcvx_burn_time_s=lcvx.objective,
                           lcvx_gap_rel=(arcs.objective - lcvx.objective) / lcvx.objective,
                           lcvx_burn_arcs_s=_arcs(lcvx.burns))
