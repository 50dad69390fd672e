"""The contract between a problem family and the rest of convexguid.

A family is one folder ``convexguid/families/<name>/`` whose ``__init__`` exports ``FAMILY``, a
:class:`Family`. The registry (:mod:`convexguid.families`) lists them; the loader, the API, the
command line and the report reach a family only through it. A family's ``__init__`` imports only
its spec model and its figures dataclass at module level; ``solve``, ``plot`` and ``bench`` import
the heavy modules (SCP, matplotlib, CasADi) when they are called.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from convexguid.sizes import DEFAULT_MEMORY_LIMIT_BYTES, SizeEstimate, check_size
from convexguid.spec.common import ProblemBase

if TYPE_CHECKING:
    from convexguid.reference import IndependentOptimum
    from convexguid.scp.check_repair import PlanningSetup
    from convexguid.scp.engine import IterationRecord
    from convexguid.solution import Figures, Solution

class Planner(Protocol):
    """What a family may ask of the rest of convexguid without importing it (a family that flies another problem
    file's plan, such as ``lpmpc``'s nominal, loads and plans it through this; the registry, which imports every
    family, is never imported by one). :mod:`convexguid.api` passes its own to every hook that takes one."""

    def load(self, path: str | PathLike[str], overrides: tuple[str, ...] | list[str] = ()) -> ProblemBase:
        """The problem file ``path`` of any family, with ``overrides`` (``convexguid.load_problem``)."""

    def solve(self, spec: ProblemBase) -> Solution:
        """``spec`` planned (or simulated) and verified (``convexguid.solve``)."""


@dataclass(frozen=True)
class Family:
    """One problem family.

    Attributes
    ----------
    name : str
        The value of the problem file's ``family`` key.
    spec_model : type of ProblemBase
        Pydantic model of the problem file (its ``family`` field is ``Literal[name]``).
    solve : callable
        ``solve(spec, log, planner) -> Solution``; for a simulated family, the closed-loop simulation. ``planner``
        (a :class:`Planner`) is for a family that needs another problem file's plan; the others ignore it.
    plot : callable
        ``plot(solution, out_dir, save) -> list[Path]``, ``save`` the shared figure writer
        (:func:`convexguid.figure_files.save_figure`); imports matplotlib only when called.
    verification_method : str
        How the solution is checked, as the report words it ("Dense verification (N points, <this>)").
    figures : type of Figures
        The dataclass (:class:`~convexguid.solution.Figures`) of the family's summary figures: its fields are the
        figure names a problem file may name (``reference.comparison.figures``, ``boundary.tf_from.figure``).
    simulated : bool
        Run by ``convexguid simulate`` (a controller in closed loop) instead of planned by ``convexguid solve``.
    key_figures : tuple of (summary key, label)
        Summary figures the validation report lists under each case of the family (fields of ``figures``).
    planning_setup : callable or None
        ``planning_setup(spec) -> PlanningSetup`` (:mod:`convexguid.scp.check_repair`) for a planned family: how it
        builds the SCP program, with which settings, and its checker (dense verification and repairs). ``solve``
        runs it through the engine's check-repair loop and summarises; None for a simulated family.
    report_section : callable or None
        ``report_section(spec, solution) -> list[str]``: markdown the validation report adds under the case (e.g.
        the paper's tables beside the family's figures); it renders, it computes nothing. None: nothing extra.
        It must not show compute times (the committed report is the same on every run): those go to
        ``timing_section``.
    timing_section : callable or None
        ``timing_section(spec, solution) -> list[str]``: markdown of the case's compute times for the validation
        timings file (:mod:`convexguid.validation.timings`, not committed), e.g. LPMPC update times. None: nothing.
    bench : callable or None
        ``bench(spec, args, planner) -> int`` (exit code) for ``convexguid bench`` on the loaded problem ``spec``
        (``spec.source`` is its file); None if the family has none.
        ``args.nodes`` is None unless the command line gave ``--nodes`` (the family picks its own default).
    console_header : callable or None
        ``console_header(spec) -> str``: the line the command line prints before a run (unless ``--quiet``),
        e.g. the simulated time and step. None: none.
    console_details : callable or None
        ``console_details(solution) -> list[str]``: lines the command line prints after the run, before the result
        block (unless ``--quiet``), e.g. one line per case of a sweep. None: none.
    independent_optimum : callable or None
        ``independent_optimum(spec, solution, starts) -> IndependentOptimum`` (:mod:`convexguid.reference`): the
        best objective an independent method reaches on the problem ``solution`` solved (IPOPT on the same NLP from
        ``starts`` starts, or a convex relaxation that also certifies infeasibility); the robustness benchmark
        judges plans by it. The solution only supplies inputs the spec leaves to the solve (a final time set as a
        multiple of the minimum time), never a start.
        None: the family has no such reference.
    estimate_size : callable or None
        ``estimate_size(spec) -> SizeEstimate`` (:mod:`convexguid.sizes`): the peak memory of a run estimated from
        the spec alone (cheap: no program is built), with the key that drives it. None: no limit.
    memory_limit_bytes : float
        The most memory :meth:`check_size` lets a run of this family need.
    """

    name: str
    spec_model: type[ProblemBase]
    solve: Callable[[ProblemBase, Callable[[IterationRecord], None] | None, Planner], Solution]
    plot: Callable[[Solution, Path], list[Path]]
    verification_method: str
    figures: type[Figures]
    simulated: bool = False
    key_figures: tuple[tuple[str, str], ...] = ()
    planning_setup: Callable[[ProblemBase], PlanningSetup] | None = None
    report_section: Callable[[ProblemBase, Solution], list[str]] | None = None
    timing_section: Callable[[ProblemBase, Solution], list[str]] | None = None
    bench: Callable[[ProblemBase, argparse.Namespace, Planner], int] | None = None
    console_header: Callable[[ProblemBase], str] | None = None
    console_details: Callable[[Solution], list[str]] | None = None
    independent_optimum: Callable[[ProblemBase, Solution, int], IndependentOptimum] | None = None
    estimate_size: Callable[[ProblemBase], SizeEstimate] | None = None
    memory_limit_bytes: float = DEFAULT_MEMORY_LIMIT_BYTES

    def check_size(self, spec: ProblemBase) -> None:
        """Refuse ``spec`` (one-line SpecError naming the key, the estimate and the limit) if its estimated memory
        is above :attr:`memory_limit_bytes`; nothing without :attr:`estimate_size`."""
        if self.estimate_size is not None:
            check_size(spec.source, self.name, self.estimate_size(spec), self.memory_limit_bytes)
