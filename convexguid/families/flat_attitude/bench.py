"""``convexguid bench``: time the SCP against IPOPT on the same flat-attitude transcription.

For every polynomial degree :math:`N` the problem file is transcribed once
(:func:`convexguid.families.flat_attitude.program.build_problem`) and solved from the
same initial guess (:meth:`FlatAttitudeProgram.initial_guess`)

- by the SCP engine (:func:`convexguid.scp.engine.solve_scp`), once per convex backend, and
- by CasADi + IPOPT with exact Hessians (:func:`convexguid.families.flat_attitude.reference.solve_flat_attitude_ipopt`),
  when ``casadi`` is installed.

Both methods solve the identical transcription: the torque box and the keep-out cones
at the nodes and at the check points between them. The path-constraint refinement
loop of ``convexguid solve`` is left out, so the SCP here is one :func:`solve_scp` call.
Every case runs ``repeat`` times and the fastest run is reported.
"""

from __future__ import annotations

import argparse
import shlex
from collections.abc import Sequence
from dataclasses import dataclass, replace
from os import PathLike
from pathlib import Path

import numpy as np

from convexguid.bench_common import (
    bench_document,
    cell,
    ipopt_availability,
    ipopt_outcome,
    markdown_grid,
    one_line,
    timed_method,
)
from convexguid.families.flat_attitude.program import FlatAttitudeProblem, FlatAttitudeProgram, build_problem
from convexguid.families.flat_attitude.reference import solve_flat_attitude_ipopt
from convexguid.outputs import write_text_atomic
from convexguid.scp.engine import SCPResult, solve_scp
from convexguid.scp.problem import SCPSettings
from convexguid.spec import with_values

DEFAULT_NODES = (16, 32, 64, 128)
"""Polynomial degrees :math:`N` ``convexguid bench`` times when ``--nodes`` is not given."""

IPOPT_TOLERANCE = 1e-8
"""IPOPT's ``tol`` in the benchmark (tighter than the SCP's, so IPOPT's objective is the reference)."""

COLUMNS = ("N", "method", "status", "objective", "iterations", "wall s", "convexify s", "solver s",
           "overhead s", "setup s", "IPOPT/SCP time")
"""Table columns; ``setup s`` is IPOPT's model construction, outside its wall time."""


@dataclass(frozen=True)
class BenchRow:
    """One method on one grid: status, objective, iterations and the best of ``repeat`` timings (s).

    Timings that do not apply to the method are ``None`` (printed as ``-``); ``ok`` is whether
    the method converged (IPOPT: reported success); ``message`` explains a failure (not in the table).
    """

    nodes: int
    method: str
    status: str
    objective: float | None = None
    iterations: int | None = None
    wall_s: float | None = None
    convexify_s: float | None = None
    solver_s: float | None = None
    overhead_s: float | None = None
    setup_s: float | None = None
    ratio: float | None = None
    ok: bool = False
    message: str = ""

    def cells(self) -> list[str]:
        """The row as strings, in the order of :data:`COLUMNS`."""
        return [str(self.nodes), self.method, self.status, cell(self.objective, ".8g"), cell(self.iterations, "d"),
                cell(self.wall_s, ".4f"), cell(self.convexify_s, ".4f"), cell(self.solver_s, ".4f"),
                cell(self.overhead_s, ".4f"), cell(self.setup_s, ".4f"), cell(self.ratio, ".2f")]


def _scp_row(nodes: int, backend: str, program: FlatAttitudeProgram, settings: SCPSettings,
             x0: np.ndarray, repeat: int) -> BenchRow:
    """Fastest of ``repeat`` SCP runs from ``x0`` on one backend."""
    def row(r: SCPResult, _) -> BenchRow:
        return BenchRow(nodes, f"scp/{backend}", r.status, r.objective, r.iterations, r.wall_time_s,
                        r.convexify_time_s, r.solver_time_s, r.overhead_time_s, ok=r.status == "converged",
                        message=r.message)

    return timed_method(repeat, lambda: solve_scp(program, settings, x0=x0), lambda r: r.wall_time_s, row,
                        lambda status, message: BenchRow(nodes, f"scp/{backend}", status, message=message))


