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

No second derivative is built for the model: one evaluation of the program's exact Lagrangian Hessian with the
multipliers of one colour of elements (no two elements of a colour share a variable) holds every element of that
colour apart, so two evaluations serve an interval-by-interval transcription.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.ocp.parts import DERIVATIVES, SparsityPattern, coo_pattern
from convexguid.scp.problem import CurvatureModel

MAX_ELEMENT = 400
"""Largest element (variables) the model decomposes; a program whose elements are larger gets no curvature model."""

Hessian = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``hessian(z, row_weights)``: the nonzeros of :math:`\\sum_i w_i \\nabla^2 c_i(z)` on a fixed pattern."""


class ElementCurvature:
    """The convex model of :math:`\\sum_i w_i \\nabla^2 c_i(z)` for constraint rows ``c``, row ``i`` in element
    ``elements[i]``: ``hessian`` gives the exact weighted Hessian's nonzeros at ``(pattern_rows, pattern_cols)``
    (both triangles), and ``contributions`` (nonzeros by rows, 0/1) which rows' second derivatives each one holds."""

    def __init__(self, hessian: Hessian, pattern_rows: np.ndarray, pattern_cols: np.ndarray,
                 contributions: sp.spmatrix, elements: np.ndarray) -> None:
        m, n = contributions.shape[1], int(max(pattern_rows.max(initial=-1), pattern_cols.max(initial=-1)) + 1)
        self._hessian = hessian
        _, element = np.unique(np.asarray(elements, dtype=int), return_inverse=True)
        num_elements = element.max(initial=-1) + 1
        # each (nonzero, element) the element's rows contribute to; an element's variables are those of its nonzeros
        pairs = (sp.csr_matrix(contributions) @ sp.csr_matrix((np.ones(m), (np.arange(m), element)),
                                                                shape=(m, num_elements))).tocoo()
        entry, owner = pairs.row, pairs.col
        rows, cols = np.asarray(pattern_rows)[entry], np.asarray(pattern_cols)[entry]
        covering = _binary(sp.csr_matrix((np.ones(2 * entry.size), (np.concatenate([owner, owner]),
                                                                      np.concatenate([rows, cols]))),
                                         shape=(num_elements, n)))
        shared = covering.getnnz(axis=0) > 2
        keep = ~shared[rows] & ~shared[cols]
        covering = _binary(sp.csr_matrix((np.ones(2 * np.count_nonzero(keep)), (
            np.concatenate([owner[keep], owner[keep]]), np.concatenate([rows[keep], cols[keep]]))),
            shape=(num_elements, n)))
        sizes = covering.getnnz(axis=1)
        self.empty = not sizes.any() or sizes.max() > MAX_ELEMENT
        self.rows = self.cols = np.zeros(0, dtype=int)
        if self.empty:
            return
        colour = _colours(covering)
        self._row_colours = [colour[element] == c for c in range(colour.max() + 1)]
        # where each pair of an element's variables sits among the Hessian's nonzeros (-1: structurally zero)
        keys = np.asarray(pattern_rows, dtype=np.int64) * n + np.asarray(pattern_cols)
        order = np.argsort(keys)
        self._classes, pattern_keys = [], []
        for size in np.unique(sizes[sizes > 0]):
            chosen = np.flatnonzero(sizes == size)
            columns = covering.indices[covering.indptr[chosen][:, None] + np.arange(size)]
            wanted = (columns[:, :, None] * n + columns[:, None, :]).ravel()
            found = np.searchsorted(keys[order], wanted)
            found = np.minimum(found, keys.size - 1)
            at = np.where(keys[order][found] == wanted, order[found], -1).reshape(chosen.size, size, size)
            i, j = np.triu_indices(size)
            self._classes.append((colour[chosen], at, i, j))
            pattern_keys.append((columns[:, i] * n + columns[:, j]).ravel())
        unique, self._slot = np.unique(np.concatenate(pattern_keys), return_inverse=True)
        self.rows, self.cols = unique // n, unique % n
        self.num_elements, self.largest = int(np.count_nonzero(sizes)), int(sizes.max())

    @classmethod
    def of(cls, hessian: tuple[ca.Function, SparsityPattern], elements: np.ndarray) -> ElementCurvature:
        """The model of a :func:`lagrangian_hessian` ``(function, pattern)``, its rows (the blocks' in turn) in
        ``elements``."""
        function, pattern = hessian
        blocks = range(1, function.n_in())
        sizes = [function.size1_in(i) for i in blocks]
        splits, rows = np.cumsum(sizes)[:-1], int(sum(sizes))
        # which rows' second derivatives each nonzero holds: the Hessian's structural Jacobian in the multipliers
        contributions = sp.hstack([coo_pattern(function.sparsity_jac(i, 0, True, False)) for i in blocks])
        return cls(lambda z, w: np.asarray(function(z, *np.split(np.asarray(w)[:rows], splits)).nonzeros(),
                                           dtype=float), pattern.rows, pattern.cols, contributions, elements)

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
        weights = np.asarray(weights, dtype=float)
        by_colour = [np.append(self._hessian(z, np.where(rows, weights, 0.0)), 0.0) for rows in self._row_colours]
        out = []
        for colours, at, i, j in self._classes:
            blocks = np.empty(at.shape)
            for c, values in enumerate(by_colour):
                mine = colours == c
                blocks[mine] = values[at[mine]]  # -1 reads the appended 0
            eigenvalues, vectors = np.linalg.eigh(0.5 * (blocks + blocks.transpose(0, 2, 1)))
            positive = np.maximum(eigenvalues, 0.0)
            total = positive.sum(axis=1)
            net = np.maximum(total - np.maximum(-eigenvalues, 0.0).sum(axis=1), 0.0)
            positive *= np.divide(net, total, out=np.zeros_like(net), where=total > 0)[:, None]
            clipped = np.einsum("eij,ej,ekj->eik", vectors, positive, vectors)
            out.append(clipped[:, i, j].ravel())
        return np.bincount(self._slot, weights=np.concatenate(out), minlength=self.rows.size)


