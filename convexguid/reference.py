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
