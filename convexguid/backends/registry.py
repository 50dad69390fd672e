"""Look backends up by name."""

from __future__ import annotations

from convexguid.backends.base import Backend, ConicProgram
from convexguid.backends.solvers import ClarabelBackend, OsqpBackend, QpsolversBackend
from convexguid.errors import BackendError

_NATIVE: dict[str, type[Backend]] = {"clarabel": ClarabelBackend, "osqp": OsqpBackend}
_QPSOLVERS_PREFIX = "qpsolvers:"


def available_backends() -> tuple[str, ...]:
    """Names accepted by :func:`make_backend` on this machine."""
    import qpsolvers

    return tuple(_NATIVE) + tuple(_QPSOLVERS_PREFIX + s for s in sorted(qpsolvers.available_solvers))


def check_backend_name(name: str) -> None:
    """Raise :class:`BackendError` listing the installed backends if ``name`` is unknown."""
    if name in _NATIVE:
        return
    names = available_backends()
    if name not in names:
        raise BackendError(f"unknown backend {name!r}; installed: {', '.join(names)}")


def make_backend(name: str, program: ConicProgram, tolerance: float = 1e-8,
                 max_iterations: int = 0) -> Backend:
    """Set up backend ``name`` for ``program`` (see :mod:`convexguid.backends`)."""
    check_backend_name(name)
    if name in _NATIVE:
        return _NATIVE[name](program, tolerance, max_iterations)
    return QpsolversBackend(name.removeprefix(_QPSOLVERS_PREFIX), program, tolerance, max_iterations)
