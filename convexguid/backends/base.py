"""The conic program handed to backends, and what they hand back."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Cones:
    """Row counts of the cone blocks of ``A x + s = b``, in this order.

    Attributes
    ----------
    zero
        Equality rows (``A x = b``).
    nonneg
        Inequality rows (``A x <= b``).
    soc
        Sizes of the second-order cones ``||(b - A x)[1:]|| <= (b - A x)[0]``.
    """

    zero: int = 0
    nonneg: int = 0
    soc: tuple[int, ...] = ()

    @property
    def rows(self) -> int:
        return self.zero + self.nonneg + sum(self.soc)


@dataclass
class ConicProgram:
    """``min 1/2 x'Px + q'x + constant  s.t.  A x + s = b, s in cones``.

    ``P`` holds the upper triangle only (CSC); ``A`` is CSC with one row per cone
    entry. The sparsity patterns of ``P`` and ``A`` are fixed for the life of a
    backend: :meth:`Backend.update` only replaces their ``data`` arrays. ``constant``
    does not change the solution; backends ignore it and :meth:`objective` adds it
    (a condensed subproblem carries the part of its model value that no longer
    depends on a variable there).
    """

    P: sp.csc_matrix
    q: np.ndarray
    A: sp.csc_matrix
    b: np.ndarray
    cones: Cones
    constant: float = 0.0

    @property
    def num_variables(self) -> int:
        return self.q.size

    def hessian_times(self, x: np.ndarray) -> np.ndarray:
        """:math:`P x` for the symmetric ``P`` whose upper triangle is stored."""
        return self.P @ x + self.P.T @ x - self.P.diagonal() * x

    def objective(self, x: np.ndarray) -> float:
        """:math:`\\tfrac12 x^T P x + q^T x` + ``constant``, with ``P`` stored as its upper triangle."""
        return float(0.5 * x @ self.hessian_times(x) + self.q @ x + self.constant)


@dataclass(frozen=True)
class BackendResult:
    """Outcome of one convex solve.

    ``status`` is one of ``optimal``, ``optimal_inaccurate``, ``infeasible``,
    ``unbounded``, ``failed``. Residuals are the backend's own primal and dual
    residuals so that optimality can be checked rather than assumed. ``z`` holds the
    multipliers of the rows of ``A x + s = b`` (nonnegative on the ``nonneg`` rows), when
    the backend reports them.
    """

    status: str
    x: np.ndarray | None
    objective: float
    iterations: int
    solve_time_s: float
    primal_residual: float
    dual_residual: float
    z: np.ndarray | None = None
    exact_objective: bool = False
    """``objective`` is :meth:`ConicProgram.objective` at ``x`` less the constant, to rounding (the dense backend's own
    check of its answer, with ``P x`` from its dense Hessian), so a caller need not evaluate it a second time."""

    @property
    def usable(self) -> bool:
        return self.status in ("optimal", "optimal_inaccurate") and self.x is not None


class Backend(ABC):
    """A convex solver set up once for a fixed sparsity pattern."""

    name: str = ""
    supports_soc: bool = False

    def __init__(self, program: ConicProgram, tolerance: float = 1e-8, max_iterations: int = 0,
                 iterative_refinement: bool = True) -> None:
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        #: refine each KKT solve of an interior-point backend (Clarabel); other backends ignore it
        self.iterative_refinement = iterative_refinement
        self._pattern = (program.P.indptr.copy(), program.P.indices.copy(),
                         program.A.indptr.copy(), program.A.indices.copy(), program.cones)
        self._setup(program)

    def same_pattern(self, program: ConicProgram) -> bool:
        """Whether ``program`` has the cones and the sparsity pattern of this backend's first program."""
        P_ptr, P_idx, A_ptr, A_idx, cones = self._pattern
        return (program.cones == cones and np.array_equal(program.P.indptr, P_ptr)
                and np.array_equal(program.A.indptr, A_ptr) and np.array_equal(program.P.indices, P_idx)
                and np.array_equal(program.A.indices, A_idx))

    def update(self, program: ConicProgram) -> None:
        """Replace the numbers of the program; the sparsity pattern must not change."""
        if not self.same_pattern(program):
            raise ValueError(f"backend {self.name}: update() needs the sparsity pattern of the first program")
        self._update(program)

    def sibling(self, program: ConicProgram) -> Backend | None:
        """A second backend of this kind and settings for ``program`` (a program of the same pattern and
        structure, solved alongside: the end game's curved subproblem), with a warm start of its own and whatever
        this one read from the pattern taken over; ``None`` when that is not possible (set one up anew)."""
        return None

    @abstractmethod
    def _setup(self, program: ConicProgram) -> None: ...

    @abstractmethod
    def _update(self, program: ConicProgram) -> None: ...

    @abstractmethod
    def solve(self) -> BackendResult: ...
