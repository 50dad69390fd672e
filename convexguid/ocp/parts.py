"""The pieces a transcription is built from that are not the transcription: the CasADi sparsity pattern of a
Jacobian block, the derivatives kept for the next statement of the same graph, the repair margins, the symbolic NLP
it hands to an independent solver, the cones as one affine map in their own scales, and classical Runge-Kutta steps
(a hold's flow, symbolic; a first guess's flight, numeric)."""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.scp.problem import ConeBlock


def runge_kutta(rate: Callable, x, step, steps: int, start=None):
    """``x`` after ``steps`` classical Runge-Kutta steps of length ``step`` under ``rate(x, t)``, the times counted
    from ``start`` (from 0 without one); on CasADi symbols and on NumPy arrays alike."""
    for i in range(steps):
        t = i * step if start is None else start + i * step
        k1 = rate(x, t)
        k2 = rate(x + step / 2 * k1, t + step / 2)
        k3 = rate(x + step / 2 * k2, t + step / 2)
        k4 = rate(x + step * k3, t + step)
        x = x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


class SparsityPattern:
    """A CasADi structural sparsity read once; each evaluation only fills its values (the engine fixes the
    subproblem's pattern from the first one)."""

    def __init__(self, pattern: ca.Sparsity) -> None:
        rows, cols = pattern.get_triplet()
        self.rows, self.cols = np.asarray(rows, dtype=int), np.asarray(cols, dtype=int)
        self.shape = pattern.shape

    def coo(self, values: ca.DM) -> sp.coo_matrix:
        return sp.coo_matrix((np.asarray(values.nonzeros(), dtype=float), (self.rows, self.cols)), shape=self.shape)


class DerivativeCache:
    """Symbolic derivatives (CasADi functions) of the last :attr:`size` statements, by their expression graph.

    Differentiating a transcription is most of its set-up (the multi-cone slew: 0.08 s of Jacobians, 0.07 s of
    function construction and 0.05 s of the Lagrangian's Hessian by element classes, in a 0.8 s solve), and a
    campaign or a repeated solve states the same graph again: a sweep of a torque limit or of the boundary
    attitudes changes only the bounds and the linear constraints, which are not in it. The key is a SHA-256 of
    the serialized graph of the given inputs and outputs, every constant in it (13 ms for the multi-cone slew's
    511 variables), so two statements share derivatives only when their maps are the same expressions.
    """

    def __init__(self, size: int = 8) -> None:
        self.size = size
        self._entries: OrderedDict[str, object] = OrderedDict()

    def get(self, kind: str, inputs: list[ca.SX], outputs: list[ca.SX], build: Callable[[], object]) -> object:
        """``build()`` (derivatives of the ``kind`` named) for this graph, or what it gave the last time."""
        key = kind + hashlib.sha256(ca.Function("statement", inputs, outputs).serialize().encode()).hexdigest()
        if key in self._entries:
            self._entries.move_to_end(key)
            return self._entries[key]
        value = self._entries[key] = build()
        while len(self._entries) > self.size:
            self._entries.popitem(last=False)
        return value


DERIVATIVES = DerivativeCache()
"""The process's derivative cache (:class:`DerivativeCache`)."""


def coo_pattern(pattern: ca.Sparsity) -> sp.coo_matrix:
    """A CasADi pattern as a 0/1 matrix."""
    rows, cols = pattern.get_triplet()
    return sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=pattern.shape)


class NumericFunction:
    """A CasADi function of column vectors evaluated on numbers through its buffers (``Function.buffer``), its first
    output returned as a dense numpy vector. About a microsecond a call against 30 for a call with numpy arrays
    (measured on a Clohessy-Wiltshire rate): the dense check calls the dynamics some 10^5 times on a 600-interval
    plan. One instance is not for two threads at once (its buffers are its own)."""

    def __init__(self, function: ca.Function) -> None:
        self._inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self._values = np.zeros(function.nnz_out(0))
        self._rows = np.asarray(function.sparsity_out(0).get_triplet()[0], dtype=int)
        self._size = function.size1_out(0)
        self._buffer, self._trigger = function.buffer()
        for i, values in enumerate(self._inputs):
            self._buffer.set_arg(i, memoryview(values))
        self._buffer.set_res(0, memoryview(self._values))

    def __call__(self, *args) -> np.ndarray:
        for target, value in zip(self._inputs, args, strict=True):
            target[:] = value
        self._trigger()
        out = np.zeros(self._size)
        out[self._rows] = self._values
        return out


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


@dataclass(frozen=True)
class AffineCones:
    """A transcription's second-order cones as one affine map :math:`Wz + w` (constant ``W``, in
    :class:`~convexguid.scp.problem.ConeBlock` order), built once in both the forms an evaluation needs.

    Each cone is divided by its own magnitude (:func:`cone_scales`), which leaves the set it describes as it is:
    its violation is then judged in that magnitude, as the defects are in the states' scales. A glide slope in
    metres over a 2 km descent was otherwise held to 1e-7 m, below what the convex solver resolves (measured: a
    powered-descent round stalled 2.5e-7 m outside it and phase 1 took that for an infeasibility). The first
    ``stated`` cones are the user's, whose bounds a repair may tighten (:attr:`Margins.cone`).
    """

    sizes: tuple[int, ...]
    W: sp.csr_matrix
    W_coo: sp.coo_matrix
    offset: np.ndarray
    first_rows: np.ndarray
    """The first row (the bound) of each stated cone."""
    margin_scale: np.ndarray
    """Each stated cone's division by its magnitude (a margin in the cone's unit is scaled the same)."""

    @classmethod
    def of(cls, z: ca.SX, parts: list, stated: int, variable_scale: np.ndarray) -> AffineCones:
        """The cones ``parts`` (each a column ``(bound, vector)`` affine in ``z``), the first ``stated`` of them the
        user's."""
        sizes = tuple(part.shape[0] for part in parts)
        stacked = ca.vertcat(*parts)
        jacobian = ca.jacobian(stacked, z)
        constant = ca.Function("cone_map", [z], [jacobian, stacked])(np.zeros(z.shape[0]))
        W = SparsityPattern(jacobian.sparsity()).coo(constant[0])
        row_scale = np.repeat(1.0 / cone_scales(W.tocsr(), variable_scale, sizes), sizes)
        W = sp.coo_matrix((W.data * row_scale[W.row], (W.row, W.col)), shape=W.shape)
        firsts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int)[:stated]
        return cls(sizes, W.tocsr(), W, np.asarray(constant[1]).ravel() * row_scale, firsts, row_scale[firsts])

    def block(self, z: np.ndarray, margins: np.ndarray, jacobians: bool) -> ConeBlock:
        """The cones at ``z``, each stated cone's bound less its repair margin."""
        values = self.W @ z + self.offset
        values[self.first_rows] -= margins * self.margin_scale
        return ConeBlock("cone_constraints", values, self.W_coo if jacobians else None, self.sizes, "scaled")
