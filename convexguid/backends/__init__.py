"""Convex solver backends, looked up by name.

Every SCP subproblem reaches a backend as a :class:`ConicProgram` in Clarabel's
standard form

.. math::

    \\min_x \\tfrac12 x^T P x + q^T x \\quad \\text{s.t.}\\quad A x + s = b,\\; s \\in \\mathcal K,

with :math:`\\mathcal K` a product of zero cones (equalities), nonnegative cones
(:math:`A x \\le b`) and second-order cones, in that order. A backend is set up
once and then receives new numbers with the same sparsity pattern every SCP
iteration (:meth:`Backend.update`), so persistent solvers skip their symbolic
factorisation.

Names: ``auto`` (the default: :func:`~convexguid.backends.registry.auto_backend`; the SCP
decides by :mod:`convexguid.scp.choice`), ``clarabel`` (QP and SOCP), ``osqp`` (QP only),
``piqp`` (sparse QP with its single-variable rows as bounds, :mod:`convexguid.backends.bounded`),
``daqp`` (dense active-set QP, :mod:`convexguid.backends.dense`; the SCP hands it the condensed
subproblem), and ``qpsolvers:<solver>`` for every QP solver that :mod:`qpsolvers` finds
installed (re-solved from scratch each time: meant for cross-checks).
"""

from __future__ import annotations

from convexguid.backends.base import Backend, BackendResult, Cones, ConicProgram
from convexguid.backends.registry import (
    AUTO,
    FallbackBackend,
    auto_backend,
    available_backends,
    check_backend_name,
    is_dense_backend,
    make_backend,
)

__all__ = [
    "AUTO",
    "Backend",
    "BackendResult",
    "ConicProgram",
    "Cones",
    "FallbackBackend",
    "auto_backend",
    "available_backends",
    "check_backend_name",
    "is_dense_backend",
    "make_backend",
]
