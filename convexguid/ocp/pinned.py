"""States stated on one of their own bounds at an end of the maneuver: a glider that takes off from and lands on the
ground (``h(0) = h(tf) = 0`` with ``h >= 0``), a propellant burned down to its floor.

Such a state touches its bound at that end, and two things follow that the nodes alone do not say.

- Its rate there must point into the bounds (``h' >= 0`` at the start, ``h' <= 0`` at the end): otherwise the
  trajectory crosses the bound just beside the end. A collocation imposes bounds at the nodes only, so its optimum
  may take off or land with the rate pointing outward and cross the bound between the last two nodes; no margin
  mends that, since the end node itself is fixed on the bound. When the dense check finds the bound broken on the
  interval beside such an end, the repair adds the rate condition at that node (:func:`with_rate_conditions`), a
  condition every trajectory of the stated problem meets, so the problem is not changed.
- The dense check flies the plan from its first node, and the flight ends within the final-state tolerance of the
  stated final value, not on it: on the last interval, a bound the state is pinned on at the final end is judged net
  of that miss (:func:`net_of_final_miss`), as the final value itself is. So is a path constraint the flight's end,
  moved onto the stated final values, sits on: PSOPT's missile holds an altitude floor, h >= 0 near the target, and
  lands on h(tf) = 0; its flight's final miss of 2.2e-3 m (1.2e-6 of the scale) broke the floor by exactly that, and
  nine repair rounds could not mend it.

Measured on Zhao's dynamic soaring (Optimal Control Applications and Methods 25, 2004; the GPOPS-II statement, 40
Hermite-Simpson intervals, a straight-line guess): the plan landed with ``h' = +2.3 ft/s`` and crossed ``h >= 0``
by 3.7 ft between its last two nodes; six rounds of margins left 0.034 ft (the airspeed then guessed at 0), and
the flight's own final miss was 0.002 ft.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from convexguid.ocp.declarations import PathConstraint
from convexguid.ocp.parts import Margins, NumericFunction
from convexguid.ocp.transcription import Transcription

if TYPE_CHECKING:  # the dense check imports this module
    from convexguid.ocp.check import DenseTrack


@dataclass(frozen=True)
class PinnedEnd:
    """State ``state`` (its index) is stated on its ``upper`` (else lower) bound at the ``final`` (else initial) end."""

    state: int
    final: bool
    upper: bool

    def name(self, problem) -> str:
        """The name of this end's rate condition."""
        return f"{problem.states[self.state].name}_rate_{'final' if self.final else 'initial'}"


def pinned_ends(problem) -> list[PinnedEnd]:
    """Every (state, end, bound) where a state's stated boundary value is one of its bounds."""
    ends = []
    for i, v in enumerate(problem.states):
        for final, value in ((False, v.initial), (True, v.final)):
            for upper, bound in ((False, v.lower), (True, v.upper)):
                if value is not None and bound is not None and abs(value - bound) <= 1e-12 * max(1.0, abs(bound)):
                    ends.append(PinnedEnd(i, final, upper))
    return ends


def end_samples(program: Transcription, t: np.ndarray, final: bool) -> np.ndarray:
    """Which of the instants ``t`` lie on the first (``final`` False) or the last interval."""
    shares = program.node_shares()
    return t >= t[-1] * shares[-2] if final else t <= t[-1] * shares[1]


SITS_ON = 1e-6
"""A path inequality within this of its bound (its own unit) at the flight's end, moved onto the stated final values,
sits on it there (the dense check's path tolerance)."""


