"""Time the ``quaternion_attitude`` SCP against IPOPT on the same Hermite-Simpson NLP, for several grid sizes.

For every interval count :math:`K` (:math:`K + 1` nodes) of ``intervals_list`` the problem file is
loaded with ``discretization.intervals = K``, ``method: scp``, ``initial_guess: eigenaxis``, and

- ``scp time``: minimum time by
  :func:`~convexguid.families.quaternion_attitude.solve.solve_quaternion_attitude`
  (SCP from the eigenaxis guess, dense verification, node-constraint tightening and re-solve when
  the dense check fails);
- ``ipopt time``: the same NLP written independently in CasADi
  (:func:`convexguid.families.quaternion_attitude.reference.solve_quaternion_attitude_ipopt`,
  exact Hessian),
  from the same eigenaxis guess and initial final time;
- ``ipopt time @scp``: that NLP again, started from the SCP's solution: when it ends below
  ``ipopt time``, the NLP has several local optima and the eigenaxis start found a worse one;
- ``scp energy``, ``ipopt energy``, ``ipopt energy @scp``: the same three for minimum energy at the fixed
  final time :data:`ENERGY_TF_FACTOR` times the SCP's minimum time of that ``K``.

The path-transfer planner (:func:`convexguid.families.quaternion_attitude.path_transfer.plan_path_transfer`), which
does not depend on :math:`K`, is timed once. Every case runs ``repeat`` times and the fastest run
is reported. Run it as ``convexguid bench problems/wang_multicone_time.yaml --repeat 3`` or
``python -m convexguid.families.quaternion_attitude.bench problems/wang_multicone_time.yaml --repeat 3``.
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
from convexguid.families.quaternion_attitude.path_transfer import plan_path_transfer
from convexguid.families.quaternion_attitude.program import AttitudeCase, eigenaxis_start
from convexguid.families.quaternion_attitude.solve import (
    build_case,
    path_transfer_problem,
    solve_quaternion_attitude,
)
from convexguid.reference import casadi_available
from convexguid.solution import Solution, write_text_atomic
from convexguid.spec import with_values

DEFAULT_INTERVALS = (20, 30, 50, 80)
"""Hermite-Simpson interval counts benchmarked by default."""

ENERGY_TF_FACTOR = 1.3
"""The minimum-energy rows fix the final time at this factor times the SCP's minimum time of the same ``K``."""

IPOPT_TOLERANCE = 1e-8
"""IPOPT's ``tol`` on the scaled NLP error."""

SCP_WALL_TARGETS_S = {"wang_multicone_time.yaml": 1.0, "guo2011_scp_time.yaml": 1.5}
"""Targets, by problem file: the whole minimum-time solve under this (s) at about :data:`SCP_TARGET_INTERVALS`
intervals. Other files get the times without a target."""

SCP_TARGET_INTERVALS = 50
"""Grid size of the SCP time target (the benchmarked ``K`` closest to it is used)."""

TIME_GAP_TARGET = 0.01
"""Target: SCP minimum time within this relative distance of IPOPT's at every ``K``."""

LOCAL_OPTIMUM_RTOL = 1e-5
"""Two IPOPT optima of the same NLP further apart than this (relative) are reported as different local optima."""

COLUMNS = ("K", "method", "status", "tf s", "energy N^2 m^2 s", "gap to ipopt", "iterations", "wall s", "SCP s",
           "solver s", "setup s", "verified", "margin deg")
"""Table columns (see the caption written by :func:`attitude_bench_markdown`)."""

_SCP, _IPOPT, _IPOPT_AT_SCP, _PATH = "scp", "ipopt", "ipopt @scp", "path_transfer"


