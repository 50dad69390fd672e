"""Which subproblem assembly and which backend an SCP run uses (``backend: auto`` and explicit names). ``auto`` decides
once per run, from the program's first evaluation: the condensed subproblem (:mod:`convexguid.scp.condensed`) with DAQP
for a small program (``DENSE_MAX_VARIABLES``) with weighted residuals and dense Jacobians (``DENSE_MIN_DENSITY``);
otherwise the lifted one (:mod:`convexguid.scp.assembly`) with PIQP, or with Clarabel when it has second-order cones;
Clarabel re-solves an answer of DAQP or PIQP that is not ``optimal``. An explicit name: the condensed subproblem for
``daqp``, the lifted one for any other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from convexguid.backends.registry import AUTO, DENSE_MAX_VARIABLES, DENSE_MIN_DENSITY, is_dense_backend, native_backends
from convexguid.scp.problem import Evaluation


@dataclass(frozen=True)
class SubproblemChoice:
    """The backend name handed to :func:`~convexguid.backends.make_backend`, the assembly, and the label shown."""

    backend: str
    condensed: bool
    label: str
    fallback: str | None = None


def jacobian_density(first: Evaluation) -> float:
    """Share of nonzeros in the Jacobians of the residuals and of the nonlinear constraints."""
    blocks = [b for b in (first.residual_jacobian, *(b.jacobian for b in (*first.inequalities, *first.equalities)))
              if b is not None]
    size = sum(b.shape[0] * b.shape[1] for b in blocks)
    nnz = sum(b.nnz if sp.issparse(b) else int(np.count_nonzero(b)) for b in blocks)
    return nnz / size if size else 0.0


def choose_subproblem(name: str, n: int, first: Evaluation, weights: np.ndarray) -> SubproblemChoice:
    """The assembly and backend for backend setting ``name`` on a program with ``n`` variables."""
    if name != AUTO:
        return SubproblemChoice(name, is_dense_backend(name) and not first.cones, name)
    if first.cones:  # second-order cones: the conic interior-point solver
        return SubproblemChoice("clarabel", False, f"{AUTO} -> clarabel (sparse, cones)")
    dense = ("daqp" in native_backends() and n <= DENSE_MAX_VARIABLES and bool(np.any(np.asarray(weights) > 0))
             and first.residuals.size > 0 and jacobian_density(first) >= DENSE_MIN_DENSITY)
    if dense:
        return SubproblemChoice("daqp", True, f"{AUTO} -> daqp (condensed)", fallback="clarabel")
    if "piqp" in native_backends():  # the bounds apart from the rows (:mod:`convexguid.backends.bounded`)
        return SubproblemChoice("piqp", False, f"{AUTO} -> piqp (sparse)", fallback="clarabel")
    return SubproblemChoice("clarabel", False, f"{AUTO} -> clarabel (sparse)")
