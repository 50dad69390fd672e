"""The dense check of a user's plan: the planned control re-propagated through the user's dynamics with SciPy.

The control is what the transcription holds between nodes (Hermite-Simpson's quadratic through node, midpoint and
node; a zero- or first-order hold), held within the control's bounds (what the actuator can deliver).
:func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-10) integrates the dynamics interval by interval from the given
initial state; on a grid of ``points`` samples per interval the path constraints and the state bounds are
evaluated (a path equality in its magnitude), and at the end the propagated state is compared with the stated
final values (scaled by each state's scale). A broken path constraint or state bound is repaired by tightening it
on the intervals where it broke (:func:`~convexguid.scp.check_repair.grown_margin`) and re-solving warm. An error
the grid makes (a final-state error, a violation the tightening stopped reducing, a broken path equality) is
repaired by refining it: a Hermite-Simpson program splits the intervals whose local error exceeds its tolerance,
where the dense check broke a constraint and where a control chatters (:mod:`convexguid.ocp.mesh`, Betts 2010,
Sec. 4.7); the others double every interval.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from convexguid.ocp.boundary import boundary_errors
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.ocp.mesh import (
    JUMP_SHARE,
    LOCAL_ERROR_TOLERANCE,
    control_jumps,
    fly,
    held_control,
    interval_errors,
    interval_flows,
    plan_refinement,
    refined_program,
    state_names,
)
from convexguid.ocp.parts import Margins, NumericFunction
from convexguid.ocp.pinned import broken_beside_end, net_of_final_miss, netted_remarks, with_rate_conditions
from convexguid.ocp.transcription import Transcription
from convexguid.scp.check_repair import Check, Repair, grown_margin
from convexguid.verification import ConstraintCheck, Verification

FINAL_TOLERANCE = 1e-4
"""Largest final-state error, as a share of each state's scale, of a verified plan."""

PATH_TOLERANCE = 1e-6
"""Largest excess over a path constraint or a state bound on the dense grid (the constraint's own unit)."""

EQUALITY_TOLERANCE = FINAL_TOLERANCE
"""Largest error of a path equality on the dense grid, in its magnitude: an equality cannot be held with a margin,
so between nodes it drifts as the final state does, and is judged as the final state is."""

NEAR_BREAKING = 0.1
"""A repair that tightens a constraint tightens it on every interval where the dense check found it broken or
within this share of the tolerance of breaking (:data:`PATH_TOLERANCE`)."""

MARGIN_FLOOR = 1e-6
"""Smallest tightening a repair adds to the path constraints."""

MAX_INTERVALS = 400
"""A refinement makes at most this many intervals (the transcription's error, not the constraints, is the cause)."""

AMPLIFIED = 1e3
"""A flight from the initial state that misses the final state by more than this many times the sum of the
intervals' local errors shows dynamics that amplify errors: the plan is judged interval by interval instead
(:meth:`DenseChecker.flown`)."""

CARRIED_FINAL_ERROR = 0.1
"""A chattering plan is carried onto its regularized program (controls linear between nodes) when its flight misses
the final state by at most this share of each state's scale, else that program starts from its first guess.
Measured at the first check, quadratic controls: COPS' hanging chain 0.065, Betts' shuttle 0.023 and COPS' Goddard
rocket 4.5e-5, each converging from its carried nodes (the shuttle in 173 iterations, 246 from the first guess);
COPS' hang glider 1.03, whose carried nodes ended ``max_iterations`` (from its first guess: converged)."""


@dataclass(frozen=True)
class DenseTrack:
    """The re-propagated trajectory: times, states ``(n, nx)``, controls ``(n, nu)``."""

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray


def jumping_controls(program: Transcription, z: np.ndarray) -> tuple[str, ...]:
    """Remarks on the controls that move by most of their range (:data:`~convexguid.ocp.mesh.JUMP_SHARE`) between
    two neighbouring values in time: a transcription's optimum that chatters between node and midpoint values (COPS'
    hang glider on a coarse Hermite-Simpson grid) satisfies the collocation equations but not the dynamics flown
    between them."""
    jumps = control_jumps(program, z)[1]
    return tuple(f"control {v.name} moves by more than {JUMP_SHARE:.0%} of its range between neighbouring values "
                 f"{int(jumps[:, j].sum())} times (a plan that chatters between collocation points)"
                 for j, v in enumerate(program.problem.controls) if jumps[:, j].any())