def net_of_final_miss(program: Transcription, track: DenseTrack,
                      excess: dict[tuple, np.ndarray]) -> dict[tuple, np.ndarray]:
    """``excess`` (by key ``("bound", (state, upper))`` and ``("path", j)``) judged on the last interval net of the
    flight's miss of the stated final values (``track.x[-1]`` against them): each bound a state is pinned on at the
    final end by that state's miss, and each judged path inequality the flight's end moved onto the stated values
    sits on (within :data:`SITS_ON` in its unit) by what the miss adds to it there."""
    out, last = dict(excess), end_samples(program, track.t, True)
    stated = [(i, v.final) for i, v in enumerate(program.problem.states) if v.final is not None]
    for end in pinned_ends(program.problem):
        key = ("bound", (end.state, end.upper))
        if end.final and key in out:
            miss = abs(float(track.x[-1, end.state]) - program.problem.states[end.state].final)
            out[key] = np.where(last, out[key] - miss, out[key])
    if program.constraint_values is None or not stated:
        return out
    g = NumericFunction(program.constraint_values)
    on_target = track.x[-1].copy()
    on_target[[i for i, _ in stated]] = [value for _, value in stated]
    flown, aimed = (g(x, track.u[-1], track.t[-1]) / program.path_divisors for x in (track.x[-1], on_target))
    for j, c in enumerate(program.problem.constraints):
        if c.judged and not c.equality and aimed[j] >= -SITS_ON and flown[j] > aimed[j]:
            out[("path", j)] = np.where(last, out[("path", j)] - (flown[j] - aimed[j]), out[("path", j)])
    return out


def broken_beside_end(program: Transcription, t: np.ndarray, excess: dict[tuple, np.ndarray],
                      tolerance: float) -> list[PinnedEnd]:
    """The pinned ends whose bound the flight broke on the interval beside them (beyond ``tolerance``) and whose
    rate condition the program does not hold yet."""
    held = {c.name for c in program.problem.constraints}
    return [end for end in pinned_ends(program.problem)
            if end.name(program.problem) not in held
            and np.any(excess[("bound", (end.state, end.upper))][end_samples(program, t, end.final)] > tolerance)]


def with_rate_conditions(program: Transcription, ends: list[PinnedEnd]) -> Transcription:
    """The program on the same grid with each end's rate condition added (a point constraint at its node: the rate
    into the bounds), the repair margins carried row by row."""
    problem = copy.copy(program.problem)
    rates = problem.rate_vector()
    added = []
    for end in ends:
        inward = 1.0 if end.final != end.upper else -1.0  # landing on a lower bound: the rate at most 0
        unit = problem.states[end.state].unit
        added.append(PathConstraint(end.name(problem), inward * rates[end.state], f"{unit}/s" if unit else "",
                                    at=1.0 if end.final else 0.0, at_midpoints=False, judged=False))
    problem.constraints = [*problem.constraints, *added]
    fresh = program.restated(problem)
    old = dict(zip(program.path_rows, program.margins.path, strict=True))
    path = np.array([old.get(row, 0.0) for row in fresh.path_rows])
    return fresh.with_margins(Margins(path, program.margins.bounds, program.margins.violation, program.margins.cone))


def netted_remarks(program: Transcription, stated: dict[tuple, np.ndarray], net: dict[tuple, np.ndarray],
                   tolerance: float) -> tuple[str, ...]:
    """A remark for each bound and path constraint the flight broke beyond ``tolerance`` as stated but not net of its
    final miss (:func:`net_of_final_miss`)."""
    remarks = []
    for key in stated:
        if key in net and np.max(stated[key]) > tolerance >= np.max(net[key]):
            if key[0] == "bound":
                v = program.problem.states[key[1][0]]
                name, missed, why = (f"{v.name}_{'max' if key[1][1] else 'min'}", f"the final {v.name}",
                                     f"where {v.name} is stated on that bound")
            else:
                name, missed, why = (program.problem.constraints[key[1]].name, "the stated final values",
                                     "where the plan ends on it")
            remarks.append(f"{name} judged on the last interval net of the flight's miss of {missed} (within the "
                           f"final-state tolerance), {why}: the flight breaks it by {np.max(stated[key]):.3g}")
    return tuple(remarks)
