"""Inputs taken from another case's result (``boundary.tf_from: {problem, figure}``), resolved by solving that case.

A problem may take a value from the result of another problem, named by its ``name`` (see
:meth:`~convexguid.spec.common.ProblemBase.input_links`). ``convexguid validate`` finds the named case among the
cases it runs; ``convexguid solve``, ``simulate`` and ``bench`` find it among the problem files beside the one they
run (:func:`linked_cases`). Both then solve the cases in :func:`run_order`, each after the cases it names
(:func:`solve_in_order`), and set each linked key to the named figure (:func:`link_values`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from convexguid.api import solve
from convexguid.errors import SpecError
from convexguid.families import get_family
from convexguid.problem_files import load_problem
from convexguid.solution import Solution
from convexguid.spec import ProblemSpec, with_values
from convexguid.spec.loader import read_yaml_mapping

_Result = TypeVar("_Result")


def run_order(specs: Sequence[ProblemSpec]) -> list[int]:
    """Indices of ``specs`` in the order to solve them: each case after the cases its input links name.

    Otherwise the given order is kept.

    Raises
    ------
    SpecError
        If a link names a problem that is not among ``specs`` (or is the case itself, or is named by two
        cases), a figure that is not a field of the named problem's family's figures type, or the links
        form a cycle.
    """
    index: dict[str, int] = {}
    for i, spec in enumerate(specs):
        if index.setdefault(spec.name, i) != i:
            raise SpecError(f"{spec.source}: name: {specs[index[spec.name]].source} has the same name "
                            f"(got {spec.name!r}); give every validated problem its own name")
    needs: list[set[int]] = []
    for spec in specs:
        deps = set()
        for _, link_key, link in spec.input_links():
            where = f"{spec.source}: {link_key}.problem"
            if link.problem not in index or link.problem == spec.name:
                others = [name for name in index if name != spec.name]
                hint = f"name one of: {', '.join(others)}" if others else "name another problem"
                raise SpecError(f"{where}: not another case of this run (got {link.problem!r}); {hint}")
            known = get_family(specs[index[link.problem]].family).figures.names()
            if link.figure not in known:
                raise SpecError(f"{spec.source}: {link_key}.figure: not a figure of {link.problem!r} "
                                f"(got {link.figure!r}); its figures: {', '.join(sorted(known))}")
            deps.add(index[link.problem])
        needs.append(deps)
    order: list[int] = []
    while len(order) < len(specs):
        ready = next((i for i in range(len(specs)) if i not in order and needs[i] <= set(order)), None)
        if ready is None:
            stuck = [i for i in range(len(specs)) if i not in order]
            raise SpecError(f"{specs[stuck[0]].source}: input links form a cycle among "
                            f"{', '.join(specs[i].name for i in stuck)}; "
                            "a case can only take inputs from cases that do not depend on it")
        order.append(ready)
    return order


def link_values(spec: ProblemSpec, solved: dict[str, Solution]) -> dict[str, Any]:
    """The values that resolve ``spec``'s input links from the solutions of the cases they name, by dotted key.

    Each link ``<link_key>: {problem, figure}`` giving ``<key>`` sets ``<link_key>`` to None and ``<key>`` to that
    problem's figure (:meth:`~convexguid.solution.Solution.figure`), the number itself (no text round trip).

    Raises
    ------
    SpecError
        If the named result lacks the figure or it is not a finite number (e.g. the maneuver was never
        completed).
    """
    values: dict[str, Any] = {}
    for key, link_key, link in spec.input_links():
        linked = solved[link.problem]
        value = linked.figure(link.figure) if link.figure in linked.figure_names() else None
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            raise SpecError(f"{spec.source}: {link_key}: the result of {link.problem!r} has no finite "
                            f"{link.figure} (got {value!r}); fix that case, or set {key} in this file")
        values.update({link_key: None, key: float(value)})
    return values


def solve_in_order(specs: Sequence[ProblemSpec], run_case: Callable[[ProblemSpec, dict[str, Any]], _Result],
                   solution_of: Callable[[_Result], Solution]) -> list[_Result]:
    """``run_case(spec, values)`` for every case in :func:`run_order`, ``values`` resolving the case's input links
    from the solutions (``solution_of`` a result) of the cases run before it; the results in the order given."""
    results: dict[int, _Result] = {}
    solved: dict[str, Solution] = {}
    for i in run_order(specs):
        results[i] = run_case(specs[i], link_values(specs[i], solved))
        solved[specs[i].name] = solution_of(results[i])
    return [results[i] for i in range(len(specs))]


def linked_cases(spec: ProblemSpec) -> list[ProblemSpec]:
    """The problems ``spec``'s input links name, and those theirs name in turn, each read from the problem file
    beside ``spec``'s whose ``name`` it is; empty when ``spec`` has no input link.

    Raises
    ------
    SpecError
        Before anything is solved: if no file beside it (or more than one) has a linked name, a linked file is
        invalid, or the links are wrong as :func:`run_order` checks them (a figure the case lacks, a cycle).
    """
    if not spec.input_links():
        return []
    folder = Path(spec.source).parent
    by_name = _problem_files_by_name(folder)
    cases = {spec.name: spec}
    pending = [spec]
    while pending:
        linking = pending.pop()
        for key, link_key, link in linking.input_links():
            if link.problem in cases:
                continue
            files = by_name.get(link.problem, [])
            if len(files) != 1:
                found = (f"no problem file in {folder} has that name" if not files else
                         f"{' and '.join(map(str, files))} both have that name")
                raise SpecError(f"{linking.source}: {link_key}.problem: {found} (got {link.problem!r}); give "
                                f"the linked problem one file beside this one, or give {key} instead (with "
                                f"{link_key}: null)")
            cases[link.problem] = load_problem(files[0])
            pending.append(cases[link.problem])
    ordered = list(cases.values())
    return [ordered[i] for i in run_order(ordered) if ordered[i] is not spec]


def _problem_files_by_name(folder: Path) -> dict[str, list[Path]]:
    """The YAML files in ``folder`` by their top-level ``name`` (files that cannot be read, or name nothing, are
    left out: a campaign file, a file being edited)."""
    found: dict[str, list[Path]] = {}
    for path in sorted(folder.glob("*.yaml")):
        try:
            name = read_yaml_mapping(path, "a problem file is a mapping").get("name")
        except SpecError:
            continue
        if isinstance(name, str):
            found.setdefault(name, []).append(path)
    return found


def resolve_links(spec: ProblemSpec, cases: Sequence[ProblemSpec],
                  log: Callable[[str], None] | None = None) -> ProblemSpec:
    """``spec`` with its input links resolved: ``cases`` (:func:`linked_cases`) solved in order, as
    ``convexguid validate`` solves them, and each linked key set to the named figure.

    ``log`` (None: quiet) receives one line before each case is solved and one with the values taken.

    Raises
    ------
    SpecError
        If a named result has no finite value of the figure (:func:`link_values`).
    """
    def run_case(case: ProblemSpec, values: dict[str, Any]) -> Solution:
        if log is not None:
            log(f"{spec.name} takes an input from {case.name}: solving {case.source} first")
        return solve(with_values(case, values) if values else case)

    solutions = solve_in_order(cases, run_case, lambda solution: solution)
    values = link_values(spec, {case.name: solution for case, solution in zip(cases, solutions, strict=True)})
    if log is not None:
        taken = ", ".join(f"{key} = {value:g}" for key, value in values.items() if value is not None)
        log(f"{spec.name}: {taken} (from {', '.join(f'{s.problem}: {s.status}' for s in solutions)})")
    return with_values(spec, values)
