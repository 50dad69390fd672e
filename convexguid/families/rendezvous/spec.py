"""Problem family ``rendezvous``: finite-thrust minimum-burn-time rendezvous in Clohessy-Wiltshire dynamics.

Positions and velocities are in the target's orbit frame of Wang & Tang (2003), Fig. 1:
x opposite to the target's orbital velocity, y away from the Earth, z along the orbit
normal. Two-component vectors give the coplanar problem ``[x, y]``; three components
the full 3-D one.

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, PlainValidator, field_validator, model_validator

from convexguid.sizes import PROCESS_BYTES, SizeEstimate
from convexguid.spec.common import (
    PositiveFloat,
    ProblemBase,
    Reference,
    SolverSettings,
    SpecModel,
    TimeInterval,
    readonly,
    spec_error,
)


def _plane_or_space_vector(v: object) -> tuple[float, ...]:
    """Two (coplanar) or three (3-D) finite numbers."""
    hint = "give a list of 2 (coplanar x, y) or 3 (x, y, z) finite numbers"
    if not isinstance(v, (list, tuple)) or len(v) not in (2, 3):
        raise spec_error("expected a list of 2 or 3 numbers", hint, value=v)
    for i, x in enumerate(v):
        if not isinstance(x, (int, float)) or isinstance(x, bool):
            raise spec_error("not a number", hint, key=(i,), value=x)
        if not math.isfinite(x):
            raise spec_error("not a finite number", hint, key=(i,), value=x)
    return tuple(float(x) for x in v)


RelativeVector = Annotated[tuple[float, ...], PlainValidator(_plane_or_space_vector)]


class RelativeState(SpecModel):
    """Chaser position and velocity relative to the target, orbit frame.

    Attributes
    ----------
    position_m : tuple of float
        (x, y) or (x, y, z), m.
    velocity_mps : tuple of float
        Same components as ``position_m``, m/s.
    """

    position_m: RelativeVector
    velocity_mps: RelativeVector

    @property
    def state(self) -> np.ndarray:
        """``[position, velocity]`` in SI units (read-only)."""
        return readonly(np.array(self.position_m + self.velocity_mps))


class RendezvousBoundary(TimeInterval):
    """Maneuver interval (``tf_s > t0_s``) and boundary states of the same dimension."""

    initial: RelativeState
    final: RelativeState

    @model_validator(mode="after")
    def _same_dimension(self) -> RendezvousBoundary:
        """Every position and velocity has the same components; the one that differs from most is named."""
        vectors = {(state, part): getattr(getattr(self, state), part)
                   for state in ("initial", "final") for part in ("position_m", "velocity_mps")}
        usual = Counter(len(v) for v in vectors.values()).most_common(1)[0][0]  # ties: the initial position's
        odd = next((key for key, v in vectors.items() if len(v) != usual), None)
        if odd is not None:
            others = [f"{{here}}{'.'.join(k)}" for k, v in vectors.items() if len(v) == usual]
            raise spec_error(f"has {len(vectors[odd])} components but {', '.join(others)} "
                             f"{'have' if len(others) > 1 else 'has'} {usual}",
                             "give every position and velocity the same components: 2 (coplanar x, y) or 3 (x, y, z)",
                             key=odd, value=list(vectors[odd]))
        return self

    @property
    def dim(self) -> int:
        """2 (coplanar) or 3."""
        return len(self.initial.position_m)


class Orbit(SpecModel):
    """Circular target orbit. ``mean_motion_radps``: orbital rate n, rad/s."""

    mean_motion_radps: PositiveFloat


class Thruster(SpecModel):
    """Constant-magnitude thruster. ``accel_mps2``: thrust acceleration a while burning, m/s^2."""

    accel_mps2: PositiveFloat


MAX_BURNS = 20
"""The most burn arcs ``scp_arcs`` plans (``discretization.burns``)."""


class RendezvousDiscretization(SpecModel):
    """Discretisation of both methods.

    Attributes
    ----------
    burns : int or "auto"
        ``scp_arcs``: number of burn arcs, separated by coast arcs (2: burn - coast - burn); ``auto`` takes the
        number of burns of the ``lcvx`` optimum (which is then solved whatever ``certify`` says).
    subintervals_per_burn : int
        ``scp_arcs``: equal Hermite-Simpson sub-intervals of each burn (12 in the paper).
    grid_steps : int
        ``lcvx``: zero-order-hold steps over the maneuver (also the certificate of ``scp_arcs``).
    """

    burns: int | Literal["auto"] = 2

    @field_validator("burns", mode="before")
    @classmethod
    def _burn_count(cls, value: object) -> object:
        whole = isinstance(value, int) and not isinstance(value, bool)
        if value == "auto" or (whole and 1 <= value <= MAX_BURNS):
            return value
        raise spec_error(f"not a number of burns from 1 to {MAX_BURNS}, nor auto",
                         "give e.g. 2 (burn - coast - burn), or auto for the lcvx optimum's count", value=value)

    @property
    def auto_burns(self) -> bool:
        return self.burns == "auto"

    @property
    def burns_at_most(self) -> int:
        """The number of burns, or the most ``auto`` can give (:data:`MAX_BURNS`): for size estimates."""
        return MAX_BURNS if self.auto_burns else self.burns
    subintervals_per_burn: Annotated[int, Field(ge=1, le=500)] = 12
    grid_steps: Annotated[int, Field(ge=2, le=100000)] = 600


class RendezvousVerification(SpecModel):
    """Dense re-propagation of the planned thrust.

    Attributes
    ----------
    grid_points : int
        Points of the dense output grid.
    rtol, atol : float
        Integrator tolerances.
    final_position_tol_m, final_velocity_tol_mps : float
        Allowed distance of the propagated final state from the target.
    thrust_tol : float
        Allowed deviation of the planned thrust magnitude from its bound (|u| <= Gamma <= 1).
    """

    grid_points: Annotated[int, Field(ge=100)] = 4001
    rtol: PositiveFloat = 1e-11
    atol: PositiveFloat = 1e-9
    final_position_tol_m: PositiveFloat = 1.0
    final_velocity_tol_mps: PositiveFloat = 0.01
    thrust_tol: PositiveFloat = 1e-6


class RendezvousProblem(ProblemBase):
    """A ``rendezvous`` problem file (see ``problems/wang2003_rendezvous.yaml``).

    ``method``: ``scp_arcs`` (the paper's burn/coast transcription solved by SCP) or
    ``lcvx`` (lossless convexification on a fixed grid, one SOCP). ``certify``: with
    ``scp_arcs``, also solve the ``lcvx`` problem and report the gap to its global optimum.
    """

    family: Literal["rendezvous"]
    method: Literal["scp_arcs", "lcvx"] = "scp_arcs"  # type: ignore[assignment]
    orbit: Orbit
    spacecraft: Thruster
    boundary: RendezvousBoundary
    objective: Literal["burn_time"] = "burn_time"
    discretization: RendezvousDiscretization = RendezvousDiscretization()
    certify: bool = True
    solver: SolverSettings = SolverSettings(max_iterations=200)
    verification: RendezvousVerification = RendezvousVerification()
    reference: Reference | None = None


BYTES_PER_GRID_STEP = 80_000
"""Peak memory per zero-order-hold step of the ``lcvx`` problem as transcribed by ``convexguid.ocp`` (measured 45 kB
coplanar at 2400 steps, 61 kB in three dimensions at 10 000; at least what ``convexguid.ocp``'s own estimate of its
flow gives, so the family's limit, naming ``discretization.grid_steps``, comes first)."""

BYTES_PER_SUBINTERVAL = (36_000, 10)
"""Peak memory of ``scp_arcs`` as ``a S + b S^2`` for ``S`` burn sub-intervals in all (fitted at S = 800, 1600)."""


def estimate_size(spec: RendezvousProblem) -> SizeEstimate:
    """Peak memory of a solve: the ``lcvx`` grid (also ``scp_arcs``'s certificate) and the ``scp_arcs`` arcs."""
    d = spec.discretization
    grid = BYTES_PER_GRID_STEP * d.grid_steps if spec.method == "lcvx" or spec.certify or d.auto_burns else 0
    s = d.burns_at_most * d.subintervals_per_burn if spec.method == "scp_arcs" else 0
    arcs = BYTES_PER_SUBINTERVAL[0] * s + BYTES_PER_SUBINTERVAL[1] * s**2
    key, value = (("discretization.grid_steps", d.grid_steps) if grid >= arcs
                  else ("discretization.subintervals_per_burn", d.subintervals_per_burn))
    return SizeEstimate(PROCESS_BYTES + grid + arcs, key, value,
                        f"{d.grid_steps if grid else 0} lcvx steps, {s} burn sub-intervals")