@dataclass(frozen=True)
class AttitudeBenchRow:
    """One method on one grid and one objective: result and the timings of the fastest of ``repeat`` runs (s).

    ``solver`` is ``scp``, ``ipopt`` (eigenaxis start), ``ipopt @scp`` (started from the SCP's
    solution) or ``path_transfer``; ``objective`` is ``time`` or ``energy``. Values that do not
    apply are ``None`` (printed ``-``). ``gap`` is relative to the ``ipopt`` row of the same ``K``
    and objective. ``ok``: converged (IPOPT: reported success); ``message`` explains a failure.
    """

    intervals: int | None
    solver: str
    objective: str
    status: str
    tf_s: float | None = None
    energy: float | None = None
    gap: float | None = None
    iterations: int | None = None
    wall_s: float | None = None
    scp_s: float | None = None
    solver_s: float | None = None
    setup_s: float | None = None
    verified: bool | None = None
    margin_deg: float | None = None
    ok: bool = False
    message: str = ""

    @property
    def method(self) -> str:
        return self.solver if self.solver == _PATH else f"{self.solver} {self.objective}"

    @property
    def value(self) -> float | None:
        """The optimised quantity: final time (s) or energy (N^2 m^2 s)."""
        return self.tf_s if self.objective == "time" else self.energy

    def cells(self) -> list[str]:
        """The row as strings, in the order of :data:`COLUMNS`."""
        return [cell(self.intervals, "d"), self.method, self.status,
                cell(self.tf_s, ".6f"), cell(self.energy, ".6e"), cell(self.gap, "+.2e"),
                cell(self.iterations, "d"), cell(self.wall_s, ".4f"),
                cell(self.scp_s, ".4f"), cell(self.solver_s, ".4f"), cell(self.setup_s, ".4f"),
                "-" if self.verified is None else ("yes" if self.verified else "NO"), cell(self.margin_deg, ".4f")]


def _failed(intervals: int | None, solver: str, objective: str):
    """The row a method that raised gets (for :func:`~convexguid.bench_common.timed_method`)."""
    return lambda status, message: AttitudeBenchRow(intervals, solver, objective, status, message=message)


def _variant(spec, intervals: int, tf: float | None = None):
    """``spec`` at ``intervals`` with SCP from the eigenaxis guess: minimum time, or minimum energy at ``tf``."""
    values = {"discretization.intervals": intervals, "method": "scp", "initial_guess": "eigenaxis",
              "boundary.tf_min_time_factor": None, "boundary.tf_from": None,  # the bench sets the final time
              "objective": "time" if tf is None else "energy", "boundary.tf_s": tf}
    return with_values(spec, values)


def _solution_nodes(sol: Solution) -> np.ndarray:
    """The SCP's node rows ``[q, omega (rad/s), u]`` from its nodes table."""
    c = sol.nodes.columns
    return np.column_stack([*(c[f"q{i}"] for i in range(1, 5)), *(np.radians(c[f"omega{i}_degps"]) for i in (1, 2, 3)),
                            *(c[f"u{i}_Nm"] for i in (1, 2, 3))])


def _path_transfer_row(case: AttitudeCase, repeat: int) -> AttitudeBenchRow:
    """The path-transfer planner's maneuver time; ``wall s`` is its planning time (skipped without a rate bound: the
    planner's time law is built on it)."""
    if case.rate_max is None:
        return AttitudeBenchRow(None, _PATH, "time", "skipped", message="no rate bound (the planner needs one)")
    def row(plan, _) -> AttitudeBenchRow:
        return AttitudeBenchRow(None, _PATH, "time", "converged", tf_s=plan.maneuver_time_s,
                                iterations=len(plan.waypoints), wall_s=plan.planning_time_s, ok=True)

    return timed_method(repeat, lambda: plan_path_transfer(path_transfer_problem(case)), lambda p: p.planning_time_s,
                        row, _failed(None, _PATH, "time"))


def _scp_row(spec, objective: str, repeat: int) -> tuple[AttitudeBenchRow, Solution | None]:
    """:func:`solve_quaternion_attitude` on ``spec``: ``wall s`` the whole call, ``SCP s`` its SCP iterations."""
    K = spec.discretization.intervals
    solved: list[Solution] = []

    def row(sol: Solution, _) -> AttitudeBenchRow:
        ok = sol.status == "converged"
        if ok:
            solved.append(sol)
        return AttitudeBenchRow(K, _SCP, objective, sol.status, tf_s=sol.figures.maneuver_time_s if ok else None,
                                energy=sol.objective if ok and objective == "energy" else None,
                                iterations=sol.iterations, wall_s=sol.wall_time_s, scp_s=sol.timing.get("scp_s"),
                                solver_s=sol.timing.get("solver_s"),
                                verified=None if sol.verification is None else sol.verification.passed,
                                margin_deg=sol.figures.node_constraint_margin_deg, ok=ok, message=sol.message)

    scp = timed_method(repeat, lambda: solve_quaternion_attitude(spec), lambda s: s.wall_time_s, row,
                       _failed(K, _SCP, objective))
    return scp, solved[0] if solved else None


