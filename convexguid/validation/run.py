"""``convexguid validate``: solve every problem with a ``reference:`` block and set it beside the paper.

For each case the report has a table (quantity | paper | convexguid | relative
difference | within tolerance), the family's key figures, the dense verification
figures and the plots (:class:`~convexguid.families.base.Family` gives the figures,
the wording of the verification and the plots).
Quantities under ``reference.values`` are compared with their relative tolerance;
those under ``reference.max_values`` are upper limits (e.g. SCP iterations). A problem named on the command line
without a ``reference:`` block is solved and verified, and the report says there is nothing to compare.

The report holds only what is the same on every machine, so re-running on an unchanged tree leaves it
unchanged: compute times and SCP iteration counts (which round-off moves by a few) go to the timings file beside
it (:mod:`convexguid.validation.timings`, not committed); a committed line is kept wherever the fresh one agrees with
it within the reproduction tolerance (:func:`~convexguid.validation.reproduction.reconcile`), and a committed picture
wherever the fresh one shows the same (:func:`~convexguid.figure_files.keep_unchanged_pictures`).
:func:`check` solves the same cases and lists the lines that do not agree, writing nothing. Output
paths are checked before anything is solved; each case's figures folder is replaced as a whole
(:func:`~convexguid.outputs.staged_folder`) and every file is written atomically.

A case may take an input from another case's result (``boundary.tf_from: {problem, figure}``, see
:meth:`~convexguid.spec.common.ProblemBase.input_links`): the runner solves the cases in an order where
each such case comes after the one it names, and sets the key to the figure's value
(:mod:`convexguid.validation.links`, shared with ``solve``, ``simulate`` and ``bench``). Cases whose
``reference.comparison`` names the same table are set side by side by :mod:`convexguid.validation.comparisons`,
which renders the results and solves nothing.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from convexguid.api import solve
from convexguid.families import get_family
from convexguid.figure_files import keep_unchanged_pictures
from convexguid.outputs import check_output_file, check_output_folder, staged_folder, write_text_atomic
from convexguid.problem_files import load_problem
from convexguid.solution import Solution
from convexguid.solution_plots import plot_solution
from convexguid.spec import ProblemSpec, with_values
from convexguid.validation.comparisons import check_comparisons, comparison_sections, comparison_timings
from convexguid.validation.links import run_order, solve_in_order
from convexguid.validation.reproduction import LineDifference, reconcile
from convexguid.validation.timings import render_timings, timings_path

DEFAULT_PROBLEMS_DIR = Path("problems")
DEFAULT_REPORT = Path("validation/REPORT.md")


@dataclass(frozen=True)
class Comparison:
    """One row of a case's table."""

    quantity: str
    paper: float
    ours: float | None
    rel_diff: float | None
    tolerance: str
    ok: bool


@dataclass(frozen=True)
class CaseResult:
    spec: ProblemSpec
    solution: Solution
    rows: tuple[Comparison, ...]
    figures: tuple[Path, ...]

    @property
    def compared(self) -> bool:
        """The problem file has a ``reference:`` block (else the case is only solved and verified)."""
        return self.spec.reference is not None

    @property
    def ok(self) -> bool:
        return self.solution.ok and all(r.ok for r in self.rows)


def compare(spec: ProblemSpec, solution: Solution) -> tuple[Comparison, ...]:
    """Rows comparing the solution's summary with ``spec.reference`` (none without a reference)."""
    if spec.reference is None:
        return ()
    ref, summary = spec.reference, solution.summary()
    rows = []
    for quantity, paper in ref.values.items():
        ours = summary.get(quantity)
        tol = ref.tolerance_for(quantity)
        if ours is None:
            rows.append(Comparison(quantity, paper, None, None, f"rel <= {tol:g}", False))
            continue
        rel = abs(ours - paper) / abs(paper) if paper != 0 else abs(ours)
        rows.append(Comparison(quantity, paper, ours, rel, f"rel <= {tol:g}", rel <= tol))
    for quantity, limit in (ref.max_values or {}).items():
        ours = summary.get(quantity)
        ok = ours is not None and ours <= limit
        rows.append(Comparison(quantity, limit, ours, None, f"<= {limit:g}", ok))
    return tuple(rows)


