"""The robustness benchmark's report (markdown): it renders the outcomes, judged by :func:`trial.judged`."""

from __future__ import annotations

import math
import statistics
from collections import Counter, defaultdict
from collections.abc import Sequence
from typing import Any

from convexguid.bench_common import cell, markdown_grid
from convexguid.robustness.instances import GENERATORS, ROUNDOFF, SMALLER_RUNS
from convexguid.robustness.trial import GAP_TOLERANCE, Trial, judged

OBJECTIVE_REL = 1e-6
"""Round-off: objectives this close (relative) are the same answer; minimum time :data:`TIME_REL`."""
TIME_REL = 1e-4
FIGURE_ABS = 1e-6
"""Round-off: summary figures (deg, s, N m, ...) this close in absolute terms are the same too (a figure that is
itself round-off, such as a quaternion's norm error of 4e-8, moves by more than 1e-6 of itself)."""

Result = tuple[Trial, dict[str, Any]]


def render(results: Sequence[Result], command: str, elapsed_s: float, executor: str,
           environment: Sequence[str]) -> str:
    """The whole report."""
    by_section: dict[str, list[Result]] = defaultdict(list)
    for trial, outcome in sorted(results, key=lambda r: r[0].run_id):
        by_section[trial.section].append((trial, outcome))
    lines = ["# Robustness benchmark", "",
             "Does convexguid give the right answer, and the same one on every machine? Made by:", "",
             f"    {command}", "", f"{len(results)} trials in {elapsed_s:.0f} s on {executor}.", "", *environment, ""]
    if "round-off" in by_section:
        lines += _roundoff(by_section.pop("round-off"))
    if by_section:
        lines += _random_intro()
        for section, rows in by_section.items():
            lines += _random_section(section, rows)
    return "\n".join(lines) + "\n"


def _roundoff(rows: list[Result]) -> list[str]:
    groups: dict[str, list[Result]] = defaultdict(list)
    for trial, outcome in rows:
        groups[trial.group].append((trial, outcome))
    body, same = [], 0
    for name, group in groups.items():
        outcomes = [o for _, o in group]
        nominal = outcomes[0]
        rel = TIME_REL if nominal.get("minimum_time") else OBJECTIVE_REL
        statuses = {o["status"] for o in outcomes}
        objectives = [o.get("objective") for o in outcomes]
        figures = [o.get("figures") or {} for o in outcomes]
        agree = len(statuses) == 1 and all(is_close(objectives[0], x, rel) for x in objectives) and all(
            is_close(figures[0].get(k), f.get(k), OBJECTIVE_REL, FIGURE_ABS) for f in figures for k in figures[0])
        same += agree
        spread = _spread(objectives)
        iterations = [o.get("iterations") for o in outcomes]
        body.append([name, nominal["status"], "yes" if len(statuses) == 1 else "no: " + ", ".join(sorted(statuses)),
                     cell(spread, ".1e"), f"{rel:.0e}", _iterations(iterations),
                     _kkt(nominal.get("kkt_met")), "same" if agree else "**differs**"])
    note = "; ".join(f"{f}: {' '.join(o)}" for f, o in SMALLER_RUNS.items())
    return ["## Round-off: the same answer under 1e-12 changes of the inputs", "",
            f"Each problem file solved as written and {len(rows) // max(len(groups), 1) - 1} more times with every "
            f"physical number moved by {ROUNDOFF:.0e} relative (random signs, "
            "`convexguid.spec.perturb.perturb_inputs`), the size of the differences between machines. Same answer: "
            f"one status, objectives within the tolerance shown and every summary figure within {OBJECTIVE_REL:.0e} "
            f"relative or {FIGURE_ABS:.0e} absolute (compute times left out). "
            f"Files whose input is another case's result take it from that case's nominal run. Smaller runs: {note}.",
            "", f"**{same} of {len(groups)} files give the same answer.**", "",
            markdown_grid(["problem file", "status", "one status", "objective spread", "tolerance",
                           "iterations: nominal (perturbed)", "KKT met", "verdict"],
                          _align("lllrrlll"), body), ""]


