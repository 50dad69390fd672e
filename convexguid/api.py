"""Python entry points: load a problem, solve or simulate it, validate against the papers."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from convexguid.errors import SpecError
from convexguid.families import FAMILIES, get_family
from convexguid.spec import ProblemSpec, load_problem

if TYPE_CHECKING:
    from convexguid.scp.engine import IterationRecord
    from convexguid.solution import Solution


def _spec(problem: str | Path | ProblemSpec, overrides: Sequence[str]) -> ProblemSpec:
    """``problem`` loaded (a YAML path) or reloaded with ``overrides`` (a spec)."""
    if isinstance(problem, ProblemSpec):
        return load_problem(problem.source, overrides) if overrides else problem
    return load_problem(problem, overrides)


def _check_resolved(spec: ProblemSpec) -> None:
    """Refuse a problem that still takes an input from another case's result (only validate resolves it)."""
    for key, link_key, link in spec.input_links():
        raise SpecError(f"{spec.source}: {link_key}: takes {link.figure} from the result of problem {link.problem!r}, "
                        f"which only `convexguid validate` resolves; run this file through convexguid validate "
                        f"together with that problem's file, or set {key} instead (e.g. --set {link_key}=null "
                        f"--set {key}=<value>)")


def solve(problem: str | Path | ProblemSpec, overrides: Sequence[str] = (),
          log: Callable[[IterationRecord], None] | None = None) -> Solution:
    """Plan and verify ``problem`` (a YAML path or a loaded spec).

    ``overrides`` are ``dotted.key=value`` strings as for ``convexguid solve --set``;
    ``log`` receives one :class:`~convexguid.scp.engine.IterationRecord` per SCP iteration.
    A simulated family (``potential_function``) is simulated as by :func:`simulate` (``log`` is unused).

    Raises
    ------
    SpecError
        For invalid input, or an input taken from another case's result (e.g. ``boundary.tf_from``),
        which only :func:`convexguid.report.validation.validate` resolves.
    """
    spec = _spec(problem, overrides)
    _check_resolved(spec)
    return get_family(spec.family).solve(spec, log)


def simulate(problem: str | Path | ProblemSpec, overrides: Sequence[str] = ()) -> Solution:
    """Simulate ``problem`` (a YAML path or a loaded spec of a simulated family, e.g. ``potential_function``).

    ``overrides`` are ``dotted.key=value`` strings as for ``convexguid simulate --set``. See
    :func:`convexguid.sim.runner.simulate_problem` for the status, checks and summary figures.

    Raises
    ------
    SpecError
        For invalid input or a family that is planned, not simulated (use :func:`solve`).
    """
    spec = _spec(problem, overrides)
    _check_resolved(spec)
    family = get_family(spec.family)
    if not family.simulated:
        simulated = ", ".join(name for name, f in FAMILIES.items() if f.simulated)
        raise SpecError(f"{spec.source}: family: {spec.family!r} is planned, not simulated; use convexguid solve "
                        f"(simulate handles: {simulated})")
    return family.solve(spec, None)
