"""The check-repair-resolve loop every planned family shares. A converged SCP iterate meets its constraints only where
the program imposes them, so :func:`solve_verified` runs solve, dense check, the repairs the family proposes and a warm
re-solve from the last plan until the check passes or the repair budget is spent. The family (:class:`PlanChecker`)
supplies ``check(program, x)``, its dense verification of the plan ``x``, and ``repair(program, x, check, attempt)``, a
new program (tightened constraints, more check points, a finer mesh) with the plan carried over as its start, or
``None``; every round is recorded (:class:`RepairRound`). Statuses: ``converged`` only when the SCP converged and the
dense check passed; ``unverified`` when the SCP ended ``converged`` or ``unverified`` but the check still fails when the
budget runs out or no repair is left (the worst violations named), when a repaired program ends ``infeasible`` (a
certificate of the repair, not of the problem as stated), or when a plan not proved optimal passes its check (a failing
one is repaired as a converged one is); otherwise the SCP's own status (``infeasible`` with its certificate,
``max_iterations``, ``solver_error``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from convexguid.errors import SolverError
from convexguid.progress import report
from convexguid.scp.engine import Log, SCPAlgorithm
from convexguid.scp.merit import max_violation
from convexguid.scp.problem import NonconvexProgram, SCPSettings
from convexguid.scp.state import IterationState, SCPResult, merge_results
from convexguid.verification import Verification

DEFAULT_REPAIR_BUDGET = 8
"""Repair rounds tried after the first solve before a plan is reported ``unverified``. Margins held between nodes
converge geometrically, not at once: Zhao's dynamic soaring cut its load factor's breach 0.0081 -> 0.0021 ->
0.00066 -> 0.00025 -> 0.0001 in rounds 2 to 6 and verified in round 7 (at 6 it ended ``unverified``)."""


@dataclass(frozen=True)
class Check:
    """A family's dense check of one plan: the verification and whatever the family keeps from it (a track)."""

    verification: Verification
    track: Any = None


@dataclass(frozen=True)
class Repair:
    """What a family proposes after a failed check: a new program, the start carried over, and what changed."""

    program: NonconvexProgram
    x0: np.ndarray
    description: str


class PlanChecker(Protocol):
    """The family's side of the loop."""

    def check(self, program: NonconvexProgram, x: np.ndarray) -> Check: ...
    def repair(self, program: NonconvexProgram, x: np.ndarray, check: Check, attempt: int) -> Repair | None: ...


@dataclass(frozen=True)
class PlanningSetup:
    """Everything the loop needs to plan one problem: the first program, the SCP settings, the family's checker."""

    program: NonconvexProgram
    settings: SCPSettings
    checker: PlanChecker
    budget: int = DEFAULT_REPAIR_BUDGET

    def solve(self, log: Log | None = None) -> VerifiedSolve:
        """:func:`solve_verified` on this setup."""
        return solve_verified(self.program, self.settings, self.checker, log, self.budget)


@dataclass(frozen=True)
class RepairRound:
    """One solve of the loop: what was repaired before it, its own SCP iterations and the figures after it."""

    round: int
    repair: str
    status: str
    iterations: int
    objective: float
    passed: bool
    max_violation: float
    final_state_error: float
    worst: str


@dataclass
class VerifiedSolve:
    """The outcome of :func:`solve_verified`; ``result`` holds every round's iterations and times."""

    program: NonconvexProgram
    result: SCPResult
    check: Check | None
    status: str
    message: str
    rounds: list[RepairRound] = field(default_factory=list)

    @property
    def x(self) -> np.ndarray:
        return self.result.x


def worst_violations(verification: Verification, count: int = 3) -> str:
    """The largest violations of a dense check among the constraints that failed it (``"name worst > bound (by
    excess)"``: six digits of the worst value alone hid an excess of 1e-7 on a bound of -0.4), then the largest
    final-state errors (every state's is judged)."""
    broken = sorted((c for c in verification.checks if c.failed), key=lambda c: -c.violation)[:count]
    parts = [f"{c.name} {c.worst:.6g} {'>' if c.sense == 'max' else '<'} {c.bound:g} (by {c.violation:.2g})"
             for c in broken]
    parts += [f"{k} {v:.3g}" for k, v in sorted(verification.final_errors.items(), key=lambda kv: -kv[1])[:count]]
    return "; ".join(parts + list(verification.remarks))


FOLLOW_VIOLATION = 1e-2
"""Violation (each block in its own unit, a defect in state scales) within which the plan's sizes mean something."""


