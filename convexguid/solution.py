"""The result of a solve: status, typed figures, dense trajectory, verification, and the summary JSON.

Every :class:`Solution` is built by :func:`make_solution` (or :func:`planned_solution`, for a plan that went
through the engine's check-repair loop). A family's figures are a frozen dataclass derived from
:class:`Figures`, registered on its :class:`~convexguid.families.base.Family`; their fields are the keys the
summary JSON adds after the common ones, in field order.

This module imports numpy only (the families' figures modules import it at registry load); files are written
through :mod:`convexguid.outputs` (atomically). ``write_text_atomic`` is re-exported from there.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from convexguid.outputs import atomic_file, write_text_atomic

if TYPE_CHECKING:
    from convexguid.scp.check_repair import RepairRound, VerifiedSolve
    from convexguid.scp.problem import ProgramSize
    from convexguid.scp.state import IterationRecord
    from convexguid.verification import Verification


def optional(along: str | None = None, compute_time: bool = False) -> Any:
    """A figure field (default None) left out of the summary while it is None.

    With ``along``, the figure is written (None included) whenever the figure ``along`` is written, and left
    out otherwise: e.g. the certificate's ``lcvx_burn_time_s`` is null when ``lcvx_status`` says the
    certificate failed, and absent without a certificate. ``compute_time`` marks a figure that times the
    computer, not the maneuver (see :meth:`Figures.compute_times`).
    """
    return field(default=None, metadata={"optional": True, "along": along, "compute_time": compute_time})


def compute_time_figure() -> Any:
    """A figure field (default None, always written) that times the computer, not the maneuver."""
    return field(default=None, metadata={"compute_time": True})


@dataclass(frozen=True)
class Figures:
    """Base of a family's figures: a frozen dataclass whose fields are summary keys.

    :meth:`to_dict` keeps the field order; nested dataclasses, lists, tuples, dicts and arrays become JSON-ready
    lists and dicts, non-finite floats None. A field declared with :func:`optional` is left out while None.
    """

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """Every figure this type can carry (its fields, i.e. summary keys), in order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def compute_times(cls) -> frozenset[str]:
        """The figures that time the computer (they differ from run to run; the answer is the rest)."""
        return frozenset(f.name for f in dataclasses.fields(cls) if f.metadata.get("compute_time"))

    def to_dict(self) -> dict[str, Any]:
        """The figures as summary entries, in field order, without the optional ones that are not set."""
        specs = {f.name: f for f in dataclasses.fields(self)}

        def written(name: str) -> bool:
            meta = specs[name].metadata
            if not meta.get("optional") or getattr(self, name) is not None:
                return True
            return meta.get("along") is not None and written(meta["along"])

        return {name: plain(getattr(self, name)) for name in specs if written(name)}


def plain(value: Any) -> Any:
    """``value`` as JSON-ready data: dataclasses and mappings to dicts, sequences and arrays to lists,
    numpy scalars to Python numbers, non-finite floats to None."""
    if isinstance(value, Figures):
        return value.to_dict()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return _finite(value)
    return value


