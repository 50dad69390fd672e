"""Solve a user's :class:`~convexguid.ocp.problem.Problem`: the engine's check-repair loop, and a
:class:`~convexguid.solution.Solution` like every family's (status, summary JSON, node and dense tables)."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from convexguid.backends.registry import check_backend_name
from convexguid.errors import BackendError, SpecError
from convexguid.ocp.chebyshev import MappedChebyshevProgram
from convexguid.ocp.check import DenseChecker
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.ocp.hold import ClosedFormFlowProgram, FirstOrderHoldProgram, ZeroOrderHoldProgram
from convexguid.ocp.phased import Link, PhasedChecker, PhasedProgram
from convexguid.ocp.scaling import scale_advice
from convexguid.ocp.transcription import Transcription
from convexguid.scp.check_repair import VerifiedSolve, solve_verified
from convexguid.scp.engine import Log
from convexguid.scp.problem import ProgramSize, SCPSettings
from convexguid.solution import Figures, Solution, Trajectory, optional, planned_solution
from convexguid.threads import single_threaded

if TYPE_CHECKING:  # the problem and phases modules import this one when they solve
    from convexguid.ocp.phases import Phases
    from convexguid.ocp.problem import Problem


@dataclass(frozen=True)
class _Statement:
    """What :func:`~convexguid.solution.planned_solution` reads of a problem file, for a problem stated in Python."""

    name: str
    family: str = "ocp"
    method: str = "scp"


@dataclass(frozen=True)
class OcpFigures(Figures):
    """The summary figures of a user's problem: the final time (s), the names of its states and controls, the
    planned value of each parameter, and the units the problem gave its variables."""

    final_time_s: float | None = None
    states: tuple[str, ...] = ()
    controls: tuple[str, ...] = ()
    parameters: dict[str, float] | None = None
    units: dict[str, str] | None = None
    phases: dict[str, dict] | None = optional()
    """A maneuver in phases: each phase's start and duration (s), transcription and intervals."""


TRANSCRIPTIONS = {program.method: program
                  for program in (HermiteSimpsonProgram, ZeroOrderHoldProgram, FirstOrderHoldProgram,
                                  MappedChebyshevProgram, ClosedFormFlowProgram)}
"""Every transcription by the name :meth:`~convexguid.ocp.problem.Problem.transcription` takes."""


def transcribe(problem: Problem | Phases) -> Transcription | PhasedProgram:
    """The problem transcribed as it says (Hermite-Simpson unless it chose another method); a maneuver in phases
    as every phase says, with its links and its first guess (:meth:`~convexguid.ocp.phases.Phases.guess`)."""
    phases = getattr(problem, "phases", None)  # a Phases (which imports this module when it solves)
    if phases is not None:
        problem.check()
        programs = [transcribe(p) for p in phases]
        return PhasedProgram(programs, tuple(Link(*link) for link in problem.links), problem.guess(programs))
    return TRANSCRIPTIONS[problem.method](problem)


def program_size(program: Transcription, z: np.ndarray) -> ProgramSize:
    """The NLP's dimensions as transcribed: its variables, its equality rows (the defects as the transcription
    collocates them, path and boundary equalities, the fixed boundary values and affine boundary rows) and its path
    constraint rows."""
    equalities = sum(block.values.size for block in program.evaluate(z, jacobians=False).equalities)
    return ProgramSize(program.num_variables, equalities + program.linear_constraints().A.shape[0],
                       program.num_path)


def _settings(objectives: list[str | None], max_iterations: int, backend: str = "auto") -> SCPSettings:
    """The engine's settings for these objectives (of a problem, or of its phases), its subproblems on ``backend``."""
    if any(o in ("time", "terminal") for o in objectives):
        # weights in units of the objective's size (the guessed final time; a terminal cost's change when the
        # final state moves by its scales): an absolute weight let COPS' hang glider trade defects for range
        return SCPSettings(max_iterations=max_iterations, backend=backend, penalty_unit="objective", penalty=30.0,
                           penalty_max=3e6)
    # the straight-line guess often has zero control energy: absolute weights, escalated when too small
    return SCPSettings(max_iterations=max_iterations, backend=backend)


def checked_backend(where: str, backend: str) -> str:
    """``backend`` when it names an installed backend (or ``auto``), else one line naming the call and what is
    installed."""
    if not isinstance(backend, str):
        raise SpecError(f"{where}: backend: expected a backend's name (got {backend!r})")
    try:
        check_backend_name(backend)
    except BackendError as error:
        raise SpecError(f"{where}: backend: {error.args[0]}") from None
    return backend


def solve_problem(problem: Problem, max_iterations: int = 300, verification_points: int = 20,
                  log: Log | None = None, backend: str = "auto") -> Solution:
    """Plan ``problem`` by SCP from its straight-line guess, verify it densely, repair, summarise (``log`` gets one
    record per SCP iteration; ``backend`` solves the subproblems)."""
    started = time.perf_counter()
    backend = checked_backend(f"{problem.name}: solve", backend)
    program = transcribe(problem)
    with single_threaded():
        outcome = solve_verified(program, _settings([problem.objective], max_iterations, backend),
                                 DenseChecker(verification_points), log)
    final = outcome.program
    outcome = _advised(outcome, [(final, outcome.x)])
    nodes, dense = _tables(final, outcome.x, outcome.check.track if outcome.check is not None else None)
    return planned_solution(_Statement(problem.name), outcome, started, program_size(final, outcome.x),
                            nodes=nodes, dense=dense, figures=_figures([problem], nodes, final.final_time(
                                final.unwrapped(outcome.x))))


