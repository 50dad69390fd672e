"""Time the rendezvous solvers on one problem file: ``lcvx`` (and its cvxpy statement), ``scp_arcs``, IPOPT.

In one run, each method solves the problem ``repeat`` times and the fastest run is reported:

- ``lcvx``: the lossless-convexification SOCP on the problem's ``discretization.grid_steps``
  zero-order-hold grid (:func:`convexguid.families.rendezvous.lcvx.solve_lcvx`), one
  convex solve whose optimum is global for that grid;
- ``lcvx (cvxpy statement)``: the same SOCP stated uncondensed in cvxpy
  (:func:`convexguid.families.rendezvous.lcvx_reference.solve_lcvx_cvxpy`), solved by cvxpy's Clarabel
  interface: an independent cross-check of the ocp statement; its ``setup s`` is cvxpy's compile time;
- ``scp_arcs``: Wang & Tang's burn/coast NLP (:class:`~convexguid.families.rendezvous.arc_phases.PhasedArcsProgram`)
  by the SCP engine (:func:`convexguid.scp.engine.solve_scp`) with the problem's solver settings,
  from the paper's kind of guess (:meth:`~convexguid.families.rendezvous.arc_layout.ArcsPlan.paper_guess`);
- ``ipopt``: the same NLP, written independently in CasADi and solved by IPOPT with exact
  Hessians (:func:`convexguid.families.rendezvous.reference.solve_rendezvous_arcs_ipopt`) from the same initial
  guess, when ``casadi`` is installed.

Run it as ``python -m convexguid.families.rendezvous.bench problems/wang2003_rendezvous.yaml --repeat 3``.

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003.
Acikmese B., Ploen S. R., "Convex programming approach to powered descent guidance
for Mars landing", J. Guidance, Control, and Dynamics 30(5), 2007 (lossless convexification).
"""

from __future__ import annotations

import argparse
import shlex
import time
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

from convexguid.bench_common import (
    bench_document,
    cell,
    ipopt_availability,
    ipopt_outcome,
    markdown_grid,
    one_line,
    timed_method,
)
from convexguid.families.rendezvous.arc_phases import PhasedArcsProgram
from convexguid.families.rendezvous.case import Rendezvous, RendezvousPlan, build_case
from convexguid.families.rendezvous.lcvx import solve_lcvx
from convexguid.families.rendezvous.lcvx_reference import solve_lcvx_cvxpy
from convexguid.families.rendezvous.reference import solve_rendezvous_arcs_ipopt
from convexguid.families.rendezvous.solve import planning_setup
from convexguid.reference import casadi_available
from convexguid.scp.engine import solve_scp
from convexguid.scp.problem import SCPSettings
from convexguid.solution import write_text_atomic

IPOPT_TOLERANCE = 1e-10
"""IPOPT's ``tol`` in the benchmark (tighter than the SCP's, so IPOPT's burn time is the NLP reference)."""

LCVX_SOLVER_TARGET_S = 0.1
"""Target: ``lcvx`` convex-solver time well under this, s."""

LCVX_CVXPY = "lcvx (cvxpy statement)"
"""Row name of the cvxpy statement of the ``lcvx`` SOCP."""

SCP_WALL_TARGET_S = 0.5
"""Target: ``scp_arcs`` wall time under this, s."""

COLUMNS = ("method", "status", "burn time s", "gap to lcvx", "iterations", "wall s", "solver s", "convexify s",
           "setup s")
"""Table columns (see the caption written by :func:`rendezvous_bench_markdown`)."""


