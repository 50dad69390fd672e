"""Pointing geometry shared by the attitude families, the path-transfer planner, verification and plots.

:class:`PointingCone` is the one representation of a keep-out or keep-in pointing cone: a body
axis :math:`b` that must stay outside (keep-out) or inside (keep-in) the half-angle
:math:`\\theta` of an inertial direction :math:`r`, i.e. :math:`b^T C_{BI}(q) r \\le \\cos\\theta`
or :math:`\\ge \\cos\\theta`. Unit vectors, radians; quaternions scalar-last (Hamilton), body
relative to inertial. The eigenaxis helpers (shortest rotation between two attitudes and the
slew along it) live here too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from convexguid.checks import unit_vector
from convexguid.errors import SpecError
from convexguid.rotations import (
    axis_angle_to_quat,
    quat_conjugate,
    quat_multiply,
    quat_normalize,
    quat_to_dcm,
)

__all__ = ["PointingCone", "eigenaxis_path", "eigenaxis_rotation", "keep_out_angles_deg"]


def keep_out_angles_deg(q: np.ndarray, body_axis: np.ndarray, inertial_dir: np.ndarray) -> np.ndarray:
    """Angle between the body axis and the inertial direction, :math:`\\arccos(b^T C_{BI}(q) r)`, in degrees."""
    cosines = np.einsum("i,nij,j->n", body_axis, quat_to_dcm(q), inertial_dir)
    return np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0)))


@dataclass(frozen=True, eq=False)
class PointingCone:
    """Pointing cone between ``body_axis`` (body frame) and ``inertial_dir`` (inertial frame).

    Keep-out (``keep_out=True``): the angle between them must exceed ``half_angle_rad``; keep-in: stay
    below it. Both directions are normalised (and made read-only) here; the half-angle lies in (0, pi).
    """

    name: str
    body_axis: NDArray
    inertial_dir: NDArray
    half_angle_rad: float
    keep_out: bool = True

    def __post_init__(self) -> None:
        for attr in ("body_axis", "inertial_dir"):
            unit = unit_vector(f"cone {self.name!r} {attr}", getattr(self, attr), 3)
            unit.setflags(write=False)
            object.__setattr__(self, attr, unit)
        if not 0 < self.half_angle_rad < math.pi:
            raise SpecError(f"cone {self.name!r} half_angle_rad must lie in (0, pi), got {self.half_angle_rad!r}")

    @classmethod
    def from_spec(cls, cone, keep_out: bool = True) -> PointingCone:
        """From a spec model with ``name``, ``body_axis``, ``inertial_dir`` and ``half_angle_deg``."""
        return cls(cone.name, cone.body_axis, cone.inertial_dir, math.radians(cone.half_angle_deg), keep_out)

    @property
    def half_angle_deg(self) -> float:
        """Half-angle, deg."""
        return float(np.degrees(self.half_angle_rad))

    @property
    def kind(self) -> str:
        """``"keep_out"`` or ``"keep_in"`` (prefix of the cone's constraint and column names)."""
        return "keep_out" if self.keep_out else "keep_in"

    @property
    def column(self) -> str:
        """Name of the dense column / check with the body-axis-to-direction angle, deg."""
        return f"{self.kind}_{self.name}_deg"

    def cos_angle(self, dcm: np.ndarray) -> np.ndarray:
        """:math:`b^T C_{BI} r` for stacked direction cosine matrices ``(n, 3, 3)`` (complex-safe)."""
        return np.einsum("i,nij,j->n", self.body_axis, dcm, self.inertial_dir)

    def angles_deg(self, q: np.ndarray) -> np.ndarray:
        """Angle between body axis and inertial direction along quaternions ``q`` ``(n, 4)``, deg."""
        return keep_out_angles_deg(q, self.body_axis, self.inertial_dir)

    def margin_deg(self, q: np.ndarray) -> np.ndarray:
        """Clearance to the cone edge along ``q``, deg: positive when the constraint holds, negative inside a
        keep-out (outside a keep-in) cone."""
        angle = self.angles_deg(q)
        return angle - self.half_angle_deg if self.keep_out else self.half_angle_deg - angle

    def to_dict(self) -> dict:
        """Plain data for the summary JSON and the sky plots."""
        return {"name": self.name, "body_axis": self.body_axis.tolist(), "inertial_dir": self.inertial_dir.tolist(),
                "half_angle_deg": self.half_angle_deg, "keep_out": self.keep_out}


def eigenaxis_rotation(q0: ArrayLike, qf: ArrayLike) -> tuple[NDArray, float]:
    r"""Body-frame Euler axis and angle in :math:`[0, \pi]` of the shortest rotation from q0 to qf (R1).

    Quaternions scalar-last, body relative to inertial; :math:`q_f = q_0 \otimes [\sin(\Phi/2)e, \cos(\Phi/2)]`
    up to sign. For :math:`\Phi = 0` the axis is +z (any axis would do). Wang et al. eqs. (16)-(19).
    """
    qe = quat_multiply(quat_conjugate(quat_normalize(q0)), quat_normalize(qf))
    qe = -qe if qe[3] < 0 else qe
    s = float(np.linalg.norm(qe[:3]))
    axis = qe[:3] / s if s > 1e-15 else np.array([0.0, 0.0, 1.0])
    return axis, 2.0 * math.atan2(s, qe[3])


def eigenaxis_path(q0: ArrayLike, qf: ArrayLike, n: int) -> NDArray:
    r"""n attitudes equally spaced in angle along the eigenaxis slew q0 -> qf, shape ``(n, 4)`` (eqs. 20-21).

    Quaternions scalar-last, body relative to inertial; the sequence is sign-continuous, starts at q0 and
    ends at :math:`\pm q_f`. Usable as an SCP initial guess. Raises SpecError for a zero quaternion or n < 2.
    """
    if int(n) != n or n < 2:
        raise SpecError(f"eigenaxis_path: n must be an integer >= 2, got {n!r}")
    q0, qf = unit_vector("q0", q0, 4), unit_vector("qf", qf, 4)
    axis, angle = eigenaxis_rotation(q0, qf)
    return quat_multiply(q0, axis_angle_to_quat(axis, np.linspace(0.0, angle, int(n))))