def lagrangian_hessian(z: ca.SX, blocks: list[ca.SX]) -> tuple[ca.Function, SparsityPattern]:
    """CasADi's exact Hessian of :math:`\\sum_j w_j^T c_j(z)` for the constraint ``blocks`` :math:`c_j`, as a
    function of ``z`` and one multiplier input per block, and its pattern (both triangles); built once for a graph
    (:data:`~convexguid.ocp.parts.DERIVATIVES`)."""

    def build() -> tuple[ca.Function, SparsityPattern]:
        weights = [ca.SX.sym(f"w{j}", block.shape[0]) for j, block in enumerate(blocks)]
        lagrangian = sum((ca.dot(w, block) for w, block in zip(weights, blocks, strict=True) if block.shape[0]),
                         ca.SX(0))
        hessian = ca.hessian(lagrangian, z)[0]
        return ca.Function("hessian", [z, *weights], [hessian]), SparsityPattern(hessian.sparsity())

    return DERIVATIVES.get("lagrangian_hessian", [z], blocks, build)


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


def _binary(matrix: sp.spmatrix) -> sp.csr_matrix:
    """``matrix``'s pattern as 0/1, explicit zeros dropped, columns sorted in each row."""
    matrix = sp.csr_matrix(matrix)
    matrix.eliminate_zeros()
    matrix.data[:] = 1.0
    matrix.sort_indices()
    return matrix


def _colours(covering: sp.csr_matrix) -> np.ndarray:
    """A colour for each element, no two elements of a colour sharing a variable (greedy, in element order)."""
    neighbours = (covering @ covering.T).tocsr()
    colour = np.full(covering.shape[0], -1)
    for e in range(covering.shape[0]):
        taken = set(colour[neighbours.indices[neighbours.indptr[e]: neighbours.indptr[e + 1]]].tolist())
        colour[e] = next(c for c in range(len(taken) + 1) if c not in taken)
    return colour