class DenseChecker:
    """:class:`~convexguid.scp.check_repair.PlanChecker` of a :class:`Transcription`."""

    def __init__(self, points: int = 20) -> None:
        self.points = points

    def control(self, program: Transcription, z: np.ndarray):
        """The planned control as flown (:func:`~convexguid.ocp.mesh.held_control`: within its bounds)."""
        return held_control(program, z)

    def propagate(self, program: Transcription, z: np.ndarray) -> DenseTrack:
        rate = NumericFunction(program.rate)
        u = self.control(program, z)
        node_times = program.final_time(z) * program.node_shares()
        state = program.states(z)[0].copy()
        names = state_names(program)
        times, states = [], []
        for k in range(program.N):
            grid = np.linspace(node_times[k], node_times[k + 1], self.points + 1)
            run = fly(rate, u, (grid[0], grid[-1]), state, names, t_eval=grid, atol=1e-12)
            keep = slice(None) if k == 0 else slice(1, None)
            times.append(run.t[keep])
            states.append(run.y.T[keep])
            state = run.y[:, -1]
        return self._track(program, u, times, states)

    def propagate_from_nodes(self, program: Transcription, z: np.ndarray, flows: list) -> DenseTrack:
        """The plan flown interval by interval, each interval from its own planned start node (``flows``, from
        :func:`~convexguid.ocp.mesh.interval_flows`), sampled on the same grid as :meth:`propagate`."""
        node_times = program.final_time(z) * program.node_shares()
        grids = [np.linspace(node_times[k], node_times[k + 1], self.points + 1)[0 if k == 0 else 1:]
                 for k in range(program.N)]
        return self._track(program, self.control(program, z), grids,
                           [flow.sol(grid).T for flow, grid in zip(flows, grids, strict=True)])

    @staticmethod
    def _track(program: Transcription, u, times: list[np.ndarray], states: list[np.ndarray]) -> DenseTrack:
        """The pieces of a flight, one after the other, with the control ``u`` at their instants."""
        t = np.concatenate(times)
        return DenseTrack(t, np.vstack(states), np.array([u(s) for s in t]).reshape(t.size, program.nu))

    def flown(self, program: Transcription, z: np.ndarray) -> tuple[DenseTrack, tuple[str, ...]]:
        """The track the plan is judged on, and a remark when it is not the flight from the initial state.

        The plan is flown from its initial state. If that flight misses the final state by more than
        :data:`AMPLIFIED` times the sum of the intervals' local errors (each interval flown from its own node),
        the miss is the dynamics' amplification of errors no grid removes (an unstable mode: Betts' alp rider grows
        as :math:`e^{2t}`, :math:`e^{40}` over its horizon, so its IPOPT optimum flown open loop misses by 1e14
        scales); the plan is then judged on the flight interval by interval from its nodes (Betts 2010, Sec. 4.7),
        and the remark says so."""
        track, planned = self.propagate(program, z), program.states(z)[-1]
        miss = max(self._final_errors(program, track, planned).values(), default=0.0)
        if not miss > FINAL_TOLERANCE:
            return track, ()
        # what the plan's own last node misses is no error of the flight (a plan that breaks a final condition)
        last_node = DenseTrack(np.array([program.final_time(z)]), planned[None, :], np.zeros((1, 0)))
        amplified = miss - max(self._final_errors(program, last_node, planned).values(), default=0.0)
        flows = interval_flows(program, z, self.control(program, z))
        local = float(np.sum(interval_errors(program, z, flows)))
        if not amplified > AMPLIFIED * local:
            return track, ()
        return self.propagate_from_nodes(program, z, flows), (
            f"flown interval by interval from the plan's nodes: from the initial state the open-loop flight misses "
            f"the final state by {miss:.3g} of the scales, {amplified / max(local, 1e-300):.3g} times the sum of the "
            "intervals' local errors beyond the plan's own miss (the dynamics amplify them)",)

    @staticmethod
    def _final_errors(program: Transcription, track: DenseTrack, planned: np.ndarray) -> dict[str, float]:
        """Each state's final error on the track's last state (in its scale): against its stated final value, or
        where none is stated against the plan's last node ``planned``; and each nonlinear boundary condition's. The
        flight must end where the plan says: a cost on the free final states (a terminal cost, an integral's own
        state) is then the one flown (docs/ocp.md, 'What the engine does with it')."""
        errors = {f"final_{v.name}_error": abs(float(track.x[-1, i]) - (planned[i] if v.final is None else v.final))
                  / program.state_scales[i] for i, v in enumerate(program.problem.states)}
        return errors | boundary_errors(program, track.x, float(track.t[-1]))

    def check(self, program: Transcription, z: np.ndarray) -> Check:
        p = program.problem
        track, flight = self.flown(program, z)
        units = self._judging_units(program, track)  # judged in each constraint's divided unit, reported in its own
        stated = self._stated_excess(program, track, units)
        excess = net_of_final_miss(program, track, stated)
        held = {key: not np.any(e > self._tolerance(p, key)) for key, e in excess.items()}
        broken = not all(held.values())
        checks = [ConstraintCheck(c.name, float(excess[("path", j)].max()) * units[j], 0.0, "max", held[("path", j)])
                  for j, c in enumerate(p.constraints) if c.judged]
        for i, v in enumerate(p.states):
            if v.upper is not None:
                checks.append(ConstraintCheck(f"{v.name}_max", float(track.x[:, i].max()), v.upper, "max",
                                              held[("bound", (i, True))]))
            if v.lower is not None:
                checks.append(ConstraintCheck(f"{v.name}_min", float(track.x[:, i].min()), v.lower, "min",
                                              held[("bound", (i, False))]))
        final_errors = self._final_errors(program, track, program.states(z)[-1])
        worst_final = max(final_errors.values(), default=0.0)
        passed = worst_final <= FINAL_TOLERANCE and not broken
        tolerances = {"final_state": FINAL_TOLERANCE, "path": PATH_TOLERANCE, "path_equality": EQUALITY_TOLERANCE}
        if p.mesh_tolerance is not None:  # the accuracy the statement asks of every interval
            local = float(np.max(interval_errors(program, z)))
            checks.append(ConstraintCheck("local_error", local, p.mesh_tolerance, "max"))
            tolerances["local_error"] = p.mesh_tolerance
            passed = passed and local <= p.mesh_tolerance
        remarks = flight + netted_remarks(program, stated, excess, PATH_TOLERANCE)
        verification = Verification(track.t.size, tuple(checks), worst_final, final_errors, passed, tolerances,
                                    remarks + (() if passed else jumping_controls(program, z)))
        return Check(verification, track)

    def repair(self, program: Transcription, z: np.ndarray, check: Check, attempt: int) -> Repair | None:
        """Where the flight broke a state's bound beside an end where the state is stated on it, first add that
        end's rate condition (:mod:`convexguid.ocp.pinned`: no margin moves a fixed end node); then
        :meth:`tighten_or_refine`."""
        excess = self._excess(program, check.track)
        ends = broken_beside_end(program, check.track.t, excess, PATH_TOLERANCE)
        if not ends:
            return self.tighten_or_refine(program, z, check, attempt, excess)
        held = with_rate_conditions(program, ends)
        note = (f"{', '.join(e.name(program.problem) for e in ends)} added (the flight crossed a bound beside an end "
                "where the plan sits on it: the rate there must point into the bounds)")
        # the conditions added are not judged densely: the excess of the program before them is the held one's
        rest = self.tighten_or_refine(held, z, check, attempt, excess)
        return Repair(held, z, note) if rest is None else Repair(rest.program, rest.x0, f"{note}; {rest.description}")

    def tighten_or_refine(self, program: Transcription, z: np.ndarray, check: Check, attempt: int,
                          excess_by_name: dict[tuple, np.ndarray]) -> Repair | None:
        """Tighten each path constraint and state bound broken between nodes on the intervals where it broke: at
        their two nodes and midpoint, by the worst excess there (grown each round, never at a node whose values
        are all fixed: there nothing can move). With nothing broken between nodes (a final-state error), when the
        last tightening left the worst violation above 90% of what it was, or for a broken path equality, the grid
        is refined instead (:meth:`refine`; None past :data:`MAX_INTERVALS`: the plan is ``unverified`` at once
        instead of after the whole repair budget)."""
        p, track = program.problem, check.track
        worst_now = max((float(e.max()) for key, e in excess_by_name.items()
                         if self._tolerance(p, key) == PATH_TOLERANCE), default=0.0)
        if (worst_now <= PATH_TOLERANCE or worst_now >= 0.9 * program.margins.violation
                or check.verification.final_state_error > FINAL_TOLERANCE):
            # nothing broken between nodes, the last tightening did not reduce it, or the flight misses the final
            # state (no margin mends that): the grid is too coarse (a refinement also splits where it broke)
            return self.refine(program, z, check)
        N = program.N
        node_times = program.final_time(z) * program.node_shares()
        interval = np.clip(np.searchsorted(node_times, track.t, side="right") - 1, 0, N - 1)
        # this round's margins, row by row: a node shared by two broken intervals takes the larger, not their sum
        # (a sum tightens every node twice as much as the midpoints beside it, and the plan zigzags between them)
        path, bounds, cone = (np.zeros_like(m) for m in (program.margins.path, program.margins.bounds,
                                                         program.margins.cone))
        nx = program.nx
        pinned = {0: all(v.initial is not None for v in p.states), N: all(v.final is not None for v in p.states)}
        broken_equality = False
        # each state bound's row between the nodes of each interval, where the transcription holds one
        between = {(i, p.constraints[j].holds_bound): (r, j) for r, (point, i, j) in enumerate(program.path_rows)
                   if point == "mid" and p.constraints[j].holds_bound is not None}
        for name, excess in excess_by_name.items():
            if name[0] == "path" and p.constraints[name[1]].equality:
                broken_equality |= bool(np.any(excess > EQUALITY_TOLERANCE))
                continue  # an equality cannot be tightened: only a finer grid helps
            for k in np.unique(interval[excess > NEAR_BREAKING * PATH_TOLERANCE]):
                worst = float(excess[interval == k].max())
                margin = grown_margin(worst, attempt, MARGIN_FLOOR)
                kind, index = name
                if kind == "path":
                    # the constraint's rows on this interval: its two nodes (unless all fixed) and its midpoint
                    stated_cone = p.constraints[index].cone is not None
                    table, target = (program.cone_rows, cone) if stated_cone else (program.path_rows, path)
                    rows = [r for r, (point, i, j) in enumerate(table) if j == index and (
                        (point in ("mid", "sample") and i == k) or (point == "node" and i in (k, k + 1)
                                                                   and not pinned.get(i)))]
                    target[rows] = np.maximum(target[rows], margin)
                else:
                    state, upper = index
                    fixed = {0: p.states[state].initial is not None, N: p.states[state].final is not None}
                    nodes = [node for node in (k, k + 1) if not fixed.get(node)]
                    entries = [node * nx + state for node in nodes]
                    bounds[entries] = np.maximum(bounds[entries], margin)
                    if (k, index) in between:  # and its row between the nodes, in that row's divided unit
                        r, j = between[(k, index)]
                        path[r] = max(path[r], margin / program.path_divisors[j])
        old = program.margins
        if not any(np.any(added > 0) for added in (path, bounds, cone)):
            # nothing to tighten: a broken path equality asks for a finer grid; anything else stays broken
            return self.refine(program, z, check) if broken_equality else None
        path, bounds, cone = old.path + path, old.bounds + bounds, old.cone + cone
        largest = max(path.max(initial=0.0), bounds.max(initial=0.0), cone.max(initial=0.0))
        return Repair(program.with_margins(Margins(path, bounds, worst_now, cone)), z,
                      f"path constraints and state bounds tightened where the dense check broke them (largest "
                      f"margin {largest:.3g})")

    def refine(self, program: Transcription, z: np.ndarray, check: Check) -> Repair | None:
        """A finer grid with the plan carried over, at most :data:`MAX_INTERVALS` intervals; None when none fits.
        Hermite-Simpson splits where the error is (:func:`~convexguid.ocp.mesh.plan_refinement`: the local error,
        the constraints the dense check broke, a chattering control); the other transcriptions double every
        interval."""
        if isinstance(program, HermiteSimpsonProgram):
            jumps = 0 if program.linear_control else int(control_jumps(program, z)[1].sum())
            if jumps:
                # a plan whose flight misses its final state by a large share of the scales has the chatter's states,
                # not the dynamics': the regularized program starts from its own first guess instead
                carry = check.verification.final_state_error <= CARRIED_FINAL_ERROR
                linear, start = program.with_linear_control(z, carry)
                return Repair(linear, start, f"the controls held linear between node values on the same grid (the "
                                             f"plan failed its check with {jumps} jumps of a control by more than "
                                             f"{JUMP_SHARE:.0%} of its range between neighbouring values: an "
                                             "optimum of the collocation that chatters), started "
                                             + ("from the plan's nodes" if carry else "from the first guess"))
            tolerance = min(LOCAL_ERROR_TOLERANCE, program.problem.mesh_tolerance or LOCAL_ERROR_TOLERANCE)
            plan = plan_refinement(program, z, self._broken_intervals(program, check), MAX_INTERVALS, tolerance)
            if plan is None:
                return None
            fine, start = refined_program(program, z, plan)
            return Repair(fine, start, plan.description)
        if 2 * program.N > MAX_INTERVALS:
            return None
        fine, start = program.refined(z)
        return Repair(fine, start, f"intervals doubled to {fine.N} (the dense check's errors are the grid's)")

    def _broken_intervals(self, program: Transcription, check: Check) -> np.ndarray:
        """Whether the dense check saw a path constraint or a state bound broken on each interval, shape ``(N,)``."""
        track = check.track
        interval = np.clip(np.searchsorted(track.t[-1] * program.node_shares(), track.t, side="right") - 1, 0,
                           program.N - 1)
        broken = np.zeros(program.N, dtype=bool)
        for key, excess in self._excess(program, track).items():
            broken[interval[excess > self._tolerance(program.problem, key)]] = True
        return broken

    @staticmethod
    def _tolerance(problem, key: tuple) -> float:
        """The tolerance of one entry of :meth:`_excess`: a path equality's, or a constraint's and a bound's."""
        return EQUALITY_TOLERANCE if key[0] == "path" and problem.constraints[key[1]].equality else PATH_TOLERANCE

    @staticmethod
    def _equality_magnitudes(program: Transcription, track: DenseTrack) -> dict[int, float]:
        """Each path equality's magnitude on the flown track (by constraint index): the largest change of its value
        when every state and control moves by its own scale. A path equality is judged in it, as the defects are in
        the states' scales: the singular arc of Goddard's rocket, a balance of forces near 100 lbf, drifts by 1e-5
        lbf between nodes however fine the grid."""
        if program.equality_magnitudes is None:
            return {}
        reach = NumericFunction(program.equality_magnitudes)
        largest = np.max([reach(x, u, t) for t, x, u in zip(track.t, track.x, track.u, strict=True)], axis=0)
        indices = [j for j, c in enumerate(program.problem.constraints) if c.equality]
        return {j: float(m) if m > 0 else 1.0 for j, m in zip(indices, largest, strict=True)}

    @staticmethod
    def _judging_units(program: Transcription, track: DenseTrack) -> list[float]:
        """What each path constraint's excess is divided by to be judged (an equality's magnitude on the track, an
        inequality's divisor: 'Units of a constraint' in docs/ocp.md), in its stated unit."""
        magnitude = DenseChecker._equality_magnitudes(program, track)
        return [magnitude[j] if c.equality else float(program.path_divisors[j])
                for j, c in enumerate(program.problem.constraints)]

    @staticmethod
    def _excess(program: Transcription, track: DenseTrack) -> dict[tuple, np.ndarray]:
        """:meth:`_stated_excess`, judged on the last interval net of the flight's miss of the stated final values
        where the plan ends on a bound or a path constraint (:func:`~convexguid.ocp.pinned.net_of_final_miss`)."""
        return net_of_final_miss(program, track, DenseChecker._stated_excess(program, track))

    @staticmethod
    def _stated_excess(program: Transcription, track: DenseTrack,
                       units: list[float] | None = None) -> dict[tuple, np.ndarray]:
        """Each path constraint's and state bound's excess on the dense grid, by ``("path", j)`` or
        ``("bound", (state, is_upper))``; a constraint imposed over part of the maneuver (or at one node) is
        ``-inf`` on the samples outside it; ``units``: :meth:`_judging_units` on this track, if already known."""
        p = program.problem
        out: dict[tuple, np.ndarray] = {}
        if program.constraint_values is not None:
            g = NumericFunction(program.constraint_values)
            values = np.array([g(x, u, t) for t, x, u in zip(track.t, track.x, track.u, strict=True)])
            share = track.t / track.t[-1]
            units = DenseChecker._judging_units(program, track) if units is None else units
            nearest_node = np.min(np.abs(share[:, None] - program.node_shares()[None, :]), axis=1) < 1e-9
            for j, c in enumerate(p.constraints):
                inside = (nearest_node & (np.abs(share - c.at) < 1e-9) if c.at is not None
                          else (share >= c.during[0] - 1e-12) & (share <= c.during[1] + 1e-12))
                excess = (np.abs(values[:, j]) if c.equality else values[:, j]) / units[j]
                out[("path", j)] = np.where(inside & c.judged, excess, -np.inf)
        for i, v in enumerate(p.states):
            if v.upper is not None:
                out[("bound", (i, True))] = track.x[:, i] - v.upper
            if v.lower is not None:
                out[("bound", (i, False))] = v.lower - track.x[:, i]
        return out
