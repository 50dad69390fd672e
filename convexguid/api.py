"""Python entry points: load a problem, solve it, validate against the papers."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from convexguid.formulations import FAMILY_SOLVERS
from convexguid.scp.engine import IterationRecord
from convexguid.solution import Solution
from convexguid.spec import ProblemSpec, load_problem


def solve(problem: str | Path | ProblemSpec, overrides: Sequence[str] = (),
          log: Callable[[IterationRecord], None] | None = None) -> Solution:
    """Plan and verify ``problem`` (a YAML path or a loaded spec).

    ``overrides`` are ``dotted.key=value`` strings as for ``convexguid solve --set``;
    ``log`` receives one :class:`~convexguid.scp.engine.IterationRecord` per SCP iteration.
    """
    if isinstance(problem, ProblemSpec):
        spec = load_problem(problem.source, overrides) if overrides else problem
    else:
        spec = load_problem(problem, overrides)
    return FAMILY_SOLVERS[spec.family](spec, log=log)
