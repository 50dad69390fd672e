"""Read problem YAML files, apply ``--set`` overrides, validate with a family's model.

Which model a file's ``family`` names is the registry's business (:mod:`convexguid.problem_files` reads a problem
file by its family); this module knows only the shared base model, so the families' spec models can import it.

Every problem reaches the user as a :class:`~convexguid.errors.SpecError` with a
one-line message ``<file>: <dotted.key.path>: <what is wrong> (got <value>); <what
would be valid>``; pydantic's :class:`~pydantic.ValidationError` never escapes.
"""

from __future__ import annotations

import copy
import typing
from collections.abc import Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from convexguid.errors import SpecError, value_text
from convexguid.spec.common import SPEC_ERROR_TYPE, ProblemBase
from convexguid.spec.numbers import read_scientific_numbers

ProblemSpec = ProblemBase
"""Type of every validated problem (each family subclasses it)."""

_PROBLEMS = {
    "greater_than": "out of range", "greater_than_equal": "out of range", "less_than": "out of range",
    "less_than_equal": "out of range", "finite_number": "not a finite number", "string_too_short": "empty",
    "literal_error": "invalid value", "invalid_key": "key is not a string",
}


MAX_EXPANDED_NODES = 100_000
"""Most YAML nodes (scalars, lists, mappings) a document may have once its aliases are expanded; the largest
problem file has under 200. Past it the document is refused (a "billion laughs" alias bomb expands to 10^9)."""


class _TooLarge(Exception):
    """The document's aliases expand past :data:`MAX_EXPANDED_NODES` nodes."""


class _UniqueKeyLoader(yaml.SafeLoader):
    """Safe YAML loader that rejects duplicate keys instead of keeping the last one, reads scientific notation
    (``1e3``) as numbers (:mod:`convexguid.spec.numbers`) and refuses documents whose aliases expand past
    :data:`MAX_EXPANDED_NODES` nodes."""

    def construct_document(self, node: yaml.Node) -> Any:
        if _expanded_size(node, {}) > MAX_EXPANDED_NODES:
            raise _TooLarge
        return super().construct_document(node)

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, typing.Hashable) and key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep)


read_scientific_numbers(_UniqueKeyLoader)


def _expanded_size(node: yaml.Node, sizes: dict[int, int]) -> int:
    """Nodes under ``node`` (itself included) with every alias expanded, counted once per distinct node
    (``sizes``, by node id); a node that contains itself counts as more than :data:`MAX_EXPANDED_NODES`."""
    key = id(node)
    if key in sizes:
        return sizes[key]
    sizes[key] = MAX_EXPANDED_NODES + 1  # until counted: an alias back to a node being counted is a cycle
    children: list[yaml.Node] = []
    if isinstance(node, yaml.SequenceNode):
        children = node.value
    elif isinstance(node, yaml.MappingNode):
        children = [part for pair in node.value for part in pair]
    total = 1
    for child in children:
        total += _expanded_size(child, sizes)
        if total > MAX_EXPANDED_NODES:
            break
    sizes[key] = total
    return total


def _yaml_load(text: str, where: str) -> Any:
    """The YAML document ``text``; ``where`` (the file, or the file and key of an override) starts the messages.

    Raises
    ------
    yaml.YAMLError
        On a syntax error.
    SpecError
        If the aliases expand past :data:`MAX_EXPANDED_NODES` nodes or the nesting is too deep to read.
    """
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except _TooLarge:
        raise SpecError(f"{where}: YAML aliases expand to more than {MAX_EXPANDED_NODES} values or refer to "
                        "themselves; write the values out instead of nesting aliases") from None
    except RecursionError:
        raise SpecError(f"{where}: YAML nested too deeply to read; a problem file nests a few levels") from None


def _one_line(text: str, limit: int = 100) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _dotted(loc: Sequence[str | int]) -> str:
    return ".".join(_key_text(part) for part in loc)


def _key_text(key: object) -> str:
    """A key as a message shows it: as is when it is a plain word, else quoted (a key may hold a line break)."""
    text = str(key)
    return text if text and text.isprintable() and not any(c.isspace() for c in text) else value_text(key)


