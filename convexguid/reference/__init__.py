"""Independent reference solutions used to cross-check the SCP engine.

The reference solvers re-implement a formulation's nonlinear maps in a modelling
language of their own (CasADi) and hand the *same* transcription (grid, quadrature,
boundary-condition rows, path-constraint points) to a general NLP solver (IPOPT).
They need the optional ``casadi`` dependency (``pip install convexguid[bench]``) and
import it lazily, so importing this package never requires it.
"""

from __future__ import annotations

from convexguid.reference.ipopt_flat import ReferenceResult, casadi_available, solve_flat_attitude_ipopt
from convexguid.reference.ipopt_rendezvous import ArcsReferenceResult, cw_free_motion, solve_rendezvous_arcs_ipopt

__all__ = ["ArcsReferenceResult", "ReferenceResult", "casadi_available", "cw_free_motion", "solve_flat_attitude_ipopt",
           "solve_rendezvous_arcs_ipopt"]
