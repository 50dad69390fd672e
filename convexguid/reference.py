"""Independent reference solutions used to cross-check the SCP engine: what the families' references share.

Each family's ``reference`` module (e.g. :mod:`convexguid.families.flat_attitude.reference`)
re-implements the formulation's nonlinear maps in a modelling language of its own (CasADi)
and hands the *same* transcription (grid, quadrature, boundary-condition rows,
path-constraint points) to a general NLP solver (IPOPT). They need the optional ``casadi``
dependency (``pip install convexguid[bench]``) and import it lazily, so importing them
never requires it.
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ReferenceResult:
    """Outcome of a reference NLP solve.

    Attributes
    ----------
    x : numpy.ndarray
        Optimal decision vector in the layout of the program solved (flat attitude: node-major
        Euler angles, rad; rendezvous arcs: the :class:`ArcLayout` vector, SI units).
    objective : float
        Optimal objective (flat attitude: energy, N^2 m^2 s; rendezvous: total burn time, s).
    iterations : int
        IPOPT iterations.
    status : str
        IPOPT's ``return_status`` (e.g. ``Solve_Succeeded``).
    success : bool
        Whether IPOPT reports success.
    wall_time_s : float
        Wall time of the solve call only, s.
    setup_time_s : float
        Wall time of building the CasADi NLP and the IPOPT solver object, s.
    """

    x: np.ndarray
    objective: float
    iterations: int
    status: str
    success: bool
    wall_time_s: float
    setup_time_s: float


def casadi_available() -> bool:
    """Whether the optional dependency ``casadi`` can be imported."""
    return importlib.util.find_spec("casadi") is not None


@dataclass(frozen=True)
class IndependentOptimum:
    """The best objective an independent method found for a problem: what a plan's optimality is judged against.

    ``objective`` is None when no start succeeded. ``method`` says what found it (e.g. ``IPOPT, exact Hessian,
    best of 4 starts``); ``solved`` counts the starts that succeeded; ``infeasible`` is True only when the method
    proves that no plan exists (a convex relaxation that is infeasible).
    """

    objective: float | None
    method: str
    solved: int = 0
    starts: int = 1
    infeasible: bool = False

    def gap(self, objective: float | None) -> float | None:
        """Relative gap ``(objective - best) / |best|`` (negative: the plan beats the reference); None if either
        is missing."""
        if objective is None or self.objective is None:
            return None
        return (objective - self.objective) / max(abs(self.objective), 1e-12)


def best_of_starts(solve_from, starts: int, method: str) -> IndependentOptimum:
    """Run ``solve_from(k)`` (a :class:`ReferenceResult`) for ``k = 0 .. starts - 1``; the best successful objective."""
    results = [solve_from(k) for k in range(starts)]
    solved = [r.objective for r in results if r.success]
    return IndependentOptimum(min(solved) if solved else None, f"{method}, best of {starts} starts", len(solved),
                              starts)