class PlanFollower:
    """The first solve's stop at its first nearly feasible plan, where a program that estimated its scales may restate
    itself in the scales the plan gives (``rescaled(x)``; docs/engine.md, 'Scales that follow the plan')."""

    def __init__(self, program: NonconvexProgram) -> None:
        self.program, self.asked = program, not hasattr(program, "rescaled")
        self.rescaled: NonconvexProgram | None = None

    def __call__(self, state: IterationState) -> bool:
        """Whether to stop at ``state``: asked once, at the first accepted iterate within :data:`FOLLOW_VIOLATION`."""
        if self.asked or not (state.history and state.history[-1].accepted) or \
                max_violation(state.ev) > FOLLOW_VIOLATION:
            return False
        self.asked, self.rescaled = True, self.program.rescaled(state.x)
        return self.rescaled is not None


def solve_verified(program: NonconvexProgram, settings: SCPSettings, checker: PlanChecker, log: Log | None = None,
                   budget: int = DEFAULT_REPAIR_BUDGET) -> VerifiedSolve:
    """Solve, check densely, repair and re-solve warm until verified or ``budget`` repairs are spent."""
    follower = PlanFollower(program)
    result = last = SCPAlgorithm(program, settings, log).run(until=follower)
    what = "first solve"
    if follower.rescaled is not None:  # the same plan, measured in the scales its size gives (warm, as a repair)
        program = follower.rescaled
        what = (f"first solve, restated after {result.iterations} iterations with its scales following the plan "
                f"({getattr(program, 'scales_followed', '')})")
        last = SCPAlgorithm(program, settings, log).run(result.x, penalty=result.penalty)
        result = merge_results(result, last)
    rounds: list[RepairRound] = []

    def ended(status: str, message: str, check: Check | None) -> VerifiedSolve:
        return VerifiedSolve(program, result, check, status, message, rounds)

    for attempt in range(budget + 1):
        report("dense check, round", attempt + 1)
        try:
            check = checker.check(program, result.x)
        except SolverError as error:
            if result.status in ("converged", "unverified"):  # a plan the dense check cannot judge is not verified
                return ended("unverified", f"{result.message}; not verified: {error}", None)
            # the last iterate of a failed solve may not even propagate; its status says why
            return ended(result.status, result.message, None)
        v = check.verification
        rounds.append(RepairRound(attempt, what, result.status, last.iterations, result.objective, v.passed,
                                  v.max_violation, v.final_state_error, worst_violations(v)))
        if result.status == "infeasible" and attempt > 0:  # a certificate of the repaired program
            return ended("unverified", f"after the repair '{what}' the SCP found no feasible point "
                                       f"({result.message}); the problem as stated is not proved infeasible", check)
        if result.status not in ("converged", "unverified"):
            # infeasible, max_iterations, solver_error: the check of the last iterate is reported, not repaired
            return ended(result.status, result.message, check)
        if result.status == "unverified" and (v.passed or result.max_violation > settings.feasibility_tolerance):
            # a feasible plan not proved optimal, or a stall short of feasibility: nothing a repair could mend
            return ended("unverified", result.message, check)
        if v.passed:
            rounds_text = f"{attempt} repair round{'s' if attempt > 1 else ''}"
            message = result.message if attempt == 0 else f"{result.message}; verified after {rounds_text}" + \
                repair_cost(rounds[0].objective, result.objective)
            # the remarks: how the plan was judged, when not as usual
            return ended("converged", "; ".join([message, *v.remarks]), check)
        repair = checker.repair(program, result.x, check, attempt) if attempt < budget else None
        if repair is None:
            why = "repair budget spent" if attempt == budget else "no repair left to try"
            return ended("unverified", f"the dense check fails after {attempt} repair rounds ({why}): "
                                       f"{worst_violations(v)}", check)
        program, what = repair.program, repair.description
        # warm: the plan and the penalty weight carry over (the repaired program's multipliers are much the same)
        last = SCPAlgorithm(program, settings, log).run(repair.x0, penalty=result.penalty)
        result = merge_results(result, last)
    raise AssertionError("unreachable: the loop returns on its last round")


def repair_cost(planned: float, verified: float) -> str:
    """What the repairs cost the objective, when it is more than 0.1% of the first solve's (a margin held between
    the nodes, a refined grid): the verified plan is optimal for the repaired program, which the user should know."""
    change = verified - planned
    if not abs(change) > 1e-3 * max(abs(planned), 1e-12):
        return ""
    return (f" (the objective went from {planned:.8g}, the first solve's plan that broke the check, to "
            f"{verified:.8g}: {change / abs(planned):+.2%})")


def grown_margin(excess: float, attempt: int, floor: float) -> float:
    """How much to tighten a bound whose dense check saw ``excess`` beyond it, in round ``attempt``: the margin starts
    at the excess plus ``floor`` and grows by half the excess each round that did not clear it, so a repair that
    undershoots converges instead of repeating."""
    return excess * (1.0 + 0.5 * attempt) + floor * (1 + attempt)
