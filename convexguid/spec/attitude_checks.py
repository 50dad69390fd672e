"""Checks that attitude problem files share: boundary attitudes outside the keep-out cones, a final time the torque
can meet.

Both read several sections at once (boundary, spacecraft, cones), so the families call them from their problem
model's validator; they raise :func:`~convexguid.spec.common.spec_error`, keyed below the problem's top level.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from convexguid.dynamics.rigid_body import min_slew_time
from convexguid.rotations import quat_angle_between
from convexguid.spec.common import KeepOutSpec, spec_error


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
