"""Look backends up by name, and the ``auto`` choice."""

from __future__ import annotations

import copy
import importlib.util
import time
from functools import cache

from convexguid.backends.base import Backend, BackendResult, ConicProgram
from convexguid.backends.bounded import PiqpBackend
from convexguid.backends.dense import DaqpBackend
from convexguid.backends.solvers import ClarabelBackend, OsqpBackend, QpsolversBackend
from convexguid.errors import BackendError

AUTO = "auto"
_QPSOLVERS_PREFIX = "qpsolvers:"

DENSE_MAX_VARIABLES = 400
"""``auto`` takes the dense solver only for programs with at most this many variables ...

(cai2018 with check points, measured: N = 128, 387 variables, DAQP condensed 2.6 s against
Clarabel 9.4 s; N = 256, 771 variables, DAQP 124 s: the dense active set no longer pays.)"""

DENSE_MIN_DENSITY = 0.3
"""... whose constraint matrix (or, in the SCP, whose Jacobians) have at least this share of nonzeros."""


@cache
def native_backends() -> dict[str, type[Backend]]:
    """The backends this package drives directly, by name (``daqp`` when it is installed; looked up once)."""
    natives: dict[str, type[Backend]] = {"clarabel": ClarabelBackend, "osqp": OsqpBackend}
    if importlib.util.find_spec("daqp") is not None:
        natives["daqp"] = DaqpBackend
    if importlib.util.find_spec("piqp") is not None:
        natives["piqp"] = PiqpBackend
    return natives


def available_backends() -> tuple[str, ...]:
    """Names accepted by :func:`make_backend` on this machine."""
    import qpsolvers  # its solver discovery is slow: only when the list is asked for

    return (AUTO, *native_backends(), *(_QPSOLVERS_PREFIX + s for s in sorted(qpsolvers.available_solvers)))


def check_backend_name(name: str) -> None:
    """Raise :class:`BackendError` listing the installed backends if ``name`` is unknown."""
    if name == AUTO or name in native_backends():
        return
    names = available_backends()
    if name not in names:
        raise BackendError(f"unknown backend {name!r}; installed: {', '.join(names)}")


def is_dense_backend(name: str) -> bool:
    """Whether backend ``name`` solves dense programs (the SCP then hands it the condensed subproblem)."""
    return bool(getattr(native_backends().get(name), "dense", False))


def auto_backend(program: ConicProgram) -> str:
    """What ``auto`` runs on ``program``: ``daqp`` when it is small, dense and has no cones but zero and
    nonnegative ones (and DAQP is installed), else ``clarabel``."""
    n = program.num_variables
    if program.cones.soc or n > DENSE_MAX_VARIABLES or "daqp" not in native_backends():
        return "clarabel"
    size = program.A.shape[0] * n
    return "daqp" if size and program.A.nnz >= DENSE_MIN_DENSITY * size else "clarabel"


def make_backend(name: str, program: ConicProgram, tolerance: float = 1e-8, max_iterations: int = 0,
                 fallback: str | None = None, iterative_refinement: bool = True) -> Backend:
    """Set up backend ``name`` for ``program`` (see :mod:`convexguid.backends`).

    ``auto`` picks by :func:`auto_backend` (a dense solve falls back to Clarabel when it is not
    ``optimal``); ``fallback`` names a backend to solve the same program whenever ``name``'s answer is
    not ``optimal``. ``iterative_refinement=False`` skips the refinement of an interior-point
    backend's KKT solves (Clarabel), for problems where that is measured to change nothing but time.
    """
    check_backend_name(name)
    if name == AUTO:
        chosen = auto_backend(program)
        backend = make_backend(chosen, program, tolerance, max_iterations,
                               fallback="clarabel" if chosen != "clarabel" else None,
                               iterative_refinement=iterative_refinement)
        backend.name = f"{AUTO} -> {chosen}"
        return backend
    natives = native_backends()
    if name in natives:
        backend = natives[name](program, tolerance, max_iterations, iterative_refinement)
    else:
        backend = QpsolversBackend(name.removeprefix(_QPSOLVERS_PREFIX), program, tolerance, max_iterations,
                                   iterative_refinement)
    if fallback is not None and fallback != name:
        backend = FallbackBackend(backend, fallback, program, tolerance, max_iterations, iterative_refinement)
    return backend


class FallbackBackend(Backend):
    """``primary``, and backend ``secondary`` on the same program whenever ``primary`` is not ``optimal``.

    The secondary is set up at its first use and kept up to date from then on. ``fallbacks`` counts
    the solves it answered; the time and status reported are those of both solves together and of
    the secondary.
    """

    def __init__(self, primary: Backend, secondary: str, program: ConicProgram, tolerance: float = 1e-8,
                 max_iterations: int = 0, iterative_refinement: bool = True) -> None:
        self.primary, self.secondary_name = primary, secondary
        self.name = f"{primary.name} (else {secondary})"
        self.supports_soc = primary.supports_soc
        self.secondary: Backend | None = None
        self.fallbacks = 0
        super().__init__(program, tolerance, max_iterations, iterative_refinement)

    def _setup(self, program: ConicProgram) -> None:
        self._program = program

    def sibling(self, program: ConicProgram) -> FallbackBackend | None:
        """The primary's sibling (:meth:`Backend.sibling`) with the same fallback, set up at its first use."""
        primary = self.primary.sibling(program)
        if primary is None:
            return None
        twin = copy.copy(self)
        twin.primary, twin.secondary, twin.fallbacks, twin._program = primary, None, 0, program
        return twin

    def _update(self, program: ConicProgram) -> None:
        self._program = program
        self.primary.update(program)
        if self.secondary is not None:
            self.secondary.update(program)

    def solve(self) -> BackendResult:
        first = self.primary.solve()
        if first.status == "optimal":
            return first
        start = time.perf_counter()
        if self.secondary is None:
            self.secondary = make_backend(self.secondary_name, self._program, self.tolerance, self.max_iterations,
                                          iterative_refinement=self.iterative_refinement)
        second = self.secondary.solve()
        self.fallbacks += 1
        elapsed = first.solve_time_s + time.perf_counter() - start
        return BackendResult(second.status, second.x, second.objective, first.iterations + second.iterations,
                             elapsed, second.primal_residual, second.dual_residual, second.z)