@dataclass(frozen=True)
class RendezvousBenchRow:
    """One method: status, burn time and the timings of the fastest of ``repeat`` runs (s).

    Timings that do not apply to the method are ``None`` (printed ``-``); ``ok`` is whether it
    converged (IPOPT: reported success); ``message`` explains a failure (not in the table).
    """

    method: str
    status: str
    burn_time_s: float | None = None
    iterations: int | None = None
    wall_s: float | None = None
    solver_s: float | None = None
    convexify_s: float | None = None
    setup_s: float | None = None
    ok: bool = False
    message: str = ""

    def cells(self, lcvx_burn_time_s: float | None) -> list[str]:
        """The row as strings in the order of :data:`COLUMNS`; the gap is relative to ``lcvx_burn_time_s``."""
        gap = None
        if self.burn_time_s is not None and lcvx_burn_time_s and self.method != "lcvx":
            gap = (self.burn_time_s - lcvx_burn_time_s) / lcvx_burn_time_s
        return [self.method, self.status, cell(self.burn_time_s, ".9g"), cell(gap, ".2e"),
                cell(self.iterations, "d"), cell(self.wall_s, ".4f"),
                cell(self.solver_s, ".4f"), cell(self.convexify_s, ".4f"), cell(self.setup_s, ".4f")]


def _failed(method: str):
    """The row a method that raised gets (for :func:`~convexguid.bench_common.timed_method`)."""
    return lambda status, message: RendezvousBenchRow(method, status, message=message)


def _lcvx_row(case: Rendezvous, steps: int, backend: str, repeat: int) -> RendezvousBenchRow:
    """``lcvx`` on ``steps`` grid steps; wall = stating and transcribing the problem + solving + reading it."""
    def run() -> tuple[RendezvousPlan, float]:
        start = time.perf_counter()
        plan = solve_lcvx(case, steps, backend)
        return plan, time.perf_counter() - start

    def row(best, _) -> RendezvousBenchRow:
        plan, wall = best
        ok = plan.status == "converged"
        return RendezvousBenchRow("lcvx", plan.status, plan.objective if ok else None, plan.iterations, wall,
                                  plan.timing.get("solver_s"), ok=ok, message=plan.message)

    return timed_method(repeat, run, lambda r: r[1], row, _failed("lcvx"))


def _lcvx_cvxpy_row(case: Rendezvous, steps: int, repeat: int) -> RendezvousBenchRow:
    """The ``lcvx`` SOCP stated in cvxpy; wall = the whole call, setup = cvxpy's compile time."""
    def row(r, _) -> RendezvousBenchRow:
        return RendezvousBenchRow(LCVX_CVXPY, r.status, r.burn_time_s if r.optimal else None, r.iterations,
                                  r.wall_time_s, r.solve_time_s, setup_s=r.compile_time_s, ok=r.optimal,
                                  message="" if r.optimal else f"cvxpy returned {r.status}")

    return timed_method(repeat, lambda: solve_lcvx_cvxpy(case, steps), lambda r: r.wall_time_s, row,
                        _failed(LCVX_CVXPY))


def _scp_row(program: PhasedArcsProgram, settings: SCPSettings, repeat: int) -> RendezvousBenchRow:
    """``scp_arcs`` from the program's initial guess."""
    def row(r, _) -> RendezvousBenchRow:
        ok = r.status == "converged"
        return RendezvousBenchRow("scp_arcs", r.status, r.objective if ok else None, r.iterations, r.wall_time_s,
                                  r.solver_time_s, r.convexify_time_s, ok=ok, message=r.message)

    return timed_method(repeat, lambda: solve_scp(program, settings), lambda r: r.wall_time_s, row,
                        _failed("scp_arcs"))


def _ipopt_row(program: PhasedArcsProgram, repeat: int) -> RendezvousBenchRow:
    """IPOPT on the arcs NLP from the program's initial guess; ``setup s`` is the fastest model build."""
    x0 = program.design_vector(program.initial_guess())

    def row(best, runs) -> RendezvousBenchRow:
        ok, message = ipopt_outcome(best)
        return RendezvousBenchRow("ipopt", best.status, best.objective if ok else None, best.iterations,
                                  best.wall_time_s, setup_s=min(r.setup_time_s for r in runs), ok=ok,
                                  message=message)

    return timed_method(repeat, lambda: solve_rendezvous_arcs_ipopt(program, x0, IPOPT_TOLERANCE),
                        lambda r: r.wall_time_s, row, _failed("ipopt"))