@dataclass(frozen=True)
class Trajectory:
    """Samples on one time grid; ``columns`` maps a header with its unit (``"roll_deg"``) to values."""

    t: np.ndarray
    columns: dict[str, np.ndarray]

    def write_csv(self, path: Path) -> None:
        """Write the samples as CSV (header ``t_s`` and the columns), atomically (:func:`atomic_file`)."""
        with atomic_file(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(["t_s", *self.columns])
            data = np.column_stack([self.t, *self.columns.values()])
            for row in data:
                writer.writerow([f"{v:.12g}" for v in row])


@dataclass
class Solution:
    """Everything a solve produces. :meth:`summary` is the machine-readable contract (docs/cli.md, "Summary JSON").

    Build one with :func:`make_solution` or :func:`planned_solution`.
    """

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
    figures: Figures | None = None
    timing: dict[str, float] = field(default_factory=dict)
    repair_rounds: list[RepairRound] = field(default_factory=list)
    kkt: dict | None = None
    """KKT residuals of the planned iterate (:meth:`convexguid.scp.optimality.KKTResiduals.summary`); None when not
    planned."""

    @property
    def ok(self) -> bool:
        """Converged and verified."""
        return self.status == "converged" and self.verification is not None and self.verification.passed

    def figure_names(self) -> tuple[str, ...]:
        """Summary keys of the figures this solution carries, in order (an unset optional figure is not one)."""
        return tuple(self.figures.to_dict()) if self.figures is not None else ()

    def figure(self, name: str) -> Any:
        """The figure ``name`` (a summary key) as the summary writes it.

        Raises
        ------
        KeyError
            If this solution carries no such figure; the message lists the ones it has.
        """
        figures = self.figures.to_dict() if self.figures is not None else {}
        if name not in figures:
            kind = type(self.figures).__name__ if self.figures is not None else "no figures"
            unset = self.figures is not None and name in self.figures.names()
            raise KeyError(f"{self.problem}: figure {name!r} is {'not set in' if unset else 'not one of'} this "
                           f"solution's figures ({kind}); available: {', '.join(figures) or 'none'}")
        return figures[name]

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
            "repair_rounds": [dataclasses.asdict(r) for r in self.repair_rounds],
            "kkt": self.kkt,
        }
        if self.figures is not None:
            out.update(self.figures.to_dict())
        return out

    def write_summary(self, path: Path) -> None:
        """Write the summary JSON atomically (a reader never sees half a file)."""
        write_text_atomic(Path(path), json.dumps(self.summary(), indent=2) + "\n")


def make_solution(spec, *, status: str, message: str, started: float, objective: float, iterations: int,
                  size: ProgramSize, solver: str | None = None, verification: Verification | None = None,
                  history: list[IterationRecord] | None = None, nodes: Trajectory | None = None,
                  dense: Trajectory | None = None, figures: Figures | None = None,
                  timing: dict[str, float] | None = None,
                  repair_rounds: list[RepairRound] | None = None, kkt: dict | None = None) -> Solution:
    """The one constructor of a :class:`Solution`.

    Problem, family and method come from ``spec``, the solver from ``spec.solver.backend`` unless ``solver``
    names it, the wall time is measured from ``started`` (a :func:`time.perf_counter` value) to now.
    """
    return Solution(problem=spec.name, family=spec.family, method=spec.method, status=status, objective=objective,
                    iterations=iterations, size=size, wall_time_s=time.perf_counter() - started,
                    solver=solver if solver is not None else spec.solver.backend, message=message,
                    verification=verification, history=list(history or []), nodes=nodes, dense=dense,
                    figures=figures, timing=dict(timing or {}), repair_rounds=list(repair_rounds or []), kkt=kkt)


def planned_solution(spec, outcome: VerifiedSolve, started: float, size: ProgramSize, *,
                     nodes: Trajectory | None = None, dense: Trajectory | None = None,
                     figures: Figures | None = None) -> Solution:
    """The :class:`Solution` of a plan that went through the engine's check-repair loop.

    Status, message, objective, iterations, history, timing, the solver as the engine resolved it
    (e.g. ``auto -> daqp (condensed)``), the dense verification and the repair rounds come from
    ``outcome``; the family adds its trajectories and figures.
    """
    result = outcome.result
    return make_solution(spec, status=outcome.status, message=outcome.message, started=started,
                         objective=result.objective, iterations=result.iterations, size=size,
                         verification=outcome.check.verification if outcome.check is not None else None,
                         history=result.history, nodes=nodes, dense=dense, figures=figures,
                         timing=result.timing(), repair_rounds=outcome.rounds, solver=result.solver or None,
                         kkt=result.kkt)


def _finite(value: float | None) -> float | None:
    """``value`` as a float, None if it is None or not finite (the summary writes no NaN or infinity)."""
    if value is None or not math.isfinite(value):
        return None
    return float(value)