def _ipopt_row(case: AttitudeCase, intervals: int, objective: str, repeat: int, solver: str = _IPOPT,
               start: tuple[np.ndarray, float] | None = None) -> AttitudeBenchRow:
    """IPOPT on the NLP of ``case`` from ``start`` (default: the eigenaxis guess); ``setup s`` the fastest build."""
    from convexguid.families.quaternion_attitude.reference import solve_quaternion_attitude_ipopt  # CasADi

    guess, tf_guess = eigenaxis_start(case, intervals) if start is None else start

    def row(best, runs) -> AttitudeBenchRow:
        ok, message = ipopt_outcome(best)
        value = best.objective if ok else None
        tf = value if objective == "time" else (float(case.tf) if ok else None)
        return AttitudeBenchRow(intervals, solver, objective, best.status, tf_s=tf,
                                energy=value if objective == "energy" else None, iterations=best.iterations,
                                wall_s=best.wall_time_s, setup_s=min(r.setup_time_s for r in runs), ok=ok,
                                message=message)

    return timed_method(repeat, lambda: solve_quaternion_attitude_ipopt(case, intervals, guess, tf_guess,
                                                                       tol=IPOPT_TOLERANCE),
                        lambda r: r.wall_time_s, row, _failed(intervals, solver, objective))


def _with_gaps(rows: list[AttitudeBenchRow]) -> list[AttitudeBenchRow]:
    """``gap`` = (value - ipopt's) / ipopt's, signed, for the other rows of the same objective."""
    reference = next((r for r in rows if r.solver == _IPOPT and r.ok and r.value), None)
    if reference is None:
        return rows
    return [replace(r, gap=(r.value - reference.value) / reference.value) if r is not reference and r.ok
            and r.value is not None else r for r in rows]


def _objective_rows(spec, objective: str, repeat: int, with_ipopt: bool) -> tuple[list[AttitudeBenchRow],
                                                                                  Solution | None]:
    """``scp``, ``ipopt`` and ``ipopt @scp`` rows of one objective on one grid, and the SCP solution."""
    K = spec.discretization.intervals
    scp, sol = _scp_row(spec, objective, repeat)
    rows = [scp]
    if with_ipopt:
        case = build_case(spec)
        rows.append(_ipopt_row(case, K, objective, repeat))
        if sol is not None:
            rows.append(_ipopt_row(case, K, objective, repeat, _IPOPT_AT_SCP, (_solution_nodes(sol), scp.tf_s)))
    return _with_gaps(rows), sol


def bench_attitude_rows(spec, intervals_list: Sequence[int] = DEFAULT_INTERVALS,
                        repeat: int = 3, with_ipopt: bool | None = None,
                        progress: bool = False) -> list[AttitudeBenchRow]:
    """Benchmark rows: ``path_transfer``, then per ``K`` the minimum-time and minimum-energy rows.

    Parameters
    ----------
    spec : QuaternionAttitudeProblem
        The loaded ``quaternion_attitude`` problem (e.g. of ``problems/wang_multicone_time.yaml``).
    intervals_list : sequence of int
        Hermite-Simpson interval counts :math:`K`.
    repeat : int
        Timed runs per case; the fastest (by wall time) is kept.
    with_ipopt : bool, optional
        Also solve with CasADi + IPOPT; default: when ``casadi`` is installed.
    progress : bool
        Print one line per finished row.

    Returns
    -------
    list of AttitudeBenchRow
        The energy rows of a ``K`` whose minimum-time SCP did not converge are one ``skipped`` row.

    Raises
    ------
    ValueError
        If the file is not of the ``quaternion_attitude`` family.
    """
    if spec.family != "quaternion_attitude":
        raise ValueError(f"{spec.source}: family {spec.family!r}, expected 'quaternion_attitude'")
    with_ipopt = casadi_available() if with_ipopt is None else with_ipopt

    def report(new: list[AttitudeBenchRow]) -> list[AttitudeBenchRow]:
        for r in new if progress else ():
            wall = "" if r.wall_s is None else f"{r.wall_s:.3f} s"
            print(f"  done: K = {'-' if r.intervals is None else r.intervals:<4} {r.method:<20} {r.status:<18} {wall}",
                  flush=True)
        return new

    rows = report([_path_transfer_row(build_case(spec), repeat)])
    for K in intervals_list:
        time_rows, sol = _objective_rows(_variant(spec, K), "time", repeat, with_ipopt)
        rows += report(time_rows)
        if sol is None:
            rows += report([AttitudeBenchRow(K, _SCP, "energy", "skipped",
                                             message="the minimum-time SCP (which sets tf) did not converge")])
            continue
        energy_rows, _ = _objective_rows(_variant(spec, K, ENERGY_TF_FACTOR * time_rows[0].tf_s), "energy",
                                         repeat, with_ipopt)
        rows += report(energy_rows)
    return rows


