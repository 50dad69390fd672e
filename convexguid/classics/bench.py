"""The classics benchmark: published optimal-control problems stated from their papers, solved as a new user would.

Each module of ``examples/classics/`` (and each example beside it or in ``examples/phases/`` that gives a published
figure) states one problem with :class:`convexguid.ocp.Problem` or, in phases, :class:`convexguid.ocp.Phases`
(straight-line guess, default settings) and gives the published figure it must
reach: ``PUBLISHED``, ``SOURCE``, ``FIGURE`` and, unless the figure is the final time,
``figure(final_state, final_time)`` computing it from the final state's values by name. For each, in one run on
this machine:

* convexguid: ``build().solve()`` in process, from the statement to the verified plan (transcription, SCP, the
  dense SciPy re-propagation and any repair rounds), its status, figure, SCP iterations and time;
* IPOPT with exact Hessians (CasADi) on the same transcription from the same guess: its status, figure,
  iterations, and the set-up (building the NLP and its derivatives) and solve times apart.

Run ``python -m convexguid.classics`` from a checkout (``--only NAME`` for some, ``--output PATH``); it writes
validation/CLASSICS.md. The document renders what the run measured; nothing in it is written by hand.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from convexguid.bench_common import bench_document, markdown_grid, one_line
from convexguid.outputs import write_text_atomic
from convexguid.threads import single_threaded

FOLDER = Path(__file__).resolve().parents[2] / "examples" / "classics"
"""Where the problem modules live (a checkout's examples/classics)."""

OUTPUT = Path(__file__).resolve().parents[2] / "validation" / "CLASSICS.md"

IPOPT_SOLVED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
"""IPOPT's statuses of a solved NLP: the iteration ratios count only these (a failed run's count is where it
stopped)."""

AGREEMENT = 1e-3
"""A figure within this share of the published one matches it."""


@dataclass(frozen=True)
class Row:
    """One problem's outcome by both solvers."""

    name: str
    published: float
    source: str
    figure_name: str
    status: str
    verified: bool
    figure: float
    iterations: int
    intervals: str
    time_s: float
    ipopt_status: str
    ipopt_figure: float
    ipopt_iterations: int
    ipopt_setup_s: float
    ipopt_solve_s: float
    guess: str = "straight line"
    """Where both solvers start: ``straight line`` (the engine's), or ``stated`` (the statement's own guess)."""

    @property
    def error(self) -> float:
        return (self.figure - self.published) / abs(self.published)

    @property
    def ipopt_error(self) -> float:
        return (self.ipopt_figure - self.published) / abs(self.published)

    @property
    def matches(self) -> bool:
        return self.status == "converged" and self.verified and abs(self.error) <= AGREEMENT


def problem_modules(folder: Path = FOLDER, only: list[str] | None = None) -> list[ModuleType]:
    """The problem modules of ``folder`` and the examples beside it that give a ``PUBLISHED`` figure (by file
    name, ``only`` some), loaded."""
    modules = []
    examples = [path for path in sorted(folder.parent.glob("*.py")) + sorted(folder.parent.glob("phases/*.py"))
                if "\nPUBLISHED = " in path.read_text()]
    for path in sorted(folder.glob("*.py")) + examples:
        if path.stem.startswith("_") or (only and path.stem not in only):
            continue
        spec = importlib.util.spec_from_file_location(f"convexguid_classic_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        modules.append(module)
    return modules


def published_figure(module: ModuleType, final_state: dict[str, float], final_time: float) -> float:
    """The module's figure of a plan: its ``figure(final_state, final_time)``, or the final time."""
    figure = getattr(module, "figure", None)
    return final_time if figure is None else float(figure(final_state, final_time))


def run_problem(module: ModuleType) -> Row:
    """convexguid and IPOPT on one problem module (see the module docstring)."""
    from convexguid.ocp.reference import solve_with_ipopt
    from convexguid.ocp.solve import transcribe

    name = Path(module.__file__).stem
    started = time.perf_counter()
    solution = module.build().solve()
    elapsed = time.perf_counter() - started
    names = list(solution.figures.states)
    ours = published_figure(module, {n: float(solution.nodes.columns[n][-1]) for n in names},
                            solution.figures.final_time_s)
    program = transcribe(module.build())
    with single_threaded():
        answer = solve_with_ipopt(program)
    theirs = published_figure(module, program.final_values(answer.z), program.final_time(answer.z)) \
        if answer.success else math.nan
    phases = getattr(program, "phases", (program,))
    first_intervals = sum(t.N for t in phases)
    final_intervals = len(solution.nodes.t) - len(phases)
    intervals = str(first_intervals) if final_intervals == first_intervals else \
        f"{first_intervals} -> {final_intervals}"
    guessed = any(t.problem.guess_nodes is not None for t in phases)
    return Row(name, float(module.PUBLISHED), module.SOURCE, module.FIGURE, solution.status,
               bool(solution.verification is not None and solution.verification.passed), ours, solution.iterations,
               intervals, elapsed, answer.status, theirs, answer.iterations, answer.setup_s, answer.solve_s,
               "stated" if guessed else "straight line")


def document(rows: list[Row], command: str) -> str:
    """validation/CLASSICS.md from the measured rows."""
    body = [[r.name, r.figure_name, f"{r.published:.7g}", one_line(r.source, 70), r.guess,
             f"{r.status}{', verified' if r.verified else ', NOT verified'}", f"{r.figure:.7g}", f"{r.error:+.1e}",
             str(r.iterations), r.intervals, f"{r.time_s:.2f}",
             r.ipopt_status, f"{r.ipopt_figure:.7g}", f"{r.ipopt_error:+.1e}" if math.isfinite(r.ipopt_error) else "-",
             str(r.ipopt_iterations), f"{r.ipopt_setup_s:.2f} + {r.ipopt_solve_s:.2f}"] for r in rows]
    table = markdown_grid(["problem", "figure", "published", "source", "guess", "convexguid", "its figure",
                           "rel. error", "SCP iterations", "intervals", "time [s]", "IPOPT", "IPOPT figure",
                           "rel. error", "IPOPT iterations", "IPOPT set-up + solve [s]"],
                          ["---", "---", "---:", "---", "---", "---", "---:", "---:", "---:", "---:", "---:", "---",
                           "---:", "---:", "---:", "---:"], body)
    matched = sum(r.matches for r in rows)
    solved = [r for r in rows if r.ipopt_status in IPOPT_SOLVED and r.ipopt_iterations > 0]
    ratios = [r.iterations / r.ipopt_iterations for r in solved]
    unsolved = [f"{r.name} ({r.ipopt_status})" for r in rows if r not in solved]
    summary = [f"{matched} of {len(rows)} problems converged, verified and within {AGREEMENT:.1%} of the published "
               f"figure.",
               f"SCP iterations against IPOPT's: median ratio {statistics.median(ratios):.2f}, largest "
               f"{max(ratios):.2f} (over the {len(ratios)} problems IPOPT solved"
               + (f"; not {', '.join(unsolved)}" if unsolved else "") + ")."
               if ratios else "No IPOPT iteration counts."]
    caption = ("Each problem stated from its paper with convexguid.ocp (`examples/classics/`, and the examples "
               "beside it and in `examples/phases/` that give a published figure), with default settings, from the "
               "engine's straight-line guess or, where 'guess' says 'stated', the statement's own (the paper's, "
               "or one the example describes). convexguid's time runs from the statement to the verified plan "
               "(transcription and CasADi derivatives, SCP, the dense SciPy re-propagation, any repair rounds; "
               "'intervals' shows a refinement), in process. IPOPT (exact Hessians, through CasADi) solves the "
               "same transcription from the same guess; its set-up (the NLP and its derivatives) and solve are "
               "timed apart, and its plan is not re-propagated. A figure matches within "
               f"{AGREEMENT:.1%} of the published one.")
    return bench_document("Classic problems: convexguid and IPOPT from the paper's statement",
                          ["numpy", "scipy", "casadi", "clarabel", "piqp"], command, caption, table, summary)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m convexguid.classics", description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", help="problem module names (file stems) to run")
    parser.add_argument("--output", type=Path, default=OUTPUT)
    args = parser.parse_args(argv)
    if not FOLDER.is_dir():
        print(f"{FOLDER}: not found; run the classics benchmark from a checkout of convexguid")
        return 2
    import convexguid.ocp.reference  # noqa: F401 - CasADi, SciPy and the engine load before any clock starts
    import convexguid.ocp.solve  # noqa: F401

    rows = []
    for module in problem_modules(only=args.only):
        rows.append(run_problem(module))
        r = rows[-1]
        print(f"{r.name}: {r.status} {r.figure:.7g} ({r.error:+.1e}) in {r.iterations} iterations, {r.time_s:.2f} s; "
              f"IPOPT {r.ipopt_status} {r.ipopt_figure:.7g} in {r.ipopt_iterations}", flush=True)
    command = "python -m convexguid.classics" + (f" --only {' '.join(args.only)}" if args.only else "")
    write_text_atomic(args.output, document(rows, command))
    print(f"wrote {args.output}")
    return 0 if all(r.matches for r in rows) else 1
