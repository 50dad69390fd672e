"""The result of a solve: status, figures, dense trajectory, verification, and the summary JSON."""

from __future__ import annotations

import csv
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from convexguid.scp.problem import ProgramSize
from convexguid.scp.state import IterationRecord
from convexguid.scp.verified import RepairRound, VerifiedSolve
from convexguid.verify import Verification


@dataclass(frozen=True)
class Trajectory:
    """Samples on one time grid; ``columns`` maps a header with its unit (``"roll_deg"``) to values."""

    t: np.ndarray
    columns: dict[str, np.ndarray]

    def write_csv(self, path: Path) -> None:
        with open(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(["t_s", *self.columns])
            data = np.column_stack([self.t, *self.columns.values()])
            for row in data:
                writer.writerow([f"{v:.12g}" for v in row])


@dataclass
class Solution:
    """Everything a solve produces. :meth:`summary` is the machine-readable contract of design.md."""

    problem: str
    family: str
    method: str
    status: str
    objective: float
    iterations: int
    size: ProgramSize
    wall_time_s: float
    solver: str
    message: str = ""
    verification: Verification | None = None
    history: list[IterationRecord] = field(default_factory=list)
    nodes: Trajectory | None = None
    dense: Trajectory | None = None
    extras: dict[str, float | int | str | None] = field(default_factory=dict)
    timing: dict[str, float] = field(default_factory=dict)
    repair_rounds: list[RepairRound] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Converged and verified."""
        return self.status == "converged" and self.verification is not None and self.verification.passed

    def summary(self) -> dict:
        out = {
            "problem": self.problem,
            "family": self.family,
            "method": self.method,
            "status": self.status,
            "message": self.message,
            "objective": _finite(self.objective),
            "iterations": self.iterations,
            "num_variables": self.size.num_variables,
            "num_equality_constraints": self.size.num_equality_constraints,
            "num_inequality_constraints": self.size.num_inequality_constraints,
            "wall_time_s": self.wall_time_s,
            "solver": self.solver,
            "timing": self.timing,
            "verification": self.verification.to_dict() if self.verification else None,
            "repair_rounds": [r.to_dict() for r in self.repair_rounds],
        }
        out.update({k: _finite(v) if isinstance(v, float) else v for k, v in self.extras.items()})
        return out

    def write_summary(self, path: Path) -> None:
        """Write the summary JSON atomically (a reader never sees half a file)."""
        write_text_atomic(Path(path), json.dumps(self.summary(), indent=2) + "\n")


def planned_solution(spec, outcome: VerifiedSolve, started: float, size: ProgramSize, *,
                     nodes: Trajectory | None = None, dense: Trajectory | None = None,
                     extras: dict | None = None) -> Solution:
    """The :class:`Solution` of a plan that went through the engine's check-repair loop.

    Status, message, objective, iterations, history, timing, the dense verification and the
    repair rounds come from ``outcome``; the family adds its trajectories and figures.
    """
    result = outcome.result
    return Solution(problem=spec.name, family=spec.family, method=spec.method, status=outcome.status,
                    objective=result.objective, iterations=result.iterations, size=size,
                    wall_time_s=time.perf_counter() - started, solver=spec.solver.backend, message=outcome.message,
                    verification=outcome.check.verification if outcome.check is not None else None,
                    history=result.history, nodes=nodes, dense=dense, extras=dict(extras or {}),
                    timing=result.timing(), repair_rounds=list(outcome.rounds))


def _finite(value: float | None) -> float | None:
    if value is None or not math.isfinite(value):
        return None
    return float(value)


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to a temporary sibling and rename it over ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)
