"""The program's evaluations as the engine asks for them: a trial point's maps are not computed twice. Each iteration
evaluates its trial points without Jacobians, then the one it accepts with them; a program that offers
``with_jacobians(x, values)`` (:class:`~convexguid.scp.problem.NonconvexProgram`) then only adds the Jacobians.
"""

from __future__ import annotations

import numpy as np

from convexguid.scp.problem import Evaluation, NonconvexProgram

MAX_TRIALS_KEPT = 8
"""Trial evaluations kept per iteration (four at most: the step, Newton's, a second-order correction of each)."""


def not_finite(ev: Evaluation) -> str:
    """The maps whose values or Jacobians have entries that are not numbers at this evaluation (a derivative
    undefined there: CasADi's derivative of a norm at zero is 0/0), or ``""``."""
    parts = [("residuals", ev.residuals, ev.residual_jacobian)]
    parts += [(b.name, b.values, b.jacobian) for b in (*ev.inequalities, *ev.equalities, *ev.cones)]
    named = []
    for name, values, jacobian in parts:
        entries = getattr(jacobian, "data", jacobian)
        bad = int(np.sum(~np.isfinite(values))) + (0 if entries is None else int(np.sum(~np.isfinite(entries))))
        if bad:
            named.append(f"{name} ({bad} entries)")
    return ", ".join(named)


class ProgramEvaluations:
    """``program.evaluate(x, jacobians)``, keeping the evaluations without Jacobians made since the last one with
    them; at one of those points (the same array, unchanged) ``with_jacobians`` only adds them (the same numbers)."""

    def __init__(self, program: NonconvexProgram) -> None:
        self.program = program
        self._complete = getattr(program, "with_jacobians", None)
        self._trials: list[tuple[np.ndarray, np.ndarray, Evaluation]] = []  # (point, its copy, evaluation)

    def __call__(self, x: np.ndarray, jacobians: bool) -> Evaluation:
        if not jacobians:
            raw = self.program.evaluate(x, False)
            if self._complete is not None and len(self._trials) < MAX_TRIALS_KEPT:
                self._trials.append((x, x.copy(), raw))
            return raw
        trials, self._trials = self._trials, []
        for point, copy, raw in trials:
            if point is x and np.array_equal(copy, x):
                return self._complete(x, raw)
        return self.program.evaluate(x, True)
