"""The package's layering, read from its own imports (issue 21).

* No import circles: the graph of every ``import`` in the package (at the top of a module and inside functions)
  has no cycle. A cycle is what an import inside a function hides; the test sees through it.
* The core, the command line, the report and the campaign reach a family only through the registry
  (``convexguid.families``: ``FAMILIES``, ``Family``, ``get_family``, ``family_names``) and the ``Family`` contract
  (``convexguid.families.base``): no family module, class or constant is imported outside ``families/``.
* A family does not import another family, nor anything that imports the registry.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "convexguid"
REGISTRY_NAMES = {"FAMILIES", "Family", "get_family", "family_names"}
"""What may be taken from ``convexguid.families`` outside it."""


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _owner(name: str) -> str | None:
    """The package module ``name`` lives in (``convexguid.x.y.attr`` -> ``convexguid.x.y``)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _type_checking(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def imports(module: str) -> Iterator[tuple[str, str, int]]:
    """``(imported module, name taken from it or "", line)`` for every import of ``module`` inside the package.

    Imports under ``if TYPE_CHECKING:`` are annotations, not imports, and are skipped.
    """
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    pending = list(ast.iter_child_nodes(tree))
    while pending:
        node = pending.pop()
        if _type_checking(node):
            continue
        pending.extend(ast.iter_child_nodes(node))
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("convexguid"):
                    yield alias.name, "", node.lineno
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("convexguid"):
            for alias in node.names:
                submodule = f"{node.module}.{alias.name}"
                yield (submodule, "", node.lineno) if submodule in MODULES else (node.module, alias.name, node.lineno)


def import_graph() -> dict[str, set[str]]:
    """Module -> the package modules importing it runs (each imported module and the packages above it)."""
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for module in MODULES:
        for target, _, _ in imports(module):
            owner = _owner(target)
            parts = owner.split(".") if owner else []
            for i in range(1, len(parts) + 1):
                ran = ".".join(parts[:i])
                if ran in MODULES and ran != module and not module.startswith(ran + "."):
                    graph[module].add(ran)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_the_package_has_no_import_cycle():
    found = cycles(import_graph())
    assert not found, "import cycles: " + "; ".join(" <-> ".join(c) for c in found)


def test_the_cycle_finder_finds_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def _family_of(module: str) -> str | None:
    parts = module.split(".")
    if parts[:2] != ["convexguid", "families"] or len(parts) < 3 or parts[2] == "base":
        return None
    return parts[2]


def test_no_family_is_imported_outside_families():
    wrong = []
    for module in MODULES:
        if module.startswith("convexguid.families"):
            continue
        for target, name, line in imports(module):
            if _family_of(_owner(target) or "") is not None or (target == "convexguid.families" and name
                                                                 and name not in REGISTRY_NAMES):
                wrong.append(f"{MODULES[module].relative_to(PACKAGE.parent)}:{line}: {target} {name}".rstrip())
    assert not wrong, "family code reached around the registry: " + "; ".join(wrong)


def test_a_family_imports_no_other_family_and_not_the_registry():
    wrong = []
    for module in MODULES:
        family = _family_of(module)
        if family is None:
            continue
        for target, _, line in imports(module):
            owner = _owner(target) or ""
            other = _family_of(owner)
            if (other is not None and other != family) or owner in ("convexguid.families", "convexguid.api",
                                                                    "convexguid.problem_files"):
                wrong.append(f"{MODULES[module].relative_to(PACKAGE.parent)}:{line}: {target}")
    assert not wrong, "a family reached outside its roof: " + "; ".join(wrong)
