"""What the attitude families' problem files share: the spacecraft (inertia, torque box), keep-out cones, and the
checks that read several sections at once (boundary attitudes outside the keep-out cones, a final time the torque
can meet).

The checks are called from each family's problem-model validator; they raise
:func:`~convexguid.spec.common.spec_error`, keyed below the problem's top level.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated

import numpy as np
from pydantic import Field

from convexguid.dynamics.rigid_body import min_slew_time
from convexguid.geometry import PointingCone
from convexguid.rotations import quat_angle_between
from convexguid.spec.common import (
    Direction3,
    InertiaMatrix,
    NonEmptyStr,
    PositiveFloat,
    SpecModel,
    named_list,
    readonly,
    spec_error,
)


class Spacecraft(SpecModel):
    """Rigid-body spacecraft with a symmetric torque bound on each body axis.

    Attributes
    ----------
    inertia_kgm2 : tuple of tuple of float
        Inertia matrix about the centre of mass in body axes, kg m^2 (3x3, symmetric positive definite).
    torque_max_Nm : float
        Bound on each body-axis control torque, N m.
    """

    inertia_kgm2: InertiaMatrix
    torque_max_Nm: PositiveFloat

    @property
    def inertia_matrix(self) -> np.ndarray:
        """Inertia matrix, kg m^2 (3x3, read-only)."""
        return readonly(np.array(self.inertia_kgm2))


class KeepOutSpec(SpecModel):
    """Keep-out cone: the body axis must stay more than ``half_angle_deg`` away from an inertial direction.

    Attributes
    ----------
    name : str
        Unique name of the cone (used in constraint names, e.g. ``keep_out_sun_deg``).
    body_axis : tuple of float
        Sensitive body axis (body frame), any nonzero length.
    inertial_dir : tuple of float
        Direction to avoid (inertial frame), any nonzero length.
    half_angle_deg : float
        Cone half-angle, deg, in (0, 180).
    """

    name: NonEmptyStr
    body_axis: Direction3
    inertial_dir: Direction3
    half_angle_deg: Annotated[float, Field(gt=0, lt=180)]

    @property
    def body_axis_unit(self) -> np.ndarray:
        """Unit body axis (read-only)."""
        axis = np.array(self.body_axis)
        return readonly(axis / np.linalg.norm(axis))

    @property
    def inertial_dir_unit(self) -> np.ndarray:
        """Unit inertial direction (read-only)."""
        direction = np.array(self.inertial_dir)
        return readonly(direction / np.linalg.norm(direction))

    @property
    def half_angle_rad(self) -> float:
        """Cone half-angle, rad."""
        return math.radians(self.half_angle_deg)

    def pointing_cone(self) -> PointingCone:
        """This cone as a keep-out :class:`~convexguid.geometry.PointingCone` (unit vectors, rad)."""
        return PointingCone.from_spec(self, keep_out=True)


KeepOutList = named_list(KeepOutSpec)
"""A YAML list of :class:`KeepOutSpec` with unique names, stored as a tuple."""


def check_outside_keep_out(keep_out: Sequence[KeepOutSpec], q0: np.ndarray, qf: np.ndarray) -> None:
    """Refuse an initial (``q0``) or final (``qf``) attitude, scalar-last quaternions, that points a cone's body
    axis inside it: no path can start or end there (error at ``keep_out.<i>.half_angle_deg``)."""
    for i, cone in enumerate(keep_out):
        for which, q in (("initial", q0), ("final", qf)):
            angle = float(cone.pointing_cone().angles_deg(np.asarray(q)[None])[0])
            if angle <= cone.half_angle_deg:
                raise spec_error(f"the {which} attitude points {cone.name!r}'s body axis {angle:.3g} deg from "
                                 f"its direction, inside the {cone.half_angle_deg:g} deg cone",
                                 "move the boundary attitude or shrink the cone",
                                 key=("keep_out", i, "half_angle_deg"), value=cone.half_angle_deg)


def check_slew_time(duration_s: float, inertia: np.ndarray, torque_box: np.ndarray, q0: np.ndarray,
                    w0: np.ndarray, qf: np.ndarray, wf: np.ndarray, key: tuple[str, ...], value: float) -> None:
    """Refuse a maneuver time shorter than any slew from ``(q0, w0)`` to ``(qf, wf)`` can take with torques in the
    per-axis box ``torque_box`` (N m; rates rad/s): :func:`~convexguid.dynamics.rigid_body.min_slew_time`, a bound
    that holds for every path. The error is at ``key`` (the final time's key path, whose ``value`` it shows) and states
    the bound."""
    angle = float(quat_angle_between(q0, qf))
    torque = float(np.linalg.norm(torque_box))
    shortest = min_slew_time(inertia, torque, angle, float(np.linalg.norm(inertia @ w0)),
                             float(np.linalg.norm(inertia @ wf)))
    if duration_s < shortest:
        smallest = float(np.linalg.eigvalsh(inertia)[0])
        raise spec_error(f"a {duration_s:.3g} s maneuver is too short: the {math.degrees(angle):.4g} deg rotation "
                         f"takes at least {shortest:.4g} s with torques within the box (|u| <= {torque:.4g} N m) "
                         f"and the smallest principal inertia {smallest:.4g} kg m^2",
                         f"give a maneuver time of at least {shortest:.4g} s", key=key, value=value)