def run_case(spec: ProblemSpec, figure_root: Path, values: Mapping[str, Any] | None = None,
             publish: bool = True) -> CaseResult:
    """Solve one loaded case (``values``: keys set from other cases' results, :func:`link_values`), compare it,
    and draw its pictures.

    With ``publish`` the case's figures folder ``figure_root/<name>`` is replaced as a whole, the committed
    pictures that show the same kept; without it they are drawn in a temporary folder and nothing is written.
    """
    if values:
        spec = with_values(spec, values)
    solution = solve(spec)
    folder = figure_root / spec.name
    if publish:
        with staged_folder(folder, replace=True) as staging:
            staged = plot_solution(solution, staging)
            keep_unchanged_pictures(staged, folder)
    else:
        with tempfile.TemporaryDirectory() as scratch:
            staging = Path(scratch)
            staged = plot_solution(solution, staging)
    figures = tuple(folder / p.relative_to(staging) for p in staged)
    return CaseResult(spec, solution, compare(spec, solution), figures)


def reference_problems(directory: Path = DEFAULT_PROBLEMS_DIR) -> list[Path]:
    """Problem files in ``directory`` that carry a ``reference:`` block."""
    return [p for p in sorted(directory.glob("*.yaml")) if load_problem(p).reference is not None]


def check_report_outputs(report: str | Path) -> None:
    """Raise :class:`~convexguid.errors.OutputError` unless the report, its timings file and its figures folder
    can be written (before anything is solved; nothing is created)."""
    report = Path(report)
    check_output_file(report, "report")
    check_output_file(timings_path(report), "timings file")
    check_output_folder(report.parent / "figures", overwrite=True)


def validate(problems: Iterable[str | Path] = (), report: str | Path = DEFAULT_REPORT) -> list[CaseResult]:
    """Run the reference cases (default: every file in ``problems/`` with a reference) and write the report.

    Cases are solved in :func:`run_order` (linked inputs resolved by :func:`link_values`); the results,
    the report's rows and its comparison tables keep the order of ``problems``. A committed line the fresh
    report agrees with is kept (:func:`~convexguid.validation.reproduction.reconcile`). The compute times go to
    :func:`~convexguid.validation.timings.timings_path` beside the report.

    Raises
    ------
    OutputError
        Before anything is solved, if the report, the timings file or the figures folder cannot be written there.
    OSError
        If writing fails after the cases were solved.
    """
    report = Path(report)
    check_report_outputs(report)
    results = _run_all(problems, report.parent / "figures", publish=True)
    fresh = render(results, report.parent, comparison_sections(results), timings_path(report).name)
    write_text_atomic(report, reconcile(_committed(report), fresh).text)
    write_text_atomic(timings_path(report), render_timings(results, comparison_timings(results), report.name))
    return results


def check(problems: Iterable[str | Path] = (), report: str | Path = DEFAULT_REPORT) \
        -> tuple[list[CaseResult], tuple[LineDifference, ...]]:
    """Solve the cases as :func:`validate` does and list where the fresh report disagrees with ``report``.

    Nothing is written (the pictures are drawn in a temporary folder, for their names). A missing report
    disagrees on every line.
    """
    report = Path(report)
    results = _run_all(problems, report.parent / "figures", publish=False)
    fresh = render(results, report.parent, comparison_sections(results), timings_path(report).name)
    return results, reconcile(_committed(report) or "", fresh).differences


def _run_all(problems: Iterable[str | Path], figure_root: Path, publish: bool) -> list[CaseResult]:
    """Every case solved in :func:`run_order`, returned in the order given."""
    specs = [load_problem(p) for p in problems] or [load_problem(p) for p in reference_problems()]
    run_order(specs)  # the links checked before the comparisons, and before anything is solved
    check_comparisons(specs)
    return solve_in_order(specs, lambda spec, values: run_case(spec, figure_root, values, publish=publish),
                          lambda result: result.solution)


def _committed(report: Path) -> str | None:
    """The report as it stands (``None`` if there is none yet)."""
    try:
        return report.read_text(encoding="utf-8")
    except FileNotFoundError:
        return None


def _fmt(value: float | None) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    if isinstance(value, int) or float(value).is_integer():
        return f"{int(value)}"
    return f"{value:.6g}"


