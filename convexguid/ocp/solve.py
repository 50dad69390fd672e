"""Solve a user's :class:`~convexguid.ocp.problem.Problem`: the engine's check-repair loop, and a
:class:`~convexguid.solution.Solution` like every family's (status, summary JSON, node and dense tables)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from convexguid.ocp.chebyshev import MappedChebyshevProgram
from convexguid.ocp.check import DenseChecker
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.ocp.hold import FirstOrderHoldProgram, ZeroOrderHoldProgram
from convexguid.ocp.transcription import Transcription
from convexguid.scp.check_repair import solve_verified
from convexguid.scp.engine import Log
from convexguid.scp.problem import ProgramSize, SCPSettings
from convexguid.solution import Figures, Solution, Trajectory, planned_solution
from convexguid.threads import single_threaded

if TYPE_CHECKING:  # the problem module imports this one when it solves
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


TRANSCRIPTIONS = {program.method: program
                  for program in (HermiteSimpsonProgram, ZeroOrderHoldProgram, FirstOrderHoldProgram,
                                  MappedChebyshevProgram)}
"""Every transcription by the name :meth:`~convexguid.ocp.problem.Problem.transcription` takes."""


def transcribe(problem: Problem) -> Transcription:
    """The problem transcribed as it says (Hermite-Simpson unless it chose a hold)."""
    return TRANSCRIPTIONS[problem.method](problem)


def program_size(program: Transcription, z: np.ndarray) -> ProgramSize:
    """The NLP's dimensions as transcribed: its variables, its equality rows (the defects as the transcription
    collocates them, path and boundary equalities, the fixed boundary values and affine boundary rows) and its path
    constraint rows."""
    equalities = sum(block.values.size for block in program.evaluate(z, jacobians=False).equalities)
    return ProgramSize(program.num_variables, equalities + program.linear_constraints().A.shape[0],
                       program.num_path)


def solve_problem(problem: Problem, max_iterations: int = 300, verification_points: int = 20,
                  log: Log | None = None) -> Solution:
    """Plan ``problem`` by SCP from its straight-line guess, verify it densely, repair, summarise (``log`` gets one
    record per SCP iteration)."""
    started = time.perf_counter()
    program = transcribe(problem)
    if problem.objective in ("time", "terminal"):
        # weights in units of the objective's size (the guessed final time; a terminal cost's change when the
        # final state moves by its scales): an absolute weight let COPS' hang glider trade defects for range
        settings = SCPSettings(max_iterations=max_iterations, penalty_unit="objective", penalty=30.0, penalty_max=3e6)
    else:
        # the straight-line guess often has zero control energy: absolute weights, escalated when too small
        settings = SCPSettings(max_iterations=max_iterations)
    with single_threaded():
        outcome = solve_verified(program, settings, DenseChecker(verification_points), log)
    final = outcome.program
    z = final.unwrapped(outcome.x)
    tf = final.final_time(z)
    nodes_t = tf * final.node_shares()
    columns = {v.name: final.states(z)[:, i] for i, v in enumerate(problem.states)}
    columns |= {v.name: final.node_controls(z)[:, j] for j, v in enumerate(problem.controls)}
    dense = None
    if outcome.check is not None:
        track = outcome.check.track
        dense = Trajectory(track.t, {v.name: track.x[:, i] for i, v in enumerate(problem.states)}
                           | {v.name: track.u[:, j] for j, v in enumerate(problem.controls)})
    return planned_solution(_Statement(problem.name), outcome, started, program_size(final, outcome.x),
                            nodes=Trajectory(nodes_t, columns), dense=dense,
                            figures=OcpFigures(final_time_s=tf, states=tuple(v.name for v in problem.states),
                                               controls=tuple(v.name for v in problem.controls),
                                               parameters={name: float(columns[name][0])
                                                           for name in problem.parameter_names} or None,
                                               units={v.name: v.unit for v in (*problem.states, *problem.controls)
                                                      if v.unit} or None))