def _random_intro() -> list[str]:
    lines = ["## Random instances against an independent optimum", "",
             f"A success is `converged`, verified by dense re-propagation and at most {GAP_TOLERANCE:.1%} above the "
             "best objective of the family's independent reference (below it is fine), or `infeasible` where "
             "the reference proves infeasibility. Gaps are relative, (plan - reference) / reference. "
             "The instances:", ""]
    for name, generator in GENERATORS.items():
        doc = " ".join(generator.__doc__.split())
        lines.append(f"- **{name}**: {doc}")
    return lines + [""]


def _random_section(section: str, rows: list[Result]) -> list[str]:
    verdicts = Counter(judged(o) for _, o in rows)
    gaps = [o["reference"]["gap"] for _, o in rows if o.get("reference") and o["reference"]["gap"] is not None]
    iterations = [o["iterations"] for _, o in rows if o.get("iterations") is not None]
    solve_s = [o["wall_time_s"] for _, o in rows if o.get("wall_time_s") is not None]
    ref_s = [o["reference_s"] for _, o in rows if o.get("reference_s") is not None]
    methods = sorted({o["reference"]["method"] for _, o in rows if o.get("reference")})
    kkt = sum(1 for _, o in rows if o.get("kkt_met"))
    lines = [f"### {section}", "", f"**{verdicts['success']} of {len(rows)} successes** "
             f"({', '.join(f'{k} {n}' for k, n in verdicts.most_common())}). Reference: {'; '.join(methods)}.", "",
             markdown_grid(["", "median", "max"], _align("lrr"), [
                 ["gap to reference", cell(_median(gaps), ".2e"), cell(max(gaps, default=None), ".2e")],
                 ["iterations", cell(_median(iterations), ".0f"), cell(max(iterations, default=None), ".0f")],
                 ["solve wall time, s", cell(_median(solve_s), ".2f"), cell(max(solve_s, default=None), ".2f")],
                 ["reference wall time, s", cell(_median(ref_s), ".2f"), cell(max(ref_s, default=None), ".2f")]]),
             "", f"KKT conditions met at {kkt} of {len(rows)} plans.", ""]
    misses = [[t.label, judged(o), o["status"], cell((o.get("reference") or {}).get("gap"), ".2e"),
               cell(o.get("iterations"), "d"), o.get("message", "")[:160]] for t, o in rows if judged(o) != "success"]
    if misses:
        lines += ["Not successes:", "", markdown_grid(["instance", "verdict", "status", "gap", "iterations", "message"],
                                                      _align("lllrrl"), misses), ""]
    return lines


def _align(codes: str) -> list[str]:
    """Markdown alignment cells from ``l`` (left) and ``r`` (right) codes."""
    return [":---" if c == "l" else "---:" for c in codes]


def _spread(values: list[float | None]) -> float | None:
    finite = [v for v in values if v is not None]
    if len(finite) < 2:
        return None
    return (max(finite) - min(finite)) / max(abs(statistics.fmean(finite)), 1e-12)


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def _iterations(values: list[int | None]) -> str:
    nominal, rest = values[0], [v for v in values[1:] if v is not None]
    text = "-" if nominal is None else str(nominal)
    if rest:
        text += f" ({min(rest)}" + (f"-{max(rest)})" if max(rest) != min(rest) else ")")
    return text


def _kkt(met: bool | None) -> str:
    return "-" if met is None else ("yes" if met else "no")


def is_close(a: float | None, b: float | None, rel: float, absolute: float = 1e-12) -> bool:
    """Both None, or both within ``rel`` of each other (relative to the larger) or ``absolute`` apart."""
    if a is None or b is None:
        return a is None and b is None
    return math.isclose(a, b, rel_tol=rel, abs_tol=absolute)
