"""A problem module: a Python file whose ``build(...)`` returns a :class:`~convexguid.ocp.problem.Problem` (or a
maneuver in phases, :class:`~convexguid.ocp.phases.Phases`).

``convexguid solve my_problem.py --set name=value`` runs it: each ``--set`` sets one parameter of ``build`` (the
value read as YAML, as for problem files); a name ``build`` does not declare, a module without ``build`` or a
``build`` that raises or returns something else is one line naming the file (exit 2). A campaign may name a module
as its problem: its keys are then ``build``'s parameters (:mod:`convexguid.campaign.definition`).
"""

from __future__ import annotations

import importlib.util
import inspect
from collections.abc import Sequence
from pathlib import Path

import yaml

from convexguid.errors import SpecError
from convexguid.ocp.phases import Phases
from convexguid.ocp.problem import Problem


def module_parameters(path: str | Path) -> dict[str, object]:
    """The parameters of the module's ``build`` and their defaults (``inspect.Parameter.empty`` for none)."""
    return {name: p.default for name, p in inspect.signature(_build_function(Path(path))).parameters.items()}


def load_module_problem(path: str | Path, overrides: Sequence[str] = ()) -> Problem | Phases:
    """The problem ``build(**parameters)`` of the module at ``path`` returns, ``overrides`` setting parameters."""
    path = Path(path)
    build = _build_function(path)
    parameters = inspect.signature(build).parameters
    values = {}
    for override in overrides:
        name, sep, raw = override.partition("=")
        name = name.strip()
        if not sep or name not in parameters:
            known = ", ".join(parameters) or "none"
            raise SpecError(f"{path}: --set {override!r}: not a parameter of build(); its parameters: {known}")
        try:
            values[name] = yaml.safe_load(raw)
        except yaml.YAMLError:
            raise SpecError(f"{path}: --set {name}: the value is not YAML (got {raw!r})") from None
    try:
        problem = build(**values)
    except SpecError as exc:  # a statement the problem refused: the line, after the file that stated it
        raise SpecError(f"{path}: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - the user's module: one line, not a traceback
        raise SpecError(f"{path}: build() raised {type(exc).__name__}: {exc}") from None
    if not isinstance(problem, (Problem, Phases)):
        raise SpecError(f"{path}: build() returned {type(problem).__name__}; it must return a convexguid.ocp.Problem "
                        "or convexguid.ocp.Phases")
    try:
        problem.check()
    except SpecError as exc:
        raise SpecError(f"{path}: {exc}") from None
    return problem


def _build_function(path: Path):
    """The module's ``build``, the module loaded afresh; one line naming the file when there is none."""
    if not path.is_file():
        raise SpecError(f"{path}: file not found; give the path of a problem module (a .py file with build())")
    spec = importlib.util.spec_from_file_location(f"convexguid_problem_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except SpecError:
        raise
    except Exception as exc:  # noqa: BLE001 - the user's module: one line, not a traceback
        raise SpecError(f"{path}: the module raised {type(exc).__name__} when loaded: {exc}") from None
    build = getattr(module, "build", None)
    if not callable(build):
        raise SpecError(f"{path}: no build() function; a problem module defines build(...) returning a "
                        "convexguid.ocp.Problem")
    return build
