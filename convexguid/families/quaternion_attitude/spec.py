"""Problem family ``quaternion_attitude``: rigid-body slews under keep-out/keep-in cones, torque and rate boxes.

Attitudes are scalar-last quaternions ``[x, y, z, w]`` (Hamilton product, body relative
to inertial), an Euler axis and angle, or Z-Y-X (3-2-1) Euler angles ``roll_pitch_yaw_deg``.
A quaternion whose norm is within :data:`convexguid.spec.common.QUATERNION_NORM_TOL` of 1 is
normalised (printed rounding); any other norm, zero included, is an error, since it is almost
certainly a typo. ``spacecraft.torque_max_Nm`` is one bound for every body axis or three (x, y, z).

References
----------
Wang, Xu, Li, path-transfer fast planning for large-angle attitude maneuvers under
multiple constraints (seed 003); Guo, Li, Ma 2011 (forbidden attitude, seed 001); Feng, Chen, Yang 2018
(per-axis torque box, Z-Y-X Euler boundary attitudes, seed 004).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from convexguid.geometry import PointingCone
from convexguid.rotations import axis_angle_to_quat, euler321_to_quat, quat_angle_between
from convexguid.sizes import PROCESS_BYTES, SizeEstimate
from convexguid.spec.attitude import KeepOutList, check_outside_keep_out, check_slew_time
from convexguid.spec.common import (
    Direction3,
    InertiaMatrix,
    InputLink,
    PositiveFloat,
    ProblemBase,
    Reference,
    ResultLink,
    SolverSettings,
    SpecModel,
    TorqueBox,
    UnitQuaternion,
    Vector3,
    VerificationSettings,
    named_list,
    readonly,
    spec_error,
    torque_box_vector,
)


class Attitude(SpecModel):
    """An attitude of the body relative to the inertial frame, in exactly one of three forms.

    ``quaternion`` (scalar last), ``axis`` + ``angle_deg`` (Euler axis and angle), or
    ``roll_pitch_yaw_deg: [roll, pitch, yaw]``: Z-Y-X (3-2-1) Euler angles, yaw :math:`\\psi` about z,
    then pitch :math:`\\theta` about the new y, then roll :math:`\\phi` about the new x, so
    :math:`C_{BI} = R_1(\\phi) R_2(\\theta) R_3(\\psi)` (:func:`convexguid.rotations.euler321_to_quat`);
    ``roll_pitch_yaw_deg: [0, 0, 90]`` is ``axis: [0, 0, 1], angle_deg: 90``.
    """

    quaternion: UnitQuaternion | None = None
    axis: Direction3 | None = None
    angle_deg: float | None = None
    roll_pitch_yaw_deg: Vector3 | None = None
    rate_degps: Vector3 = (0.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _one_form(self) -> Attitude:
        by_axis = self.axis is not None or self.angle_deg is not None
        forms = (self.quaternion is not None) + by_axis + (self.roll_pitch_yaw_deg is not None)
        if forms != 1 or (by_axis and (self.axis is None or self.angle_deg is None)):
            raise spec_error("give exactly one of quaternion, both axis and angle_deg, or roll_pitch_yaw_deg",
                             "e.g. quaternion: [0, 0, 0, 1] or roll_pitch_yaw_deg: [0, 0, 0]")
        return self

    @property
    def q(self) -> np.ndarray:
        if self.quaternion is not None:
            return readonly(np.array(self.quaternion))
        if self.roll_pitch_yaw_deg is not None:
            return readonly(euler321_to_quat(np.radians(self.roll_pitch_yaw_deg)))
        return readonly(axis_angle_to_quat(self.axis, math.radians(self.angle_deg)))

    @property
    def rate_radps(self) -> np.ndarray:
        return readonly(np.radians(self.rate_degps))


class QuaternionBoundary(SpecModel):
    """Initial and final attitudes; ``tf_s`` for a fixed final time (energy), omitted for minimum time.

    ``tf_min_time_factor``: with ``objective: energy`` and no ``tf_s``, the final time is this
    factor times the minimum time, which is solved for first.

    ``tf_from``: with ``objective: energy``, the final time is a figure of another case's result,
    ``{problem: <name>, figure: <summary key>}`` (e.g. a controller's maneuver time). The
    commands resolve it (they run that case first and set ``tf_s``, :mod:`convexguid.validation.links`); give
    ``tf_s`` or ``tf_from``, not both, and not with ``tf_min_time_factor``.
    """

    t0_s: float = 0.0
    tf_s: PositiveFloat | None = None
    tf_from: ResultLink | None = None
    tf_min_time_factor: Annotated[float, Field(gt=1.0)] | None = None
    initial: Attitude
    final: Attitude

    @model_validator(mode="after")
    def _one_final_time(self) -> QuaternionBoundary:
        if self.tf_from is not None:
            for other in ("tf_s", "tf_min_time_factor"):
                if getattr(self, other) is not None:
                    raise spec_error(f"{{here}}tf_from and {{here}}{other} are both set",
                                     f"give either tf_from (a figure of another case's result) or {other}",
                                     key=("tf_from",), value=self.tf_from.model_dump())
        return self


class AttitudeSpacecraft(SpecModel):
    """Rigid body with per-axis torque and rate boxes.

    ``torque_max_Nm`` is one positive number (the same bound on every body axis) or a list of 3 (x, y, z),
    :math:`|u_i| \\le u_{max,i}`; ``rate_max_degps`` bounds every body-rate component. Omit it (or write
    ``null``) for no rate bound: the rates are scaled by the slew's own eigenaxis rate, not by the bound, so a
    generous bound and none give the same plan.
    """

    inertia_kgm2: InertiaMatrix
    torque_max_Nm: TorqueBox
    rate_max_degps: PositiveFloat | None = None

    @property
    def inertia_matrix(self) -> np.ndarray:
        return readonly(np.array(self.inertia_kgm2))

    @property
    def torque_max_vector(self) -> np.ndarray:
        """Torque bound of each body axis (x, y, z), N m (length 3, read-only)."""
        return torque_box_vector(self.torque_max_Nm)


class KeepInSpec(SpecModel):
    """``body_axis`` must stay within ``half_angle_deg`` of the inertial ``inertial_dir``."""

    name: Annotated[str, Field(min_length=1)]
    body_axis: Direction3
    inertial_dir: Direction3
    half_angle_deg: Annotated[float, Field(gt=0, lt=180)]

    def pointing_cone(self) -> PointingCone:
        """This cone as a keep-in :class:`~convexguid.geometry.PointingCone` (unit vectors, rad)."""
        return PointingCone.from_spec(self, keep_out=False)


class ForbiddenAttitude(SpecModel):
    """The attitude must stay more than ``min_angle_deg`` (Euler-axis angle) from ``quaternion``."""

    name: Annotated[str, Field(min_length=1)]
    quaternion: UnitQuaternion
    min_angle_deg: Annotated[float, Field(gt=0, lt=180)]


class HermiteSimpsonGrid(SpecModel):
    """``intervals`` equal Hermite-Simpson intervals over the maneuver."""

    method: Literal["hermite_simpson"] = "hermite_simpson"
    intervals: Annotated[int, Field(ge=4, le=2000)] = 50


FAMILY_PENALTY = 30.0
"""Default exact-penalty weight, in units of the objective at the initial guess (the SCP scales it)."""


class QuaternionAttitudeProblem(ProblemBase):
    """A ``quaternion_attitude`` problem file (see ``problems/wang_multicone_time.yaml``)."""

    family: Literal["quaternion_attitude"]
    method: Literal["scp", "path_transfer"] = "scp"  # type: ignore[assignment]
    spacecraft: AttitudeSpacecraft
    boundary: QuaternionBoundary
    keep_out: KeepOutList = ()
    keep_in: named_list(KeepInSpec) = ()  # type: ignore[valid-type]
    forbidden: named_list(ForbiddenAttitude) = ()  # type: ignore[valid-type]
    objective: Literal["time", "energy"] = "time"
    initial_guess: Literal["eigenaxis", "path_transfer"] = "eigenaxis"
    discretization: HermiteSimpsonGrid = HermiteSimpsonGrid()
    solver: SolverSettings = SolverSettings(max_iterations=100, penalty=FAMILY_PENALTY)
    verification: VerificationSettings = VerificationSettings()
    reference: Reference | None = None

    @field_validator("solver", mode="before")
    @classmethod
    def _family_solver_defaults(cls, value):
        """Keys a file leaves out of ``solver`` take this family's defaults, not the generic ones."""
        return {"max_iterations": 100, "penalty": FAMILY_PENALTY, **value} if isinstance(value, dict) else value

    @model_validator(mode="after")
    def _consistent(self) -> QuaternionAttitudeProblem:
        b = self.boundary
        if self.objective == "energy" and b.tf_s is None and b.tf_min_time_factor is None and b.tf_from is None:
            raise spec_error("minimum energy needs a final time",
                             "give boundary.tf_s, boundary.tf_from or boundary.tf_min_time_factor",
                             key=("boundary",), value=None)
        if self.objective == "time":
            for key in ("tf_s", "tf_from", "tf_min_time_factor"):
                value = getattr(b, key)
                if value is not None:
                    raise spec_error("minimum time has a free final time", f"remove boundary.{key}",
                                     key=("boundary", key),
                                     value=value.model_dump() if isinstance(value, ResultLink) else value)
        check_outside_keep_out(self.keep_out, b.initial.q, b.final.q)
        rate_max = self.spacecraft.rate_max_degps
        for which in ("initial", "final"):
            rates = getattr(b, which).rate_degps
            if rate_max is not None and max(abs(r) for r in rates) > rate_max:
                raise spec_error(f"a component is above spacecraft.rate_max_degps = {rate_max:g}",
                                 "a boundary rate must lie within the rate box", key=("boundary", which, "rate_degps"),
                                 value=list(rates))
        if b.tf_s is not None:
            sc = self.spacecraft
            check_slew_time(b.tf_s, sc.inertia_matrix, sc.torque_max_vector, b.initial.q, b.initial.rate_radps,
                            b.final.q, b.final.rate_radps, key=("boundary", "tf_s"), value=b.tf_s)
        for i, keep_in in enumerate(self.keep_in):
            axis = np.array(keep_in.body_axis) / np.linalg.norm(keep_in.body_axis)
            d_in = np.array(keep_in.inertial_dir) / np.linalg.norm(keep_in.inertial_dir)
            for cone in self.keep_out:
                if not np.allclose(axis, cone.body_axis_unit):
                    continue
                sep = math.degrees(math.acos(np.clip(d_in @ cone.inertial_dir_unit, -1, 1)))
                if sep + keep_in.half_angle_deg <= cone.half_angle_deg:
                    raise spec_error(f"keep-in cone {keep_in.name!r} lies inside keep-out cone {cone.name!r}",
                                     "the two cones leave no admissible direction; fix one of them",
                                     key=("keep_in", i, "half_angle_deg"), value=keep_in.half_angle_deg)
        for i, f in enumerate(self.forbidden):
            for which in ("initial", "final"):
                q = getattr(b, which).q
                angle = math.degrees(float(quat_angle_between(q, f.quaternion)))
                if angle <= f.min_angle_deg:
                    raise spec_error(f"the {which} attitude is {angle:.3g} deg from forbidden attitude {f.name!r}",
                                     f"it must be more than {f.min_angle_deg:g} deg away",
                                     key=("forbidden", i, "min_angle_deg"), value=f.min_angle_deg)
        return self

    def input_links(self) -> tuple[InputLink, ...]:
        """``boundary.tf_from`` while unresolved: it gives ``boundary.tf_s``."""
        link = self.boundary.tf_from
        return () if link is None else (InputLink("boundary.tf_s", "boundary.tf_from", link),)


BYTES_PER_INTERVAL = 175_000
"""Peak memory per Hermite-Simpson interval of a solve (sparse program; measured 0.17 MB at 800 and 2000
intervals, the multi-cone case)."""


def estimate_size(spec: QuaternionAttitudeProblem) -> SizeEstimate:
    """Peak memory of a solve: :data:`BYTES_PER_INTERVAL` per interval, plus the process (linear in the grid)."""
    intervals = spec.discretization.intervals
    return SizeEstimate(PROCESS_BYTES + BYTES_PER_INTERVAL * intervals, "discretization.intervals", intervals,
                        f"{intervals} Hermite-Simpson intervals")
