"""One trial of the robustness benchmark: solve a problem, fetch its independent optimum, judge the plan.

A :class:`Trial` travels to a worker; :func:`run_trial` returns a small dictionary (never raises: a failure is
an ``error`` outcome), like a campaign run's (:func:`convexguid.campaign.execute.run_task`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from convexguid.bench_common import one_line
from convexguid.problem_files import parse_problem

GAP_TOLERANCE = 1e-3
"""A plan within this relative gap above the best reference objective is optimal (0.1%)."""


@dataclass(frozen=True)
class Trial:
    """A problem to solve: its data, where it came from, and how many reference starts judge it (0: none).

    ``section`` and ``label`` name it in the report; ``group`` gathers the trials compared with one another
    (a problem file and its perturbations).
    """

    run_id: int
    section: str
    group: str
    label: str
    problem: dict[str, Any]
    source: str
    reference_starts: int = 0
    figures: tuple[str, ...] = ()


def run_trial(trial: Trial) -> dict[str, Any]:
    """Solve ``trial``, and judge it against the family's independent optimum when it asks for one."""
    # imported in the worker that runs the trial: the scheduler unpickling the task does not load the solver
    from convexguid.api import solve
    from convexguid.families import get_family

    started = time.perf_counter()
    outcome: dict[str, Any] = {"run_id": trial.run_id, "status": "error", "objective": None, "iterations": None,
                               "verified": None, "kkt_met": None, "minimum_time": False, "figures": {},
                               "reference": None, "reference_s": None, "message": ""}
    try:
        spec = parse_problem(trial.problem, trial.source)
        solution = solve(spec)
        summary = solution.summary()
        kkt = summary.get("kkt")
        outcome.update(status=solution.status, objective=solution.objective, iterations=solution.iterations,
                       message=one_line(solution.message, 300),
                       verified=None if solution.verification is None else solution.verification.passed,
                       kkt_met=None if not kkt else kkt.get("met"),
                       minimum_time=getattr(spec, "objective", None) == "time",
                       figures=_answer_figures(solution, summary))
        outcome["wall_time_s"] = time.perf_counter() - started
        hook = get_family(spec.family).independent_optimum
        if trial.reference_starts and hook is not None:
            begun = time.perf_counter()
            reference = hook(spec, solution, trial.reference_starts)
            outcome["reference_s"] = time.perf_counter() - begun
            outcome["reference"] = {"objective": reference.objective, "method": reference.method,
                                    "solved": reference.solved, "starts": reference.starts,
                                    "infeasible": reference.infeasible, "gap": reference.gap(solution.objective)}
    except Exception as exc:  # noqa: BLE001 - a trial that raises is recorded as an error, never the benchmark's end
        outcome["message"] = one_line(f"{type(exc).__name__}: {exc}", 300)
    outcome.setdefault("wall_time_s", time.perf_counter() - started)
    return outcome


def _answer_figures(solution, summary: dict[str, Any]) -> dict[str, float]:
    """The numeric summary figures that describe the answer (the computer's timings left out)."""
    timings = type(solution.figures).compute_times() if solution.figures is not None else frozenset()
    return {name: summary[name] for name in solution.figure_names()
            if name not in timings and isinstance(summary.get(name), (int, float))}


def judged(outcome: dict[str, Any]) -> str:
    """``success``, or why not: ``not converged``, ``not verified``, ``gap``, ``no reference``, ``error``."""
    status, reference = outcome["status"], outcome.get("reference")
    if status == "error":
        return "error"
    if status == "infeasible":
        return "success" if reference and reference["infeasible"] else "infeasible without certificate"
    if status != "converged":
        return status
    if outcome["verified"] is False:
        return "not verified"
    if reference is None or reference["objective"] is None:
        return "no reference"
    return "success" if reference["gap"] <= GAP_TOLERANCE else "gap"
