"""The measures the SCP engine judges an iterate by besides its objective: the violation of each constraint block,
and the exact-penalty merit's ingredients (:mod:`convexguid.scp.engine`)."""

from __future__ import annotations

import numpy as np

from convexguid.scp.problem import Evaluation


def violation_by_block(ev: Evaluation) -> dict[str, float]:
    """Worst violation of each nonlinear constraint block, in its own unit."""
    out = {b.name: float(np.max(b.values, initial=0.0)) for b in ev.inequalities}
    out.update({b.name: float(np.max(np.abs(b.values), initial=0.0)) for b in ev.equalities})
    return {k: max(v, 0.0) for k, v in out.items()}


def max_violation(ev: Evaluation) -> float:
    return max(violation_by_block(ev).values(), default=0.0)


def describe_violations(ev: Evaluation) -> str:
    """``"name by value unit; ..."`` for each violated block (its worst row named if it labels them), or ``"none"``."""
    blocks = {b.name: b for b in (*ev.inequalities, *ev.equalities)}
    parts = []
    for name, worst in violation_by_block(ev).items():
        if worst > 0:
            block = blocks[name]
            violations = block.values if any(b is block for b in ev.inequalities) else np.abs(block.values)
            where = f" (worst: {block.labels[int(np.argmax(violations))]})" if block.labels else ""
            parts.append(f"{name} by {worst:.3g} {block.unit}".rstrip() + where)
    return "; ".join(parts) or "none"


def penalty_sum(ev: Evaluation) -> float:
    """The :math:`\\ell_1` violation :math:`\\sum \\max(0, g) + \\sum |e|` the merit weighs."""
    total = sum(float(np.maximum(b.values, 0.0).sum()) for b in ev.inequalities)
    return total + sum(float(np.abs(b.values).sum()) for b in ev.equalities)


def decrease_ratio(actual: float, predicted: float) -> float:
    """Actual over predicted decrease of the merit function; -1 where the trial point's merit is not a number (the
    program is undefined there: a logarithm of a negative value), so the step is refused and the region shrinks."""
    if not np.isfinite(actual):
        return -1.0
    return actual / predicted if predicted > 0 else (1.0 if actual >= 0 else -1.0)