def _ipopt_row(nodes: int, label: str, problem: FlatAttitudeProblem, x0: np.ndarray, repeat: int,
               nodes_only: bool) -> BenchRow:
    """Fastest of ``repeat`` IPOPT solves; the setup time is the fastest model construction.

    On the nodes-only NLP the CasADi graph is expanded to SX (the fastest evaluation, exact Hessian);
    with check points it stays an MX graph of SX node functions (expanding it takes minutes at N = 128).
    """
    method = f"ipopt {label}"

    def row(best, runs) -> BenchRow:
        ok, message = ipopt_outcome(best)
        return BenchRow(nodes, method, best.status, best.objective, best.iterations, best.wall_time_s,
                        setup_s=min(r.setup_time_s for r in runs), ok=ok, message=message)

    return timed_method(repeat, lambda: solve_flat_attitude_ipopt(problem, x0, IPOPT_TOLERANCE, nodes_only=nodes_only,
                                                                  expand=nodes_only),
                        lambda r: r.wall_time_s, row, lambda status, message: BenchRow(nodes, method, status,
                                                                                       message=message))


NLP_VARIANTS = (("[nodes]", True), ("[+checks]", False))
"""The two NLPs benched: path constraints at the nodes only (the paper's), and also at the check points (ours)."""


def bench_nodes(spec, nodes: int, repeat: int, backends: Sequence[str],
                with_ipopt: bool) -> list[BenchRow]:
    """Benchmark rows of one grid size, for each NLP variant: one per SCP backend, then IPOPT (if ``with_ipopt``).

    Parameters
    ----------
    spec : FlatAttitudeProblem
        The loaded ``flat_attitude`` problem; ``discretization.nodes`` is overridden with ``nodes``.
    nodes : int
        Polynomial degree :math:`N` (:math:`N + 1` nodes).
    repeat : int
        Timed runs per method; the fastest is kept.
    backends : sequence of str
        Convex backends of the SCP (see :mod:`convexguid.backends`).
    with_ipopt : bool
        Also solve with CasADi + IPOPT.

    Returns
    -------
    list of BenchRow
        With ``ratio`` = IPOPT solve time / SCP wall time on the converged SCP rows of the same NLP when IPOPT
        succeeded.
    """
    rows: list[BenchRow] = []
    for label, nodes_only in NLP_VARIANTS:
        values = {"discretization.nodes": nodes} | ({"discretization.check_points_per_interval": 0}
                                                    if nodes_only else {})
        variant = with_values(spec, values)
        problem = build_problem(variant)
        program = FlatAttitudeProgram(problem)
        x0 = program.initial_guess()
        scp = [_scp_row(nodes, f"{backend} {label}", program, SCPSettings.from_spec(variant.solver, backend=backend),
                        x0, repeat) for backend in backends]
        if with_ipopt:
            ipopt = _ipopt_row(nodes, label, problem, x0, repeat, nodes_only)
            if ipopt.ok and ipopt.wall_s is not None:
                scp = [replace(r, ratio=ipopt.wall_s / r.wall_s) if r.ok and r.wall_s else r for r in scp]
            scp.append(ipopt)
        rows += scp
    return rows


