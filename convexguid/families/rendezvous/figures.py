"""Summary figures of a ``rendezvous`` solve, and the figures either method hands over with its plan."""

from __future__ import annotations

from dataclasses import dataclass

from convexguid.solution import Figures, optional

Arc = tuple[float, float]
"""A burn ``(start, end)``, s."""


@dataclass(frozen=True)
class ArcsPlanFigures:
    """What the ``scp_arcs`` plan adds: the arc durations, the mesh and the interpolated direction's norm."""

    arc_durations_s: tuple[float, ...]
    subintervals_per_burn: int
    planned_direction_norm_min: float


@dataclass(frozen=True)
class LcvxPlanFigures:
    """What the ``lcvx`` plan adds (a plan the solver could not use reports the solver iterations only)."""

    solver_iterations: int
    grid_steps: int | None = None
    intermediate_throttle_share: float | None = None
    intermediate_throttle_steps: int | None = None
    lossless_gap_max: float | None = None


@dataclass(frozen=True)
class LcvxCertificate:
    """The ``scp_arcs`` burn time against the ``lcvx`` global optimum on the fixed grid (None where not both
    converged; the lcvx burns only when they did)."""

    lcvx_status: str
    lcvx_burn_time_s: float | None = None
    lcvx_gap_rel: float | None = None
    lcvx_burn_arcs_s: tuple[Arc, ...] | None = None


@dataclass(frozen=True)
class RendezvousFigures(Figures):
    """Figures of a rendezvous plan; the optional ones belong to one method (or to the certificate).

    ``burn_time_s`` is None unless the plan converged. The ``scp_arcs`` fields are those of
    :class:`ArcsPlanFigures`, the ``lcvx`` ones those of :class:`LcvxPlanFigures`, the ``lcvx_*`` ones
    those of :class:`LcvxCertificate` (``scp_arcs`` with ``certify``).
    """

    burn_time_s: float | None
    num_burns: int
    burn_arcs_s: tuple[Arc, ...]
    accel_mps2: float
    mean_motion_radps: float
    # scp_arcs
    arc_durations_s: tuple[float, ...] | None = optional()
    subintervals_per_burn: int | None = optional()
    planned_direction_norm_min: float | None = optional()
    # lcvx
    grid_steps: int | None = optional()
    solver_iterations: int | None = optional()
    intermediate_throttle_share: float | None = optional()
    intermediate_throttle_steps: int | None = optional()
    lossless_gap_max: float | None = optional()
    # certificate of scp_arcs by lcvx
    lcvx_status: str | None = optional()
    lcvx_burn_time_s: float | None = optional(along="lcvx_status")
    lcvx_gap_rel: float | None = optional(along="lcvx_status")
    lcvx_burn_arcs_s: tuple[Arc, ...] | None = optional()
