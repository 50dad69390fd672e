"""Problem files read by their family: ``family:`` names the model (through the registry) that validates the rest.

This is the one place that joins the YAML reader (:mod:`convexguid.spec.loader`, which knows no family) and the
registry (:mod:`convexguid.families`, which imports every family's spec model); a family never imports it (a
family that flies another problem's plan gets it through its ``solve`` hook's planner,
:class:`~convexguid.families.base.Planner`). Every problem reaches the user as a one-line
:class:`~convexguid.errors.SpecError`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from os import PathLike
from typing import Any

from convexguid.errors import SpecError, value_text
from convexguid.families import FAMILIES
from convexguid.spec.loader import ProblemSpec, apply_overrides, read_yaml_mapping, validate_as


def load_problem(path: str | PathLike[str], overrides: Sequence[str] = ()) -> ProblemSpec:
    """Read, override and validate a problem YAML file.

    Parameters
    ----------
    path : str or path-like
        Problem file.
    overrides : sequence of str
        ``dotted.key.path=value`` strings applied in order (see :func:`~convexguid.spec.loader.apply_overrides`).

    Returns
    -------
    ProblemSpec
        The validated problem of the file's family; ``.source`` is ``str(path)``.

    Raises
    ------
    SpecError
        If the file cannot be read or parsed, an override does not apply, or validation fails.
    """
    source = str(path)
    data = read_yaml_mapping(path, "a problem file is a mapping of keys such as name, family, spacecraft")
    return parse_problem(apply_overrides(data, overrides, source), source)


def parse_problem(data: Mapping[str, Any], source: str = "<dict>") -> ProblemSpec:
    """Validate raw problem data with the model of its ``family``.

    Parameters
    ----------
    data : mapping
        Raw problem data, as read from YAML.
    source : str
        File name used in error messages and stored as ``.source``.

    Returns
    -------
    ProblemSpec
        Instance of the ``spec_model`` of the family named by ``data["family"]`` (see :mod:`convexguid.families`).

    Raises
    ------
    SpecError
        One line naming the first problem (and how many more there are).
    """
    known = ", ".join(FAMILIES)
    if not isinstance(data, Mapping):
        raise SpecError(f"{source}: top level is not a mapping (got {value_text(data)}); "
                        "give a mapping of keys such as name, family, spacecraft")
    if "family" not in data:
        raise SpecError(f"{source}: family: missing required key; known families: {known}")
    family = data["family"]
    model = FAMILIES[family].spec_model if isinstance(family, str) and family in FAMILIES else None
    if model is None:
        raise SpecError(f"{source}: family: unknown family (got {value_text(family)}); "
                        f"known families: {known}")
    return validate_as(model, data, source)
