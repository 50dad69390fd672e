"""What the SCP loop carries from one iteration to the next, and what it hands back. :class:`IterationState` is the
whole state of :class:`~convexguid.scp.engine.SCPAlgorithm`: a step reads it and returns it updated, so a run can be
inspected, logged or resumed between any two iterations.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from convexguid.scp.lagrangian import Multipliers, WorkingSet
from convexguid.scp.optimality import KKTResiduals
from convexguid.scp.policies import Funnel
from convexguid.scp.problem import Evaluation


@dataclass(frozen=True)
class IterationRecord:
    """One row of the iteration table."""

    iteration: int
    objective: float
    violation: float
    step: float
    trust_radius: float
    ratio: float
    accepted: bool
    solver_status: str
    solver_iterations: int
    time_s: float
    penalty: float = float("nan")
    """The exact penalty's weight the step was judged with (phase 1 weighs the violation alone, by 1)."""


@dataclass
class IterationState:
    """The state of one SCP run between two steps: ``raw`` is the program's own evaluation at ``x`` (with Jacobians),
    ``ev`` the merit's (see ``SCPAlgorithm._evaluate``); ``status`` stays ``None`` while the run goes on."""

    x: np.ndarray
    raw: Evaluation
    ev: Evaluation
    objective: float
    merit: float
    radius: float
    penalty: float
    started: float
    multipliers: Multipliers | None = None
    augmented: bool = False
    """The multipliers are the curved subproblem's, which leaves part of each working row's to its augmentation
    (:mod:`convexguid.scp.curved`): they understate the weight the penalty needs."""
    kkt: KKTResiduals | None = None
    funnel: Funnel | None = None
    """The funnel on the violation (:class:`~convexguid.scp.policies.FunnelPolicy`), None without one."""
    newton_radius: float = np.inf
    newton_earned: float = 0.0
    """The whole length of the last Newton step cut and predicted well: Newton's until one of its steps fails, however
    the refused first-order steps between shrink their own region (docs/engine.md, 'Newton end game')."""
    working_set: WorkingSet | None = None
    escapes: int = 0
    polish: int = 0
    kept: int = 0
    """Accepted steps in a row inside the trust region that kept the violation (the penalty's steering)."""
    pinned: int = 0
    """Linear subproblems in a row whose step reached the trust region (the model lacks the curvature to stop it) or
    whose merit fell far more than predicted (its curvature is more than the problem's): the model is wrong."""
    curved_refused_at: np.ndarray | None = None
    """The iterate where a curved step inside its trust region was refused: the same QP there gives it again."""
    reopened_at: np.ndarray | None = None
    """The iterate where the polish last opened a collapsed trust region again (:meth:`SCPAlgorithm._stalled`)."""
    escape_log: list[str] = field(default_factory=list)
    iteration: int = 0
    failures: int = 0
    phase1_runs: int = 0
    history: list[IterationRecord] = field(default_factory=list)
    status: str | None = None
    message: str = ""
    convexify_time_s: float = 0.0
    solver_time_s: float = 0.0

    @property
    def finished(self) -> bool:
        return self.status is not None

    def finish(self, status: str, message: str) -> None:
        self.status, self.message = status, message


@dataclass
class SCPResult:
    """Outcome of :func:`~convexguid.scp.engine.solve_scp`."""

    x: np.ndarray
    status: str
    objective: float
    max_violation: float
    violations: dict[str, float]
    iterations: int
    history: list[IterationRecord] = field(default_factory=list)
    message: str = ""
    wall_time_s: float = 0.0
    convexify_time_s: float = 0.0
    solver_time_s: float = 0.0
    solver: str = ""
    """The backend that solved the subproblems, resolved (e.g. ``auto -> daqp (condensed)``)."""
    kkt: dict | None = None
    """The KKT residuals at ``x`` (:meth:`~convexguid.scp.optimality.KKTResiduals.summary`), None if never measured."""
    notes: tuple[str, ...] = ()
    """What the run did besides its iterations (e.g. a step off a saddle)."""
    penalty: float | None = None
    """The penalty weight the run ended with (a warm restart may start from it)."""

    @property
    def overhead_time_s(self) -> float:
        return max(0.0, self.wall_time_s - self.convexify_time_s - self.solver_time_s)

    def timing(self) -> dict[str, float]:
        """The time split reported in a solution's summary (``timing``), s."""
        return {"scp_s": self.wall_time_s, "convexify_s": self.convexify_time_s,
                "solver_s": self.solver_time_s, "overhead_s": self.overhead_time_s}


def merge_results(first: SCPResult, second: SCPResult) -> SCPResult:
    """``second`` continued from ``first`` (e.g. after a repair): histories and times add up."""
    history = first.history + [replace(r, iteration=r.iteration + first.iterations) for r in second.history]
    return replace(second, history=history, iterations=len(history),
                   wall_time_s=first.wall_time_s + second.wall_time_s,
                   convexify_time_s=first.convexify_time_s + second.convexify_time_s,
                   solver_time_s=first.solver_time_s + second.solver_time_s, notes=first.notes + second.notes)
