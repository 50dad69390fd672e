"""Summary figures of a ``quaternion_attitude`` solve (SCP or path transfer)."""

from __future__ import annotations

from dataclasses import dataclass

from convexguid.solution import Figures, optional


@dataclass(frozen=True)
class ConeGeometry:
    """A pointing cone as plain data, for the summary and the sky plots
    (:meth:`convexguid.geometry.PointingCone.to_dict`)."""

    name: str
    body_axis: tuple[float, float, float]
    inertial_dir: tuple[float, float, float]
    half_angle_deg: float
    keep_out: bool = True

    @classmethod
    def of(cls, cone) -> ConeGeometry:
        """The geometry of a :class:`~convexguid.geometry.PointingCone`."""
        d = cone.to_dict()
        return cls(d["name"], tuple(d["body_axis"]), tuple(d["inertial_dir"]), d["half_angle_deg"], d["keep_out"])


@dataclass(frozen=True)
class QuaternionAttitudeFigures(Figures):
    """Figures of a quaternion attitude plan.

    Always: the eigenaxis slew's clearance to each keep-out cone direction (deg, by cone name) and the cone
    geometry. The SCP fills ``min_time_s`` (minimum energy with the final time from the minimum time), the node
    figures and, after a dense check, ``energy`` and ``min_cone_margin_deg`` (None without cones); path transfer
    fills ``planning_time_s``, ``energy``, ``min_cone_margin_deg`` and ``actions``. Fields a solve does not
    fill are left out of the summary (a minimum-time step that fails leaves only the first two).
    """

    eigenaxis_min_angle_deg: dict[str, float]
    cones: tuple[ConeGeometry, ...]
    min_time_s: float | None = optional()
    maneuver_time_s: float | None = optional()
    planning_time_s: float | None = optional(compute_time=True)
    node_constraint_margin_deg: float | None = optional()
    max_quaternion_norm_error: float | None = optional()
    interval_s: float | None = optional()
    initial_guess: str | None = optional()
    objective_kind: str | None = optional()
    energy: float | None = optional()
    min_cone_margin_deg: float | None = optional(along="energy")
    actions: tuple[str, ...] | None = optional()
