"""Numbers written the way people type them: ``1e12``, ``-3.5E-2``, ``1e-6``.

YAML 1.1 (PyYAML) reads a float only with a dot and a signed exponent (``1.0e-6``); ``1e2`` and
``1.0e6`` stay strings, which a number key then rejects. :func:`read_scientific_numbers` teaches a
loader to read every scientific scalar as a :class:`ScientificFloat`, a float that remembers how it was
written, so that a key which takes a string (a name such as ``name: 1e5``) still receives the text, and a
key which takes an integer (``discretization.nodes: 1e3``, ``1.0e+3``) a whole number (see :func:`as_declared`).
A quoted ``"1e5"`` is always a string.
"""

from __future__ import annotations

import re
import types
import typing
from typing import Any

import yaml

SCIENTIFIC_TAG = "tag:convexguid,2024:scientific"
"""Tag the loader gives a plain scalar in scientific notation."""

SCIENTIFIC_PATTERN = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$")
"""Mantissa (with or without a dot), ``e`` or ``E``, exponent with or without a sign."""


class ScientificFloat(float):
    """A float read from scientific notation; ``text`` is the scalar as it was written."""

    text: str

    def __new__(cls, text: str) -> ScientificFloat:
        number = super().__new__(cls, text.replace("_", ""))
        number.text = text
        return number

    def __repr__(self) -> str:
        return self.text

    def __reduce__(self) -> tuple[type[ScientificFloat], tuple[str]]:  # copies and pickles rebuild from the text
        return ScientificFloat, (self.text,)


def _construct(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> ScientificFloat:
    return ScientificFloat(loader.construct_scalar(node))


def read_scientific_numbers(loader: type[yaml.SafeLoader]) -> None:
    """Make ``loader`` (a SafeLoader subclass; its own resolver table) read scientific notation as numbers.

    Ours is tried before PyYAML's float resolver, so every scientific scalar (``1e2`` and ``1.0e+2`` alike) is a
    :class:`ScientificFloat`; plain decimals (``1.5``) stay PyYAML floats.
    """
    first_characters = "-+0123456789."
    loader.add_implicit_resolver(SCIENTIFIC_TAG, SCIENTIFIC_PATTERN, list(first_characters))
    for first in first_characters:
        resolvers = loader.yaml_implicit_resolvers[first]
        resolvers.insert(0, resolvers.pop())  # add_implicit_resolver appends: move ours to the front
    loader.add_constructor(SCIENTIFIC_TAG, _construct)


def _scalar_type(annotation: Any) -> type | None:
    """``str`` or ``int`` if a field of this annotation takes that scalar (also ``X | None``), else None."""
    if annotation in (str, int):
        return annotation
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        kinds = {_scalar_type(arg) for arg in typing.get_args(annotation) if arg is not type(None)}
        if len(kinds) == 1:
            return kinds.pop()
    return None


def as_declared(annotation: Any, value: Any) -> Any:
    """``value`` as a field declared ``annotation`` wants it, when it is a :class:`ScientificFloat`: its text for
    a string field, an int for an integer field when it is whole; anything else unchanged."""
    if not isinstance(value, ScientificFloat):
        return value
    kind = _scalar_type(annotation)
    if kind is str:
        return value.text
    if kind is int and value.is_integer():
        return int(value)
    return value