def bench_rendezvous_rows(spec, repeat: int,
                          with_ipopt: bool | None = None) -> list[RendezvousBenchRow]:
    """Benchmark rows ``lcvx``, its cvxpy statement, ``scp_arcs`` and (if ``with_ipopt``) ``ipopt``.

    Parameters
    ----------
    spec : RendezvousProblem
        The loaded ``rendezvous`` problem (e.g. of ``problems/wang2003_rendezvous.yaml``).
    repeat : int
        Timed runs per method; the fastest (by wall time) is kept.
    with_ipopt : bool, optional
        Also solve with CasADi + IPOPT; default: when ``casadi`` is installed.

    Returns
    -------
    list of RendezvousBenchRow
        In the order ``lcvx``, ``lcvx (cvxpy statement)``, ``scp_arcs``, ``ipopt``.

    Raises
    ------
    ValueError
        If the file is not of the ``rendezvous`` family.
    """
    if spec.family != "rendezvous":
        raise ValueError(f"{spec.source}: family {spec.family!r}, expected 'rendezvous'")
    case = build_case(spec)
    disc, s = spec.discretization, spec.solver
    burns = planning_setup(spec).program.layout.burns if disc.auto_burns else disc.burns
    program = PhasedArcsProgram(case, burns, disc.subintervals_per_burn)  # both from the paper's kind of guess
    settings = SCPSettings.from_spec(s)
    rows = [_lcvx_row(case, disc.grid_steps, s.backend, repeat), _lcvx_cvxpy_row(case, disc.grid_steps, repeat),
            _scp_row(program, settings, repeat)]
    if casadi_available() if with_ipopt is None else with_ipopt:
        rows.append(_ipopt_row(program, repeat))
    return rows


def _by_method(rows: Sequence[RendezvousBenchRow], method: str) -> RendezvousBenchRow | None:
    return next((r for r in rows if r.method == method), None)


def _notes(rows: Sequence[RendezvousBenchRow]) -> list[str]:
    """Targets met or not, the cvxpy-lcvx and SCP-IPOPT burn-time agreements, then failures."""
    lines = []
    lcvx, lcvx_cvxpy, scp, ipopt = (_by_method(rows, m) for m in ("lcvx", LCVX_CVXPY, "scp_arcs", "ipopt"))
    if lcvx is not None and lcvx.ok and lcvx.solver_s is not None:
        met = "met" if lcvx.solver_s < LCVX_SOLVER_TARGET_S else "NOT met"
        lines.append(f"lcvx solver time {lcvx.solver_s:.4f} s vs target < {LCVX_SOLVER_TARGET_S:g} s: {met}")
    if scp is not None and scp.ok and scp.wall_s is not None:
        met = "met" if scp.wall_s < SCP_WALL_TARGET_S else "NOT met"
        lines.append(f"scp_arcs wall time {scp.wall_s:.4f} s vs target < {SCP_WALL_TARGET_S:g} s: {met}")
    if lcvx is not None and lcvx_cvxpy is not None and lcvx.ok and lcvx_cvxpy.ok:
        rel = abs(lcvx_cvxpy.burn_time_s - lcvx.burn_time_s) / lcvx.burn_time_s
        lines.append(f"{LCVX_CVXPY} vs lcvx burn time (the same SOCP, stated in cvxpy and on convexguid.ocp): relative "
                     f"difference {rel:.2e}; cvxpy compile {lcvx_cvxpy.setup_s:.4f} s + solve "
                     f"{lcvx_cvxpy.solver_s:.4f} s vs lcvx solver {lcvx.solver_s:.4f} s")
    if scp is not None and ipopt is not None and scp.ok and ipopt.ok:
        rel = abs(scp.burn_time_s - ipopt.burn_time_s) / ipopt.burn_time_s
        lines.append(f"scp_arcs vs ipopt burn time (same NLP): relative difference {rel:.2e}")
    for r in rows:
        if not r.ok:
            status = "failed" if r.status.startswith("failed") else r.status
            lines.append(f"{r.method}: {status}: {one_line(r.message, 200)}")
    return lines


def _markdown_table(rows: Sequence[RendezvousBenchRow]) -> str:
    lcvx = _by_method(rows, "lcvx")
    reference = lcvx.burn_time_s if lcvx is not None and lcvx.ok else None
    align = [":---", ":---"] + ["---:"] * (len(COLUMNS) - 2)
    return markdown_grid(COLUMNS, align, [r.cells(reference) for r in rows])


