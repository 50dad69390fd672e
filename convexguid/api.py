"""Python entry points: load a problem, solve or simulate it, validate against the papers."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

from convexguid.checks import optional_callable, override_list
from convexguid.errors import SpecError, value_text
from convexguid.families import FAMILIES, Family, get_family
from convexguid.problem_files import load_problem
from convexguid.spec import ProblemSpec
from convexguid.spec.loader import with_overrides
from convexguid.threads import single_threaded

if TYPE_CHECKING:
    from convexguid.scp.engine import IterationRecord
    from convexguid.solution import Solution


def _spec(problem: str | Path | ProblemSpec, overrides: Sequence[str] | str | None) -> ProblemSpec:
    """``problem`` loaded (a YAML path) or reloaded with ``overrides`` (a spec), the arguments checked first."""
    overrides = override_list(overrides)
    if isinstance(problem, ProblemSpec):
        return with_overrides(problem, overrides) if overrides else problem
    if not isinstance(problem, (str, PathLike)):
        raise SpecError(f"problem: expected the path of a problem YAML file or a loaded spec (got "
                        f"{value_text(problem)}); e.g. convexguid.solve('problems/cai2018_flat_attitude.yaml')")
    return load_problem(problem, overrides)


def check_resolved(spec: ProblemSpec) -> None:
    """Refuse a problem that still takes an input from another case's result (the command line resolves it,
    :func:`convexguid.validation.links.resolve_links`; the Python API does not solve another problem unasked)."""
    for key, link_key, link in spec.input_links():
        raise SpecError(f"{spec.source}: {link_key}: takes {link.figure} from the result of problem {link.problem!r}, "
                        f"which the Python API does not solve; resolve it first (convexguid.validation.links."
                        f"resolve_links, as the convexguid commands do), or set {key} instead (overrides "
                        f"'{link_key}=null', '{key}=<value>')")


def check_runnable(spec: ProblemSpec) -> Family:
    """The family of ``spec`` once the spec can run: no input waits for another case's result
    (:func:`check_resolved`) and the estimated memory is within the family's limit (:meth:`Family.check_size`).

    Raises
    ------
    SpecError
        One line naming the key (and for a size, the estimate and the limit).
    """
    check_resolved(spec)
    family = get_family(spec.family)
    family.check_size(spec)
    return family


def solve(problem: str | Path | ProblemSpec, overrides: Sequence[str] | str | None = (),
          log: Callable[[IterationRecord], None] | None = None) -> Solution:
    """Plan and verify ``problem`` (a YAML path or a loaded spec).

    ``overrides`` are ``dotted.key=value`` strings as for ``convexguid solve --set`` (None: none; a single string:
    one override); ``log`` (a function or None) receives one :class:`~convexguid.scp.engine.IterationRecord` per
    SCP iteration.
    A simulated family (``potential_function``) is simulated as by :func:`simulate` (``log`` is unused).

    Raises
    ------
    SpecError
        For invalid input (arguments of the wrong type included), a problem above its family's size limit, or an
        input taken from another case's result (e.g. ``boundary.tf_from``; resolve it first with
        :func:`convexguid.validation.links.resolve_links`).
    """
    optional_callable("log", log)
    spec = _spec(problem, overrides)
    with single_threaded():
        return check_runnable(spec).solve(spec, log, PLANNER)


def simulate(problem: str | Path | ProblemSpec, overrides: Sequence[str] | str | None = ()) -> Solution:
    """Simulate ``problem`` (a YAML path or a loaded spec of a simulated family, e.g. ``potential_function``).

    ``overrides`` are ``dotted.key=value`` strings as for ``convexguid simulate --set`` (None: none; a single
    string: one override). See
    :func:`convexguid.families.potential_function.runner.simulate_problem` for the status, checks and summary figures.

    Raises
    ------
    SpecError
        For invalid input, a problem above its family's size limit, or a family that is planned, not simulated
        (use :func:`solve`).
    """
    spec = _spec(problem, overrides)
    family = check_runnable(spec)
    if not family.simulated:
        simulated = ", ".join(name for name, f in FAMILIES.items() if f.simulated)
        raise SpecError(f"{spec.source}: family: {spec.family!r} is planned, not simulated; use convexguid solve "
                        f"(simulate handles: {simulated})")
    with single_threaded():
        return family.solve(spec, None, PLANNER)


class _ApiPlanner:
    """The :class:`~convexguid.families.base.Planner` every family hook gets: this module's loader and solve."""

    @staticmethod
    def load(path: str | PathLike[str], overrides: Sequence[str] = ()) -> ProblemSpec:
        return load_problem(path, overrides)

    @staticmethod
    def solve(spec: ProblemSpec) -> Solution:
        return solve(spec)


PLANNER = _ApiPlanner()
"""What a family that needs another problem's plan is given (see :class:`~convexguid.families.base.Planner`)."""
