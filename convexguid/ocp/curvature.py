"""The constraints' curvature as a convex model for every SCP subproblem: exact second derivatives, made positive
semidefinite element by element.

A transcription's constraints come in elements: the rows of one interval (its defects, the path rows at its nodes)
depend on that interval's values only; the transcription says which row is in which element. The Lagrangian's
Hessian is the sum of the elements' Hessians :math:`H_e = \\sum_{i \\in e} \\lambda_i \\nabla^2 c_i`, each a small
dense block. Raising each block's negative eigenvalues to zero gives
:math:`\\bar H = \\sum_e P_e^T [H_e]_+ P_e \\succeq 0`: a convex model, sparse like the Hessian itself (the
partitioned view of Griewank & Toint, 1982, with exact element Hessians where they update quasi-Newton ones).
Clipping the whole Hessian at once would keep more, but costs a dense eigendecomposition of the program's size.

Two parts of an element's curvature are left out:

* A variable in more than two elements (a free final time, a phase's duration; a node belongs to the intervals on
  either side of it) couples all of them: each element's cross terms with it, clipped, would add curvature along
  it that the sum does not have (measured: the CW docking plan stalled at 0.92 of its fuel for 300 iterations and
  Betts' slew ended at 29.42 s instead of 28.63 s). Along it the trust region alone limits the step.
* An element whose negative curvature is as large as its positive (a bilinear term such as the quaternion
  kinematics' :math:`\\Omega(\\omega) q`, with eigenvalues :math:`\\pm a`) says nothing about which way the
  problem bends; clipped, it would bend the model where the problem is flat. Each element's positive part is
  weighted by its net share :math:`\\max(0, P - N) / P` of the sums :math:`P` and :math:`N` of its positive and
  negative eigenvalues (measured with the whole positive part instead: Betts' slew 18 -> 35 iterations, the
  two-instrument slew from 15 to ``max_iterations``).

The elements' Hessians come from :class:`~convexguid.ocp.element_hessian.ElementHessian`, which builds them class by
class in each element's own variables.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from convexguid.ocp.element_hessian import ElementClass, ElementHessian, summed_pattern
from convexguid.scp.problem import CurvatureModel

MAX_ELEMENT = 400
"""Largest element (variables) the model decomposes; a program whose elements are larger gets no curvature model."""


class ElementCurvature:
    """The convex model of an :class:`~convexguid.ocp.element_hessian.ElementHessian`: each element's block, less
    its variables shared by more than two elements, clipped as the module says. ``rows`` and ``cols`` are the
    model's pattern (upper triangle)."""

    def __init__(self, hessian: ElementHessian) -> None:
        n = hessian.size
        touching = np.zeros(n, dtype=int)  # how many elements' Hessians touch each variable
        for c in hessian.classes:
            np.add.at(touching, c.variables[:, np.union1d(c.local_rows, c.local_cols)].ravel(), 1)
        shared = touching > 2
        self._blocks = [_ClassBlock.of(c, shared) for c in hessian.classes]
        self._blocks = [b for b in self._blocks if b.size]
        self.empty = not self._blocks or max(b.size for b in self._blocks) > MAX_ELEMENT
        self.rows = self.cols = np.zeros(0, dtype=int)
        if self.empty:
            return
        self.rows, self.cols, self._slot = summed_pattern([b.keys(n) for b in self._blocks], n)

    def model(self, row_weights: Callable[[object], np.ndarray]) -> CurvatureModel | None:
        """The engine's :class:`~convexguid.scp.problem.CurvatureModel` (None when there is no curvature to model);
        ``row_weights`` turns the engine's multipliers into one weight per row."""
        if self.empty:
            return None
        return CurvatureModel(self.rows, self.cols, lambda z, weights: self.values(z, row_weights(weights)))

    def values(self, z: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """The model's entries on its pattern at ``z``, each row's second derivatives weighted by ``weights``."""
        if self.empty:
            return np.zeros(0)
        z, weights = np.asarray(z, dtype=float), np.asarray(weights, dtype=float)
        parts = [b.clipped(z, weights) for b in self._blocks]
        return np.bincount(self._slot, weights=np.concatenate(parts), minlength=self.rows.size)


class _ClassBlock:
    """One element class's part of the model: its elements' blocks on the local variables ``kept`` by any of them
    (``size`` of them), each element's entries with a shared variable zeroed."""

    def __init__(self, element_class: ElementClass, kept: np.ndarray, entries: np.ndarray,
                 owned: np.ndarray) -> None:
        self.element_class, self.kept, self.size = element_class, kept, kept.size
        self._entries = entries  # (elements, local nonzeros): the nonzero is the element's own
        position = np.full(element_class.variables.shape[1], -1)
        position[kept] = np.arange(kept.size)
        self._at = position[element_class.local_rows], position[element_class.local_cols]
        self._i, self._j = np.triu_indices(kept.size)
        self._emitted = owned[:, self._i] & owned[:, self._j]  # (elements, pairs) both variables the element's

    @classmethod
    def of(cls, element_class: ElementClass, shared: np.ndarray) -> _ClassBlock:
        rows, cols = element_class.local_rows, element_class.local_cols
        variables = element_class.variables
        entries = ~shared[variables[:, rows]] & ~shared[variables[:, cols]]
        owned = np.zeros(variables.shape, dtype=bool)  # each element's variables in an entry of its own
        for e in range(variables.shape[0]):
            owned[e, rows[entries[e]]] = owned[e, cols[entries[e]]] = True
        kept = np.flatnonzero(owned.any(axis=0))
        return cls(element_class, kept, entries, owned[:, kept])

    def keys(self, n: int) -> np.ndarray:
        """The model entries its elements give, as ``row * n + col``."""
        variables = self.element_class.variables[:, self.kept]
        return (variables[:, self._i] * n + variables[:, self._j])[self._emitted]

    def clipped(self, z: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """The clipped blocks' entries at :meth:`keys`."""
        values = np.where(self._entries, self.element_class.nonzeros(z, weights), 0.0)
        blocks = np.zeros((values.shape[0], self.size, self.size))
        inside = (self._at[0] >= 0) & (self._at[1] >= 0)
        blocks[:, self._at[0][inside], self._at[1][inside]] = values[:, inside]
        eigenvalues, vectors = np.linalg.eigh(0.5 * (blocks + blocks.transpose(0, 2, 1)))
        positive = np.maximum(eigenvalues, 0.0)
        total = positive.sum(axis=1)
        net = np.maximum(total - np.maximum(-eigenvalues, 0.0).sum(axis=1), 0.0)
        positive *= np.divide(net, total, out=np.zeros_like(net), where=total > 0)[:, None]
        clipped = np.einsum("eij,ej,ekj->eik", vectors, positive, vectors)
        return clipped[:, self._i, self._j][self._emitted]


def interval_of_rows(program, num_equalities: int, num_epigraph: int) -> np.ndarray:
    """A transcription's element of each constraint row (its equalities, path rows and epigraph row in turn): the
    interval of a defect (a block of ``nx`` rows) and of a path row (its node's interval, the last node's the last),
    one element for the boundary rows, one for the epigraph row."""
    defects = num_equalities - len(program.equality_rows) - len(program.boundary_equality_rows)
    blocks = defects // program.nx

    def at(rows: list[tuple[str, int, int]]) -> list[int]:
        return [min(k, blocks - 1) for _, k, _ in rows]

    return np.concatenate([np.repeat(np.arange(blocks), program.nx), at(program.equality_rows),
                           np.full(len(program.boundary_equality_rows), blocks), at(program.path_rows),
                           np.full(num_epigraph, blocks + 1)]).astype(int)