def _text_table(rows: Sequence[BenchRow]) -> str:
    cells = [list(COLUMNS)] + [r.cells() for r in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(len(COLUMNS))]
    left = {1, 2}  # method and status are text
    lines = ["  ".join(c.ljust(w) if i in left else c.rjust(w)
                       for i, (c, w) in enumerate(zip(row, widths, strict=True))) for row in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _markdown_table(rows: Sequence[BenchRow]) -> str:
    align = ["---:", ":---", ":---"] + ["---:"] * (len(COLUMNS) - 3)
    return markdown_grid(COLUMNS, align, [r.cells() for r in rows])


def _command(problem_path: str, nodes_list: Sequence[int], repeat: int,
             backends: Sequence[str], output_path: str | PathLike[str] | None) -> str:
    """The ``convexguid bench`` command line that reproduces this run."""
    args = ["convexguid", "bench", problem_path, "--nodes", *map(str, nodes_list),
            "--repeat", str(repeat), "--backends", *backends]
    if output_path is not None:
        args += ["--output", str(output_path)]
    return shlex.join(args)


def _notes(rows: Sequence[BenchRow]) -> list[str]:
    """Per grid: the largest relative gap between a converged SCP objective and IPOPT's; then failures."""
    lines = []
    for n in dict.fromkeys(r.nodes for r in rows):
        for label, _ in NLP_VARIANTS:
            solved = [r for r in rows if r.nodes == n and r.ok and r.objective is not None
                      and r.method.endswith(label)]
            ipopt = [r.objective for r in solved if r.method.startswith("ipopt")]
            scp = [r.objective for r in solved if not r.method.startswith("ipopt")]
            if ipopt and scp:
                gap = max(abs(o - ipopt[0]) for o in scp) / abs(ipopt[0])
                lines.append(f"N = {n} {label}: largest relative objective gap, converged SCP vs IPOPT: {gap:.2e}")
    for r in rows:
        if not r.ok:
            status = "failed" if r.status.startswith("failed") else r.status
            lines.append(f"N = {r.nodes}, {r.method}: {status}: {one_line(r.message, 200)}")
    return lines


CAPTION = (
    "Both methods solve the identical transcription (mapped Chebyshev) from the same initial guess, in two "
    "variants: `[nodes]`, the torque box and the keep-out cones at the nodes only (the paper's NLP), and "
    "`[+checks]`, also at the check points between them (what `convexguid solve` imposes); the dense-check "
    "repairs of `convexguid solve` are not run. Times are the best of the repeats, in seconds. "
    "For the SCP, `wall s` = `convexify s` (maps and Jacobians) + `solver s` (convex backend) "
    "+ `overhead s` (assembly, bookkeeping), setup included. For IPOPT (CasADi, exact Hessian, MUMPS, "
    f"tol = {IPOPT_TOLERANCE:g}; the `[nodes]` graph expanded to SX), `wall s` is the solve call only and "
    "`setup s` builds the CasADi model. `IPOPT/SCP time` = IPOPT wall time / SCP wall time on the same NLP, "
    "converged runs only (above 1: SCP faster).")
"""The benchmark document's caption."""


def run_bench(spec, nodes_list: Sequence[int] | None, repeat: int,
              backends: Sequence[str], output_path: str | PathLike[str] | None = None) -> int:
    """Time the SCP (each backend) and IPOPT on ``spec`` for every grid size in ``nodes_list``.

    Parameters
    ----------
    spec : FlatAttitudeProblem
        The loaded ``flat_attitude`` problem (``spec.source``: its file, named in the table).
    nodes_list : sequence of int or None
        Polynomial degrees :math:`N` to benchmark; ``None`` means :data:`DEFAULT_NODES`.
    repeat : int
        Timed runs per case; the fastest is reported.
    backends : sequence of str
        Convex backends of the SCP; a backend that fails is reported as ``failed: <reason>``.
    output_path : str or path-like, optional
        Also write the table as markdown, with machine, versions, date and command.

    Returns
    -------
    int
        Exit code: 0 if every row converged (IPOPT: succeeded), else 1.
    """
    if nodes_list is None:
        nodes_list = DEFAULT_NODES
    with_ipopt, ipopt_note = ipopt_availability("column")
    if ipopt_note:
        print(ipopt_note)
    rows: list[BenchRow] = []
    for nodes in nodes_list:
        new = bench_nodes(spec, nodes, repeat, backends, with_ipopt)
        rows += new
        for r in new:
            print(f"  done: N = {r.nodes:<4} {r.method:<14} {r.status}", flush=True)
    print()
    print(_text_table(rows))
    for line in _notes(rows):
        print(line)
    if output_path is not None:
        command = _command(spec.source, nodes_list, repeat, backends, output_path)
        path = Path(output_path)
        write_text_atomic(path, bench_document(f"convexguid benchmark: SCP vs IPOPT on `{Path(spec.source).name}`",
                                               ("numpy", "clarabel", "daqp", "osqp", "casadi"), command, CAPTION,
                                               _markdown_table(rows), _notes(rows), ipopt_note))
        print(f"table written to {path}")
    return 0 if all(r.ok for r in rows) else 1


def bench_command(spec, args: argparse.Namespace, planner: object = None) -> int:
    """``convexguid bench`` on a ``flat_attitude`` file: :func:`run_bench` with the command line's arguments
    (``planner`` is unused: the benchmark plans this problem only)."""
    return run_bench(spec, args.nodes, args.repeat, args.backends, args.output)