def _advised(outcome: VerifiedSolve, plans: list[tuple[Transcription, np.ndarray]]) -> VerifiedSolve:
    """``outcome``, its message naming the estimated state scales its last plan outgrew when it did not converge
    (:func:`~convexguid.ocp.scaling.scale_advice`; each plan a program and its part of the iterate)."""
    if outcome.status == "converged":
        return outcome
    advice = "; ".join(f"{t.problem.name}: {said}" if len(plans) > 1 else said for t, x in plans
                       if (said := scale_advice(t, t.unwrapped(x))))
    return replace(outcome, message=f"{outcome.message}; {advice}") if advice else outcome


def _tables(program: Transcription, x: np.ndarray, track, start: float = 0.0) -> tuple[Trajectory, Trajectory | None]:
    """The node table and the dense table (None without a check) of one problem's plan, its time from ``start``."""
    problem = program.problem
    z = program.unwrapped(x)
    columns = {v.name: program.states(z)[:, i] for i, v in enumerate(problem.states)}
    columns |= {v.name: program.node_controls(z)[:, j] for j, v in enumerate(problem.controls)}
    nodes = Trajectory(start + program.final_time(z) * program.node_shares(), columns)
    if track is None:
        return nodes, None
    return nodes, Trajectory(start + track.t, {v.name: track.x[:, i] for i, v in enumerate(problem.states)}
                             | {v.name: track.u[:, j] for j, v in enumerate(problem.controls)})


def _figures(problems: list[Problem], nodes: Trajectory, final_time: float, phases=None) -> OcpFigures:
    variables = [v for p in problems for v in (*p.states, *p.controls)]
    return OcpFigures(final_time_s=final_time,
                      states=tuple(dict.fromkeys(v.name for p in problems for v in p.states)),
                      controls=tuple(dict.fromkeys(v.name for p in problems for v in p.controls)),
                      parameters={name: _first(nodes.columns[name]) for p in problems
                                  for name in p.parameter_names} or None,
                      units={v.name: v.unit for v in variables if v.unit} or None, phases=phases)


def _first(column: np.ndarray) -> float:
    """A parameter's planned value: its first in the table (the phases without it leave NaN)."""
    return float(column[~np.isnan(column)][0])


def _joined(tables: list[Trajectory]) -> Trajectory:
    """Phases' tables one after the other: every column any of them has (NaN where a phase has not), and
    ``phase``, the index of the phase each row belongs to."""
    names = list(dict.fromkeys(name for table in tables for name in table.columns))
    columns = {"phase": np.concatenate([np.full(table.t.size, float(i)) for i, table in enumerate(tables)])}
    for name in names:
        columns[name] = np.concatenate([table.columns.get(name, np.full(table.t.size, np.nan)) for table in tables])
    return Trajectory(np.concatenate([table.t for table in tables]), columns)


def solve_phases(statement: Phases, started: float, max_iterations: int = 300, verification_points: int = 20,
                 log: Log | None = None, backend: str = "auto") -> Solution:
    """Plan a maneuver in phases (:class:`~convexguid.ocp.phases.Phases`): every phase transcribed as it says, the
    links, the engine's check-repair loop with every phase checked densely, one solution over the whole maneuver."""
    backend = checked_backend(f"{statement.name}: solve", backend)
    program = transcribe(statement)
    with single_threaded():
        outcome = solve_verified(program, _settings([p.objective for p in statement.phases], max_iterations,
                                                    backend),
                                 PhasedChecker(verification_points), log)
    final: PhasedProgram = outcome.program
    outcome = _advised(outcome, list(zip(final.phases, final.pieces(outcome.x), strict=True)))
    checks = outcome.check.track.phases if outcome.check is not None else [None] * len(final.phases)
    start, nodes, dense, phases = 0.0, [], [], {}
    for t, piece, check in zip(final.phases, final.pieces(outcome.x), checks, strict=True):
        node_table, dense_table = _tables(t, piece, check.track if check is not None else None, start)
        nodes.append(node_table)
        dense.append(dense_table)
        duration = t.final_time(piece)
        phases[t.problem.name] = {"start_s": start, "duration_s": duration, "method": t.method, "intervals": t.N}
        start += duration
    size = [program_size(t, piece) for t, piece in zip(final.phases, final.pieces(outcome.x), strict=True)]
    equal_links = int(final.link_equality.sum())
    total = ProgramSize(final.num_variables, sum(s.num_equality_constraints for s in size) + equal_links,
                        sum(s.num_inequality_constraints for s in size) + final.link_equality.size - equal_links)
    node_table = _joined(nodes)
    return planned_solution(_Statement(statement.name), outcome, started, total, nodes=node_table,
                            dense=_joined(dense) if outcome.check is not None else None,
                            figures=_figures(statement.phases, node_table, start, phases))
