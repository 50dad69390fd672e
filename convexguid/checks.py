"""Argument checks of the Python API (planners, controllers, simulation), each raising a one-line SpecError.

Problem files are checked by :mod:`convexguid.spec`; these guard the same quantities when a
caller builds the objects directly from Python.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from convexguid.errors import SpecError


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