def _fmt_any(value: object) -> str:
    """Numbers as in :func:`_fmt`; nested lists of numbers bracketed."""
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_fmt_any(v) for v in value) + "]"
    if isinstance(value, (int, float)) or value is None:
        return _fmt(value)
    return str(value)


def render(results: list[CaseResult], base: Path, comparisons: Sequence[str] = (),
           timings_name: str = "the timings file") -> str:
    """The markdown report; ``comparisons`` are cross-method sections put after the summary table.

    It shows no compute time (they are in ``timings_name``, beside it), so it is the same on every run.
    """
    lines = ["# convexguid validation report", "",
             "Generated by `convexguid validate`: every problem file with a `reference:` block is solved, its plan",
             "re-propagated with SciPy on a dense grid, and its figures set beside the published ones.",
             f"Compute times change from run to run, so they are not here: `convexguid validate` writes them to "
             f"`{timings_name}` beside this report (not committed).", "",
             "| case | status | verification | matches paper |", "|---|---|---|---|"]
    for r in results:
        v = r.solution.verification
        matches = ("yes" if r.ok else "NO") if r.compared else "no reference"
        lines.append(f"| {r.spec.name} | {r.solution.status} | {'passed' if v and v.passed else 'FAILED'} | "
                     f"{matches} |")
    lines += list(comparisons)
    for r in results:
        lines += _case_section(r, base)
    return "\n".join(lines) + "\n"


def _case_section(r: CaseResult, base: Path) -> list[str]:
    ref, sol = r.spec.reference, r.solution
    lines = ["", f"## {r.spec.name}", ""]
    if ref is not None:
        lines += [f"*{' '.join(ref.citation.split())}*, {ref.table}.", ""]
    else:
        lines += [f"{r.spec.source} has no `reference:` block: the case is solved and verified, and there is "
                  "nothing to compare.", ""]
    if r.spec.notes:
        lines += [f"Notes: {' '.join(r.spec.notes.split())}", ""]
    if r.rows:
        lines += ["| quantity | paper | convexguid | relative difference | within tolerance |", "|---|---|---|---|---|"]
    for row in r.rows:
        rel = "n/a" if row.rel_diff is None else f"{row.rel_diff:.2e}"
        limit = row.rel_diff is None and row.ours is not None
        paper = f"limit {_fmt(row.paper)}" if limit else _fmt(row.paper)
        # a count under a limit (SCP iterations) moves by a few with round-off: the report says whether it is
        # within the limit, the timings file has the count
        count = isinstance(row.ours, int) and not isinstance(row.ours, bool)
        ours = "within the limit" if limit and count and row.ok else _fmt(row.ours)
        lines.append(f"| {row.quantity} | {paper} | {ours} | {rel} ({row.tolerance}) | "
                     f"{'yes' if row.ok else 'NO'} |")
    if ref is not None and ref.notes:
        lines += ["", f"Reference notes: {' '.join(ref.notes.split())}"]
    if "scp_s" in sol.timing:
        lines += ["", f"Status `{sol.status}` ({sol.message}); solver `{sol.solver}`. The number of SCP iterations "
                  "is in the timings file."]
    else:
        lines += ["", f"Status `{sol.status}` ({sol.message}); {sol.method} with `{sol.solver}`, "
                  f"{sol.iterations} steps."]
    family, carried = get_family(sol.family), sol.figure_names()
    figures = [(label, sol.figure(key)) for key, label in family.key_figures if key in carried]
    if figures:
        lines += ["", "| figure | value |", "|---|---|"]
        lines += [f"| {label} | {_fmt_any(value)} |" for label, value in figures]
    if family.report_section is not None:
        lines += family.report_section(r.spec, sol)
    v = sol.verification
    if v is not None:
        lines += ["", f"Dense verification ({v.grid_points} points, {family.verification_method}):",
                  "", "| constraint | worst on dense grid | bound |", "|---|---|---|"]
        for c in v.checks:
            lines.append(f"| {c.name} | {c.worst:.6g} | {'<=' if c.sense == 'max' else '>='} {c.bound:g} |")
        finals = ", ".join(f"{k} = {val:.3g}" for k, val in v.final_errors.items())
        lines += ["", f"Final state: {finals}; verification {'passed' if v.passed else 'FAILED'}."]
    if r.figures:
        lines.append("")
        lines += [f"![{f.stem}]({f.relative_to(base).as_posix()})" for f in r.figures]
    return lines
