"""Argument checks of the Python API (planners, controllers, simulation), each raising a one-line SpecError.

Problem files are checked by :mod:`convexguid.spec`; these guard the same quantities when a
caller builds the objects directly from Python.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from convexguid.errors import SpecError, value_text


def finite_vector(name: str, value: ArrayLike, n: int) -> NDArray:
    """``value`` as a float array of ``n`` finite numbers."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise SpecError(f"{name} must be {n} finite numbers, got {np.asarray(value).tolist()}")
    return arr


def unit_vector(name: str, value: ArrayLike, n: int) -> NDArray:
    """``value`` normalised: ``n`` finite numbers, not all (nearly) zero (a direction or a quaternion)."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)) or np.linalg.norm(arr) < 1e-12:
        raise SpecError(f"{name} must be a finite nonzero {n}-vector, got {np.asarray(value).tolist()}")
    return arr / np.linalg.norm(arr)


def positive(name: str, value: float | None) -> float:
    """``value`` as a float; it must be finite and > 0."""
    if value is None or not math.isfinite(value) or value <= 0:
        raise SpecError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def inertia_matrix(value: ArrayLike) -> NDArray:
    """A finite symmetric positive definite 3x3 inertia matrix, kg m^2."""
    arr = np.asarray(value, dtype=float)
    if (arr.shape != (3, 3) or not np.all(np.isfinite(arr)) or not np.allclose(arr, arr.T)
            or np.any(np.linalg.eigvalsh(arr) <= 0)):
        raise SpecError(f"inertia must be a symmetric positive definite 3x3 matrix, got {np.asarray(value).tolist()}")
    return arr


def override_list(overrides: object) -> tuple[str, ...]:
    """``overrides`` of :func:`convexguid.solve` / :func:`convexguid.simulate` as a tuple of ``key.path=value`` strings.

    None means no overrides; a single string is one override (never read character by character); otherwise
    every item must be a string.
    """
    if overrides is None:
        return ()
    if isinstance(overrides, str):
        return (overrides,)
    if isinstance(overrides, (bytes, Mapping)) or not isinstance(overrides, Iterable):
        raise SpecError(f"overrides: expected a list of 'key.path=value' strings (got {value_text(overrides)}); "
                        "e.g. overrides=['boundary.tf_s=25']")
    items = tuple(overrides)
    for i, item in enumerate(items):
        if not isinstance(item, str):
            raise SpecError(f"overrides[{i}]: expected a 'key.path=value' string (got {value_text(item)}); "
                            "e.g. overrides=['boundary.tf_s=25']")
    return items


def optional_callable(name: str, value: object) -> None:
    """Refuse a ``value`` that is neither None nor callable (a callback argument)."""
    if value is not None and not callable(value):
        raise SpecError(f"{name}: expected a function or None (got {value_text(value)}); e.g. {name}=print")
