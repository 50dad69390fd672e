"""The compute times of a ``convexguid validate`` run, written beside the report (``REPORT.timings.md``).

Wall-clock and compute times change from run to run and from machine to machine, so the validation report,
which is committed, carries none of them and stays the same when nothing changed. This file has them: the
machine, per case the wall, SCP and convex-solver times, the compute-time (``timed``) columns of the
cross-method tables (:func:`~convexguid.validation.comparisons.comparison_timings`) and each family's own times
(:attr:`~convexguid.families.base.Family.timing_section`, e.g. the LPMPC update times of Feng et al.'s
Table 4). It is git-ignored. Rendering only: nothing here solves or measures.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from convexguid.bench_common import cell, environment_lines
from convexguid.families import get_family

if TYPE_CHECKING:
    from convexguid.validation.run import CaseResult

TIMED_PACKAGES = ("numpy", "scipy", "clarabel", "piqp", "daqp", "osqp")
"""Versions listed with the machine: the packages whose speed the times mostly measure."""


def timings_path(report: Path) -> Path:
    """The timings file of ``report``: ``<report stem>.timings.md`` beside it."""
    return report.with_name(f"{report.stem}.timings.md")


def render_timings(results: Sequence[CaseResult], comparisons: Sequence[str] = (),
                   report_name: str = "the report") -> str:
    """The markdown timings file: machine, one row per case, the ``comparisons`` lines, the families' sections."""
    lines = ["# convexguid validation timings", "",
             f"Compute times of the `convexguid validate` run that wrote `{report_name}` beside this file. They change "
             "from run to run and machine to machine, so they are kept out of the report and out of the repository "
             "(git-ignored); `convexguid bench` repeats such timings with more care.", "",
             *environment_lines(TIMED_PACKAGES), "",
             "| case | status | iterations or steps | wall time [s] | SCP [s] | convex solver [s] |",
             "|---|---|---|---|---|---|"]
    for r in results:
        sol = r.solution
        lines.append(f"| {r.spec.name} | {sol.status} | {sol.iterations} | {cell(sol.wall_time_s, '.3f')} | "
                     f"{cell(sol.timing.get('scp_s'), '.3f')} | {cell(sol.timing.get('solver_s'), '.3f')} |")
    lines += list(comparisons)
    for r in results:
        family = get_family(r.solution.family)
        section = family.timing_section(r.spec, r.solution) if family.timing_section is not None else []
        if section:
            lines += ["", f"## {r.spec.name}", *section]
    return "\n".join(lines) + "\n"