def read_yaml_mapping(path: str | PathLike[str], hint: str) -> dict[str, Any]:
    """Read a YAML file whose top level is a mapping (duplicate keys rejected).

    ``hint`` ends the message when the top level is not a mapping (what the file should be).

    Raises
    ------
    SpecError
        If the file cannot be read or parsed, or its top level is not a mapping.
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SpecError(f"{source}: file not found; give the path of an existing problem YAML file") from None
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise SpecError(f"{source}: cannot read file ({_one_line(reason)}); give a readable UTF-8 YAML file"
                        ) from None
    try:
        data = _yaml_load(text, source)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        what = _one_line(str(getattr(exc, "problem", None) or exc))
        raise SpecError(f"{source}: {where}YAML syntax error: {what}; fix the YAML syntax") from None
    if not isinstance(data, dict):
        raise SpecError(f"{source}: top level is not a mapping (got {value_text(data)}); {hint}")
    return data


def apply_overrides(data: Mapping[str, Any], overrides: Sequence[str], source: str) -> dict[str, Any]:
    """Apply ``--set`` overrides to a copy of the raw problem data.

    Parameters
    ----------
    data : mapping
        Raw problem data (not modified).
    overrides : sequence of str
        ``dotted.key.path=value``; the value is parsed as YAML, list items are addressed by
        integer index (``keep_out.0.half_angle_deg=30``). Every path component must exist,
        except that a missing last key of a mapping is added (validation then judges it).
    source : str
        File name used in error messages.

    Returns
    -------
    dict
        Deep copy of ``data`` with the overrides applied.

    Raises
    ------
    SpecError
        If an override is malformed, its value is not YAML, or its path does not exist.
    """
    values: list[tuple[str, Any, str]] = []
    for override in overrides:
        key, sep, raw = override.partition("=")
        if not sep or not all(key.strip().split(".")):
            raise SpecError(f"{source}: malformed override (got {override!r}); "
                            "write key.path=value, e.g. boundary.tf_s=25")
        try:
            value = _yaml_load(raw, f"{source}: {key}")
        except yaml.YAMLError:
            raise SpecError(f"{source}: {key}: override value is not valid YAML (got {raw!r}); "
                            "give a YAML number, string, list or mapping") from None
        values.append((key.strip(), value, f"override {override!r}"))
    return _set_values(data, values, source)


def set_values(data: Mapping[str, Any], values: Mapping[str, Any], source: str) -> dict[str, Any]:
    """A copy of the raw problem data with the value at each dotted key replaced, as :func:`apply_overrides`
    does, but with values already made (a number computed in this process is not written out as text and read
    back).

    Raises
    ------
    SpecError
        If a key path does not exist (a missing last key of a mapping is added).
    """
    return _set_values(data, [(key, value, f"value {value!r}") for key, value in values.items()], source)


def _set_values(data: Mapping[str, Any], values: Sequence[tuple[str, Any, str]], source: str) -> dict[str, Any]:
    """``data`` deep-copied with each ``(dotted key, value, what)`` applied in order (``what`` names it in errors)."""
    result = copy.deepcopy(dict(data))
    for key, value, what in values:
        parts = key.split(".")
        node: Any = result
        for depth, part in enumerate(parts):
            last = depth == len(parts) - 1
            here = _dotted(parts[: depth + 1])
            if isinstance(node, dict):
                if part not in node and not last:
                    names = ", ".join(map(_key_text, node)) or "none"
                    parent = _dotted(parts[:depth]) or "the top level"
                    raise SpecError(f"{source}: {here}: key does not exist (got {what}); "
                                    f"existing keys under {parent}: {names}")
                if last:
                    node[part] = value
                else:
                    node = node[part]
            elif isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    valid = f"valid indices: 0 to {len(node) - 1}" if node else "the list is empty"
                    raise SpecError(f"{source}: {here}: list index does not exist (got {what}); {valid}")
                if last:
                    node[int(part)] = value
                else:
                    node = node[int(part)]
            else:
                raise SpecError(f"{source}: {here}: key does not exist (got {what}); "
                                f"{_dotted(parts[:depth])} is a {type(node).__name__}, not a mapping or list")
    return result


MISSING = object()
"""What :func:`value_at` returns where a key path leads nowhere."""


def value_at(data: Any, key: str) -> Any:
    """The value at dotted ``key`` in nested mappings and lists (list items by index, as in ``--set``), or
    :data:`MISSING` where the path leads nowhere."""
    node = data
    for part in key.split("."):
        if isinstance(node, Mapping) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            return MISSING
    return node


def with_overrides(spec: ProblemSpec, overrides: Sequence[str]) -> ProblemSpec:
    """``spec`` validated again, by its own model, with ``overrides`` applied to the data it was made from (a
    file's or a dict's: the file is not read again).

    Raises
    ------
    SpecError
        If an override does not apply or the result is invalid.
    """
    return validate_as(type(spec), apply_overrides(spec._data, overrides, spec.source), spec.source)


def with_values(spec: ProblemSpec, values: Mapping[str, Any]) -> ProblemSpec:
    """``spec`` validated again, by its own model, with the value at each dotted key replaced (:func:`set_values`).

    Raises
    ------
    SpecError
        If a key does not exist or the result is invalid.
    """
    return validate_as(type(spec), set_values(spec._data, values, spec.source), spec.source)


def validate_as(model: type[ProblemBase], data: Mapping[str, Any], source: str) -> ProblemSpec:
    """``data`` validated by ``model`` (a family's spec model), with ``.source`` set to ``source``.

    Raises
    ------
    SpecError
        One line naming the first problem (and how many more there are).
    """
    try:
        spec = model.model_validate(dict(data))
    except ValidationError as exc:
        raise SpecError(f"{source}: {describe_validation_error(exc, model)}") from None
    spec._source = source
    spec._data = copy.deepcopy(dict(data))
    return spec


def describe_validation_error(exc: ValidationError, model: type[BaseModel]) -> str:
    """The first problem of ``exc`` (raised validating ``model``) on one line, ``path: problem (got value); hint``,
    followed by how many more problems there are."""
    errors = exc.errors()
    more = {1: "", 2: " (and 1 more problem)"}.get(len(errors), f" (and {len(errors) - 1} more problems)")
    return f"{_describe(errors[0], model)}{more}"


def _describe(error: ErrorDetails, model: type[BaseModel]) -> str:
    """Render one pydantic error as ``path: problem (got value); hint``."""
    loc = tuple(error["loc"])
    ctx = error.get("ctx") or {}
    kind = error["type"]
    value = error.get("input")
    if kind == SPEC_ERROR_TYPE:
        here = _dotted(loc)
        problem = ctx["problem"].replace("{here}", here + "." if here else "")
        path = _dotted(loc + tuple(ctx["key"]))
        return f"{path}: {problem} (got {value_text(ctx.get('value', value))}); {ctx['hint']}"
    path = _dotted(loc) or "<top level>"
    if kind == "missing":
        return f"{path}: missing required key"
    if kind == "extra_forbidden":
        keys = _valid_keys(model, loc[:-1])
        return f"{path}: unknown key (got {value_text(value)}); valid keys: {keys}"
    if kind in ("model_type", "model_attributes_type", "dict_type"):
        sub = _valid_keys(model, loc)
        hint = f"give a mapping with keys: {sub}" if sub else "give a mapping"
        return f"{path}: wrong type, expected a mapping (got {value_text(value)}); {hint}"
    problem = _PROBLEMS.get(kind, "wrong type" if kind.endswith("_type") else "invalid value")
    msg = error["msg"]
    return f"{path}: {problem} (got {value_text(value)}); {msg[:1].lower()}{_one_line(msg[1:], 200)}"


def _valid_keys(model: type[BaseModel], loc: Sequence[str | int]) -> str:
    """Comma-separated keys of the model reached from ``model`` along ``loc`` ('' if none)."""
    current: type[BaseModel] | None = model
    for part in loc:
        if isinstance(part, int):  # list item: the item model was already found
            continue
        field = current.model_fields.get(part) if current is not None else None
        current = _find_model(field.annotation) if field is not None else None
    return ", ".join(current.model_fields) if current is not None else ""


def _find_model(annotation: Any) -> type[BaseModel] | None:
    """First pydantic model class inside a type annotation (through lists, unions, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _find_model(arg)
        if found is not None:
            return found
    return None
