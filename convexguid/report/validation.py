"""``convexguid validate``: solve every problem with a ``reference:`` block and set it beside the paper.

For each case the report has a table (quantity | paper | convexguid | relative
difference | within tolerance), the dense verification figures and the plots.
Quantities under ``reference.values`` are compared with their relative tolerance;
those under ``reference.max_values`` are upper limits (e.g. SCP iterations).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from convexguid.api import solve
from convexguid.report.comparisons import comparison_sections
from convexguid.report.plots import plot_solution
from convexguid.solution import Solution, write_text_atomic
from convexguid.spec import ProblemSpec, load_problem

KEY_FIGURES: dict[str, tuple[tuple[str, str], ...]] = {
    "rendezvous": (
        ("burn_time_s", "total burn time, s"),
        ("burn_arcs_s", "burns [start, end], s"),
        ("lcvx_burn_time_s", "lcvx global optimum on the fixed grid, s"),
        ("lcvx_burn_arcs_s", "lcvx burns [start, end], s"),
        ("lcvx_gap_rel", "(scp_arcs - lcvx) / lcvx"),
        ("planned_direction_norm_min", "smallest norm of the interpolated direction on burns (1 at nodes)"),
    ),
    "potential_function": (
        ("maneuver_time_1deg_s", "time to within 1 deg of the command, s"),
        ("maneuver_time_01deg_s", "time to within 0.1 deg of the command, s"),
        ("min_theta_b_deg", "smallest angle to the forbidden attitude, deg"),
        ("theta_m_deg", "forbidden half-angle theta_m, deg"),
        ("max_abs_torque_Nm", "largest torque component, N m"),
        ("energy_N2m2s", "energy integral of squared torque, N^2 m^2 s"),
        ("final_error_deg", "final attitude error, deg"),
    ),
}
"""Family figures listed under each case (summary key, description), beyond the paper comparison."""

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
    def ok(self) -> bool:
        return self.solution.ok and all(r.ok for r in self.rows)


def compare(spec: ProblemSpec, solution: Solution) -> tuple[Comparison, ...]:
    """Rows comparing the solution's summary with ``spec.reference``."""
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


def run_case(path: Path, figure_root: Path) -> CaseResult:
    spec = load_problem(path)
    solution = solve(spec)
    figures = tuple(plot_solution(solution, figure_root / spec.name))
    return CaseResult(spec, solution, compare(spec, solution), figures)


def reference_problems(directory: Path = DEFAULT_PROBLEMS_DIR) -> list[Path]:
    """Problem files in ``directory`` that carry a ``reference:`` block."""
    return [p for p in sorted(directory.glob("*.yaml")) if load_problem(p).reference is not None]


def validate(problems: Iterable[str | Path] = (), report: str | Path = DEFAULT_REPORT) -> list[CaseResult]:
    """Run the reference cases (default: every file in ``problems/`` with a reference) and write the report."""
    report = Path(report)
    paths = [Path(p) for p in problems] or reference_problems()
    results = [run_case(p, report.parent / "figures") for p in paths]
    extra = comparison_sections(results, DEFAULT_PROBLEMS_DIR)
    write_text_atomic(report, render(results, report.parent, extra))
    return results


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


def render(results: list[CaseResult], base: Path, comparisons: Sequence[str] = ()) -> str:
    """The markdown report; ``comparisons`` are cross-method sections put after the summary table."""
    lines = ["# convexguid validation report", "",
             "Generated by `convexguid validate`: every problem file with a `reference:` block is solved, its plan",
             "re-propagated with SciPy on a dense grid, and its figures set beside the published ones.", "",
             "| case | status | verification | matches paper |", "|---|---|---|---|"]
    for r in results:
        v = r.solution.verification
        lines.append(f"| {r.spec.name} | {r.solution.status} | {'passed' if v and v.passed else 'FAILED'} | "
                     f"{'yes' if r.ok else 'NO'} |")
    lines += list(comparisons)
    for r in results:
        lines += _case_section(r, base)
    return "\n".join(lines) + "\n"


def _case_section(r: CaseResult, base: Path) -> list[str]:
    ref, sol = r.spec.reference, r.solution
    lines = ["", f"## {r.spec.name}", "", f"*{' '.join(ref.citation.split())}*, {ref.table}.", ""]
    if r.spec.notes:
        lines += [f"Notes: {' '.join(r.spec.notes.split())}", ""]
    lines += ["| quantity | paper | convexguid | relative difference | within tolerance |", "|---|---|---|---|---|"]
    for row in r.rows:
        rel = "n/a" if row.rel_diff is None else f"{row.rel_diff:.2e}"
        paper = _fmt(row.paper) if row.rel_diff is not None or row.ours is None else f"limit {_fmt(row.paper)}"
        lines.append(f"| {row.quantity} | {paper} | {_fmt(row.ours)} | {rel} ({row.tolerance}) | "
                     f"{'yes' if row.ok else 'NO'} |")
    if ref.notes:
        lines += ["", f"Reference notes: {' '.join(ref.notes.split())}"]
    if "scp_s" in sol.timing:
        lines += ["", f"Status `{sol.status}` after {sol.iterations} SCP iterations ({sol.message}); "
                  f"solver `{sol.solver}`; wall time {sol.wall_time_s:.3f} s (SCP {sol.timing['scp_s']:.3f} s, "
                  f"of which convex solver {sol.timing.get('solver_s', float('nan')):.3f} s)."]
    else:
        lines += ["", f"Status `{sol.status}` ({sol.message}); {sol.method} with `{sol.solver}`, "
                  f"{sol.iterations} steps; wall time {sol.wall_time_s:.3f} s."]
    summary = sol.summary()
    figures = [(label, summary[key]) for key, label in KEY_FIGURES.get(sol.family, ()) if key in summary]
    if figures:
        lines += ["", "| figure | value |", "|---|---|"]
        lines += [f"| {label} | {_fmt_any(value)} |" for label, value in figures]
    v = sol.verification
    if v is not None:
        how = ("closed-loop simulation" if sol.family == "potential_function"
               else "SciPy DOP853 re-propagation of the plan")
        lines += ["", f"Dense verification ({v.grid_points} points, {how}):",
                  "", "| constraint | worst on dense grid | bound |", "|---|---|---|"]
        for c in v.checks:
            lines.append(f"| {c.name} | {c.worst:.6g} | {'<=' if c.sense == 'max' else '>='} {c.bound:g} |")
        finals = ", ".join(f"{k} = {val:.3g}" for k, val in v.final_errors.items())
        lines += ["", f"Final state: {finals}; verification {'passed' if v.passed else 'FAILED'}."]
    if r.figures:
        lines.append("")
        lines += [f"![{f.stem}]({f.relative_to(base).as_posix()})" for f in r.figures]
    return lines
