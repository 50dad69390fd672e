"""The pieces a transcription is built from that are not the transcription: the CasADi sparsity pattern of a
Jacobian block, the repair margins, the symbolic NLP it hands to an independent solver, and the cones' scales."""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sp


class SparsityPattern:
    """A CasADi structural sparsity read once; each evaluation only fills its values (the engine fixes the
    subproblem's pattern from the first one)."""

    def __init__(self, pattern: ca.Sparsity) -> None:
        rows, cols = pattern.get_triplet()
        self.rows, self.cols = np.asarray(rows, dtype=int), np.asarray(cols, dtype=int)
        self.shape = pattern.shape

    def coo(self, values: ca.DM) -> sp.coo_matrix:
        return sp.coo_matrix((np.asarray(values.nonzeros(), dtype=float), (self.rows, self.cols)), shape=self.shape)


@dataclass(frozen=True)
class SymbolicNLP:
    """The NLP a transcription states, in CasADi: the decision vector ``z``, the objective (the linear cost plus the
    weighted squared residuals) and the constraint blocks ``(name, expression, lower, upper)``, the repair margins
    included; the second-order cones are left to :meth:`Transcription.evaluate` (exact affine maps)."""

    z: ca.SX
    objective: ca.SX
    blocks: tuple[tuple[str, ca.SX, float, float], ...]


@dataclass(frozen=True)
class Margins:
    """How much tighter than stated a repair made each path-constraint row (in the order of the path vector) and
    each node state bound (the states' part of ``z``)."""

    path: np.ndarray
    bounds: np.ndarray
    violation: float = float("inf")
    """The dense check's worst violation that led to these margins (the next repair must do better)."""
    cone: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Each stated cone's tightening at each node it holds (its bound less this), in :attr:`cone_rows` order."""

    @classmethod
    def none(cls, path_rows: int, state_values: int, cone_rows: int = 0) -> Margins:
        return cls(np.zeros(path_rows), np.zeros(state_values), cone=np.zeros(cone_rows))


def cone_scales(W: sp.csr_matrix, variable_scale: np.ndarray, sizes: tuple[int, ...]) -> np.ndarray:
    """The magnitude of each cone's entries: the largest change of one of its rows when every variable moves by its
    own scale, :math:`\\max_r \\sum_j |W_{rj}| \\sigma_j` (1 for a cone whose entries do not move)."""
    reach = np.abs(W) @ variable_scale
    ends = np.cumsum(sizes)
    out = np.array([float(np.max(reach[end - size: end], initial=0.0)) for end, size in zip(ends, sizes, strict=True)])
    return np.where(out > 0, out, 1.0)