def rendezvous_bench_markdown(rows: Sequence[RendezvousBenchRow], problem_path: str, repeat: int,
                              grid_steps: int | None = None, ipopt_note: str | None = None,
                              output: str | PathLike[str] | None = None) -> str:
    """The benchmark as a markdown document: machine, versions, date, command, caption, table, notes."""
    args = ["convexguid", "bench", problem_path, "--repeat", str(repeat)]
    command = shlex.join(args + (["--output", str(output)] if output is not None else []))
    steps = "the problem's `grid_steps`" if grid_steps is None else f"{grid_steps} steps"
    caption = (
        f"Best of {repeat} runs per method, times in seconds. `lcvx`: one SOCP on {steps} (zero-order hold); "
        "stated on convexguid.ocp; `wall s` includes stating and transcribing it, `solver s` is the convex solver "
        f"alone, `iterations` SCP iterations (one: every map is affine). `{LCVX_CVXPY}`: the same SOCP stated in "
        "cvxpy (a cross-check of the convexguid.ocp statement), solved by cvxpy's Clarabel interface at the same "
        "tolerance; `wall s` is the whole call, `solver s` Clarabel's solve time, `setup s` cvxpy's compile time. "
        "`scp_arcs`: Wang & Tang's burn/coast NLP by SCP; `wall s` = `convexify s` (maps and "
        "Jacobians) + `solver s` (convex subproblems) + bookkeeping, `iterations` are SCP iterations. `ipopt`: "
        f"the same NLP in CasADi, IPOPT with exact Hessian (MUMPS, tol = {IPOPT_TOLERANCE:g}) from the same "
        "initial guess; `wall s` is the solve call only, `setup s` builds the CasADi model. `gap to lcvx` = "
        "(burn time - lcvx burn time) / lcvx burn time; the two transcriptions differ (Hermite-Simpson arcs vs "
        "zero-order-hold grid), so it is a discretization difference, not an optimality gap (for "
        f"`{LCVX_CVXPY}` it is the same program, so only the solvers' round-off). "
        f"Targets: lcvx solver time well under {LCVX_SOLVER_TARGET_S:g} s at 600 steps; scp_arcs wall time "
        f"under {SCP_WALL_TARGET_S:g} s.")
    return bench_document(f"convexguid rendezvous benchmark: lcvx vs scp_arcs vs IPOPT on `{Path(problem_path).name}`",
                          ("numpy", "scipy", "clarabel", "cvxpy", "casadi"), command, caption, _markdown_table(rows),
                          _notes(rows), ipopt_note)


def run_rendezvous_bench(spec, repeat: int,
                         output: str | PathLike[str] | None = None) -> int:
    """Time ``lcvx`` (condensed and in cvxpy), ``scp_arcs`` and IPOPT on one problem; print, optionally save.

    Parameters
    ----------
    spec : RendezvousProblem
        The loaded ``rendezvous`` problem (``spec.source``: its file, named in the document).
    repeat : int
        Timed runs per method; the fastest is reported.
    output : str or path-like, optional
        Also write the markdown document here (atomically).

    Returns
    -------
    int
        0 if every method that ran converged, else 1. Without ``casadi`` the IPOPT row is
        skipped (noted in the document), which does not count as a failure.
    """
    with_ipopt, ipopt_note = ipopt_availability("row")
    rows = bench_rendezvous_rows(spec, repeat, with_ipopt)
    text = rendezvous_bench_markdown(rows, spec.source, repeat, spec.discretization.grid_steps, ipopt_note, output)
    print(text, end="")
    if output is not None:
        write_text_atomic(Path(output), text)
        print(f"table written to {output}")
    return 0 if all(r.ok for r in rows) else 1


def bench_command(spec, args: argparse.Namespace, planner: object = None) -> int:
    """``convexguid bench`` on a ``rendezvous`` file (``--nodes`` and ``--backends`` do not apply; ``planner`` is
    unused: the benchmark plans this problem only)."""
    return run_rendezvous_bench(spec, args.repeat, args.output)
