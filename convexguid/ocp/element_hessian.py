"""The exact Hessian of a transcription's Lagrangian, built element by element.

A transcription's constraint rows come in elements (:func:`~convexguid.ocp.curvature.interval_of_rows`): the rows
of one interval depend on that interval's few values only, and so does their weighted sum
:math:`L_e = \\sum_{i \\in e} w_i c_i`. The Lagrangian's Hessian is the sum of the elements' Hessians, each placed
on its element's variables: :math:`\\nabla^2 L = \\sum_e P_e^T \\nabla^2 L_e P_e`. Elements whose rows are the same
expressions of their own variables (every interior interval of a time-invariant problem) form one class, and one
symbolic Hessian in a class's local variables, mapped over its elements, serves them all.

Differentiating the whole Lagrangian at once costs the program's size times the Hessian's colours (the multi-cone
slew's 511 variables: 0.26 s, a quarter of its solve); by classes it is one small Hessian per class (0.05 s there,
most of it spent telling the classes apart).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.ocp.parts import DERIVATIVES, coo_pattern


@dataclass(frozen=True)
class ElementClass:
    """Elements whose rows are the same expressions of their own variables.

    ``variables`` and ``rows`` (one line per element) are the elements' variables (ascending) and constraint rows;
    ``function`` (mapped over the elements) gives each one's Hessian nonzeros at local ``(local_rows, local_cols)``
    (both triangles) from its variables' and rows' values, one column per element.
    """

    function: ca.Function
    variables: np.ndarray
    rows: np.ndarray
    local_rows: np.ndarray
    local_cols: np.ndarray

    def nonzeros(self, z: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """Each element's Hessian nonzeros ``(elements, local nonzeros)`` at ``z``, rows weighted by ``weights``."""
        if not self.local_rows.size:
            return np.zeros((self.variables.shape[0], 0))
        out = self.function(z[self.variables].T, weights[self.rows].T)
        return np.asarray(out.nonzeros(), dtype=float).reshape(self.variables.shape[0], self.local_rows.size)


class ElementHessian:
    """:math:`\\sum_i w_i \\nabla^2 c_i(z)` for the rows ``c`` of ``constraints`` (a column of expressions of the
    symbols ``z``), row ``i`` in element ``elements[i]``, assembled from the element classes
    (:class:`ElementClass`). ``rows`` and ``cols`` are its pattern (both triangles)."""

    def __init__(self, z: ca.SX, constraints: ca.SX, elements: np.ndarray) -> None:
        self.size = z.shape[0]
        jacobian = sp.csr_matrix(coo_pattern(ca.jacobian_sparsity(constraints, z)))
        elements = np.asarray(elements, dtype=int)
        found: dict[str, tuple[ca.SX, ca.SX, ca.SX, list[tuple[np.ndarray, np.ndarray]]]] = {}
        for element in np.unique(elements):
            rows = np.flatnonzero(elements == element)
            variables = np.unique(jacobian[rows].indices)
            local, weights = ca.SX.sym("y", variables.size), ca.SX.sym("w", rows.size)
            lagrangian = ca.substitute(ca.dot(weights, constraints[rows.tolist()]), z[variables.tolist()], local)
            # two elements are one class when their local Lagrangians are the same graph, constants included
            key = hashlib.sha256(ca.Function("element", [local, weights], [lagrangian]).serialize().encode())
            found.setdefault(key.hexdigest(), (local, weights, lagrangian, []))[3].append((variables, rows))
        self.classes = [_element_class(*entry) for entry in found.values()]
        keys = [(c.variables[:, c.local_rows] * self.size + c.variables[:, c.local_cols]).ravel()
                for c in self.classes]
        self.rows, self.cols, self._slot = summed_pattern(keys, self.size)

    def values(self, z: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """The Hessian's entries on :attr:`rows`, :attr:`cols` at ``z``, rows weighted by ``weights``."""
        z, weights = np.asarray(z, dtype=float), np.asarray(weights, dtype=float)
        parts = [c.nonzeros(z, weights).ravel() for c in self.classes]
        return np.bincount(self._slot, weights=np.concatenate(parts + [np.zeros(0)]), minlength=self.rows.size)

    def matrix(self, z: np.ndarray, weights: np.ndarray) -> sp.csr_matrix:
        """The Hessian at ``z`` as a sparse matrix."""
        return sp.csr_matrix((self.values(z, weights), (self.rows, self.cols)), shape=(self.size, self.size))


def _element_class(local: ca.SX, weights: ca.SX, lagrangian: ca.SX,
                   members: list[tuple[np.ndarray, np.ndarray]]) -> ElementClass:
    hessian = ca.hessian(lagrangian, local)[0]
    local_rows, local_cols = (np.asarray(i, dtype=int) for i in hessian.sparsity().get_triplet())
    function = ca.Function("element_hessian", [local, weights], [hessian]).map(len(members))
    return ElementClass(function, np.array([v for v, _ in members]), np.array([r for _, r in members]),
                        local_rows, local_cols)


def summed_pattern(keys: list[np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rows, cols, slot)`` of the entries ``row * n + col`` in ``keys``: the distinct positions, and where each
    entry adds (``np.bincount(slot, values)`` sums them onto the pattern)."""
    unique, slot = np.unique(np.concatenate([*keys, np.zeros(0, dtype=np.int64)]), return_inverse=True)
    return unique // n, unique % n, slot


def element_hessian(z: ca.SX, constraints: ca.SX, elements: np.ndarray) -> ElementHessian:
    """The :class:`ElementHessian`, built once for a graph and its elements
    (:data:`~convexguid.ocp.parts.DERIVATIVES`)."""
    elements = np.asarray(elements, dtype=int)
    kind = "element_hessian" + hashlib.sha256(elements.tobytes()).hexdigest()
    return DERIVATIVES.get(kind, [z], [constraints], lambda: ElementHessian(z, constraints, elements))