def _find(rows: Sequence[AttitudeBenchRow], K: int, solver: str, objective: str) -> AttitudeBenchRow | None:
    return next((r for r in rows if r.intervals == K and r.solver == solver and r.objective == objective), None)


def _speed_line(rows: Sequence[AttitudeBenchRow], grids: Sequence[int], objective: str) -> str | None:
    """SCP alone vs IPOPT (solve + setup) at every grid where both converged."""
    parts, faster = [], []
    for K in grids:
        scp, ipopt = _find(rows, K, _SCP, objective), _find(rows, K, _IPOPT, objective)
        if scp is None or ipopt is None or not (scp.ok and ipopt.ok) or not scp.scp_s:
            continue
        ipopt_s = ipopt.wall_s + (ipopt.setup_s or 0.0)
        parts.append(f"K = {K}: SCP {scp.scp_s:.3f} s (whole solve {scp.wall_s:.3f} s) vs IPOPT {ipopt_s:.3f} s "
                     f"(solve {ipopt.wall_s:.3f} + setup {ipopt.setup_s:.3f})")
        if scp.scp_s < ipopt_s:
            faster.append(K)
    if not parts:
        return None
    verdict = (f"SCP faster at K = {', '.join(map(str, faster))}" if faster else "SCP faster at no K")
    return f"minimum {objective}, SCP alone vs IPOPT solve + setup: {verdict}; " + "; ".join(parts)


def _notes(rows: Sequence[AttitudeBenchRow], target_s: float | None = None) -> list[str]:
    """Targets, speed comparison, local optima seen by IPOPT, tightened SCP rows, then failures."""
    lines = []
    grids = list(dict.fromkeys(r.intervals for r in rows if r.intervals is not None))
    pairs = [(K, _find(rows, K, _SCP, "time"), _find(rows, K, _IPOPT, "time")) for K in grids]
    gaps = [(K, s.gap) for K, s, i in pairs if s is not None and i is not None and s.ok and i.ok and s.gap is not None]
    if gaps:
        compared = [K for K, s, i in pairs if i is not None]
        within = len(gaps) == len(compared) and all(abs(g) <= TIME_GAP_TARGET for _, g in gaps)
        worst_K, worst = max(gaps, key=lambda kg: abs(kg[1]))
        lines.append(f"SCP minimum time within {TIME_GAP_TARGET:.0%} of IPOPT's (eigenaxis start) at every K: "
                     f"{'yes' if within else 'NO'} (largest |gap| {abs(worst):.2e} at K = {worst_K}; "
                     + ", ".join(f"K = {K}: {g:+.2e}" for K, g in gaps) + ")")
    if grids:
        K = min(grids, key=lambda k: abs(k - SCP_TARGET_INTERVALS))
        scp = _find(rows, K, _SCP, "time")
        if scp is not None and scp.ok and scp.wall_s is not None:
            def met(t: float | None) -> str:
                if target_s is None:
                    return ""
                return " (-)" if t is None else (" (met)" if t < target_s else " (NOT met)")

            goal = "" if target_s is None else f" under {target_s:g} s"
            lines.append(f"SCP minimum time at K = {K} ({K + 1} nodes){goal}: whole solve "
                         f"{scp.wall_s:.3f} s{met(scp.wall_s)}, SCP alone {scp.scp_s:.3f} s{met(scp.scp_s)}")
    for objective in ("time", "energy"):
        line = _speed_line(rows, grids, objective)
        if line:
            lines.append(line)
    for K in grids:
        for objective in ("time", "energy"):
            a, b = _find(rows, K, _IPOPT, objective), _find(rows, K, _IPOPT_AT_SCP, objective)
            if a is None or b is None or not (a.ok and b.ok) or b.gap is None or abs(b.gap) <= LOCAL_OPTIMUM_RTOL:
                continue
            unit = "s" if objective == "time" else "N^2 m^2 s"
            lines.append(f"K = {K}, minimum {objective}: IPOPT ends at different local optima of the same NLP from "
                         f"the eigenaxis guess ({a.value:.6g} {unit}) and from the SCP's solution ({b.value:.6g} "
                         f"{unit}), {b.gap:+.2e} apart")
    tightened = [f"K = {r.intervals} {r.objective} ({r.margin_deg:.4f} deg)" for r in rows
                 if r.solver == _SCP and r.margin_deg]
    if tightened:
        lines.append("SCP re-solved with node constraints tightened after a failed dense check (so on a slightly "
                     "more constrained NLP than IPOPT's; the rate box may be tightened too): " + ", ".join(tightened))
    for r in rows:
        if not r.ok:
            status = "failed" if r.status.startswith("failed") else r.status
            where = "" if r.intervals is None else f"K = {r.intervals}, "
            lines.append(f"{where}{r.method}: {status}: {one_line(r.message, 200)}")
        elif r.verified is False:
            lines.append(f"K = {r.intervals}, {r.method}: converged but the dense verification FAILED")
    return lines


def _command(problem_path: str, intervals_list: Sequence[int], repeat: int,
             output: str | PathLike[str] | None) -> str:
    args = ["convexguid", "bench", problem_path, "--nodes", *map(str, intervals_list), "--repeat", str(repeat)]
    return shlex.join(args + (["--output", str(output)] if output is not None else []))


def attitude_bench_markdown(rows: Sequence[AttitudeBenchRow], problem_path: str,
                            intervals_list: Sequence[int], repeat: int, ipopt_note: str | None = None,
                            output: str | PathLike[str] | None = None) -> str:
    """The benchmark as a markdown document: machine, versions, threads, date, command, caption, table, notes."""
    caption = (
        f"Best of {repeat} runs per case, times in seconds. `K`: Hermite-Simpson intervals (K + 1 nodes). "
        "`path_transfer`: the path-transfer planner (independent of K), `wall s` its planning time, `iterations` "
        "its way-points. `scp`: `convexguid solve` with `initial_guess: eigenaxis` "
        "(`solve_quaternion_attitude`); `wall s` is the whole call (guess, SCP, dense verification, "
        "tightening re-solves), `SCP s` the SCP iterations alone (`timing.scp_s`), `solver s` the convex "
        "solver within them, `iterations` SCP iterations (re-solves included), `verified` the dense check, "
        "`margin deg` the node-constraint margin after tightening. `ipopt`: the same NLP (margin 0) in CasADi, "
        f"IPOPT with exact Hessian (MUMPS, tol = {IPOPT_TOLERANCE:g}) from the same eigenaxis guess; `wall s` "
        "is the solve call, `setup s` builds the CasADi model. `ipopt @scp`: that NLP started from the SCP's "
        "solution instead (a lower value than `ipopt` means the eigenaxis start ended at a worse local "
        f"optimum). `energy` rows: minimum energy at tf = {ENERGY_TF_FACTOR:g} x the SCP minimum time of "
        "the same K; energy is Simpson's rule on the nodes' torque. `gap to ipopt` = (value - ipopt's) / "
        "ipopt's, signed, same K and objective.")
    align = ["---:", ":---", ":---"] + ["---:"] * (len(COLUMNS) - 3)
    table = markdown_grid(COLUMNS, align, [r.cells() for r in rows])
    return bench_document(
        f"convexguid attitude benchmark: SCP vs IPOPT on `{Path(problem_path).name}` against the grid size",
        ("numpy", "scipy", "clarabel", "piqp", "casadi"), _command(problem_path, intervals_list, repeat, output),
        caption, table, _notes(rows, SCP_WALL_TARGETS_S.get(Path(problem_path).name)), ipopt_note)


def run_attitude_bench(spec, intervals_list: Sequence[int] = DEFAULT_INTERVALS,
                       repeat: int = 3, output: str | PathLike[str] | None = None) -> int:
    """Run :func:`bench_attitude_rows` on the loaded problem ``spec``, print the markdown document, optionally write
    it to ``output``.

    Returns
    -------
    int
        0 if every method that ran converged, else 1. Without ``casadi`` the IPOPT rows are
        skipped (noted in the document), which does not count as a failure.
    """
    with_ipopt, ipopt_note = ipopt_availability("rows")
    rows = bench_attitude_rows(spec, intervals_list, repeat, with_ipopt, progress=True)
    text = attitude_bench_markdown(rows, spec.source, intervals_list, repeat, ipopt_note, output)
    print()
    print(text, end="")
    if output is not None:
        write_text_atomic(Path(output), text)
        print(f"table written to {output}")
    return 0 if all(r.ok for r in rows) else 1


def bench_command(spec, args: argparse.Namespace, planner: object = None) -> int:
    """``convexguid bench`` on a ``quaternion_attitude`` file: ``--nodes`` are interval counts ``K``.

    Without ``--nodes``, :data:`DEFAULT_INTERVALS`; ``--backends`` does not apply (the SCP uses the file's backend);
    ``planner`` is unused (the benchmark plans this problem only).
    """
    intervals = DEFAULT_INTERVALS if args.nodes is None else args.nodes
    return run_attitude_bench(spec, intervals, args.repeat, args.output)
