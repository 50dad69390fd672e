"""Problem family ``flat_attitude``: rest-to-rest attitude slew with differential flatness.

The attitude is parametrised by 3-2-1 (yaw-pitch-roll, Z-Y-X) Euler angles, the flat
outputs of the rigid body; the torque follows from the flat map, which is singular at
pitch = +-90 deg. The trajectory is discretised on mapped Chebyshev-Gauss-Lobatto nodes.

References
----------
Cai, Zhu, Zeng (2018), J. Dynamics and Control, DOI 10.6052/1672-6553-2018-005.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from convexguid.rotations import euler321_to_quat
from convexguid.sizes import PROCESS_BYTES, SizeEstimate
from convexguid.spec.attitude import KeepOutList, Spacecraft, check_outside_keep_out, check_slew_time
from convexguid.spec.common import (
    ProblemBase,
    Reference,
    SolverSettings,
    SpecModel,
    TimeInterval,
    Vector3,
    VerificationSettings,
    readonly,
    spec_error,
)

PITCH_LIMIT_DEG = 89.9
"""Largest accepted absolute pitch of a boundary attitude, deg."""


class Attitude321(SpecModel):
    """Attitude and body rates at a boundary.

    Attributes
    ----------
    roll_pitch_yaw_deg : tuple of float
        3-2-1 Euler angles (roll, pitch, yaw) of the body relative to the inertial frame, deg;
        ``|pitch| < 89.9``.
    rate_degps : tuple of float
        Body angular rate in body axes, deg/s.
    """

    roll_pitch_yaw_deg: Vector3
    rate_degps: Vector3 = (0.0, 0.0, 0.0)

    @field_validator("roll_pitch_yaw_deg")
    @classmethod
    def _pitch_not_singular(cls, rpy: tuple[float, float, float]) -> tuple[float, float, float]:
        if abs(rpy[1]) >= PITCH_LIMIT_DEG:
            raise spec_error("the 3-2-1 flat map is singular at pitch = +-90 deg",
                             f"give |pitch| < {PITCH_LIMIT_DEG} deg", key=(1,), value=rpy[1])
        return rpy

    @property
    def rpy_rad(self) -> np.ndarray:
        """Roll, pitch, yaw, rad (read-only)."""
        return readonly(np.radians(self.roll_pitch_yaw_deg))

    @property
    def rate_radps(self) -> np.ndarray:
        """Body angular rate, rad/s (read-only)."""
        return readonly(np.radians(self.rate_degps))


class AttitudeBoundary(TimeInterval):
    """Time interval and boundary attitudes.

    Attributes
    ----------
    t0_s, tf_s : float
        Initial and final time, s (``tf_s > t0_s``).
    initial, final : Attitude321
        Boundary attitudes and rates.
    """

    initial: Attitude321
    final: Attitude321


class ChebyshevDiscretization(SpecModel):
    """Mapped Chebyshev pseudospectral discretisation.

    Attributes
    ----------
    method : str
        ``mapped_chebyshev``.
    nodes : int
        Polynomial degree N (N + 1 Chebyshev-Gauss-Lobatto nodes), at least 4.
    map_epsilon : float
        Parameter of the node map, in (0, 1).
    check_points_per_interval : int
        Extra points per node interval where path constraints are also imposed.
    """

    method: Literal["mapped_chebyshev"] = "mapped_chebyshev"
    nodes: Annotated[int, Field(ge=4)]
    map_epsilon: Annotated[float, Field(gt=0, lt=1)] = 1e-6
    check_points_per_interval: Annotated[int, Field(ge=0)] = 2


class FlatAttitudeProblem(ProblemBase):
    """A ``flat_attitude`` problem file (see ``problems/cai2018_flat_attitude.yaml``)."""

    family: Literal["flat_attitude"]
    spacecraft: Spacecraft
    boundary: AttitudeBoundary
    keep_out: KeepOutList = ()
    objective: Literal["energy"] = "energy"
    discretization: ChebyshevDiscretization
    solver: SolverSettings = SolverSettings()
    verification: VerificationSettings = VerificationSettings()
    reference: Reference | None = None

    @model_validator(mode="after")
    def _feasible_boundary(self) -> FlatAttitudeProblem:
        """Boundary attitudes outside the keep-out cones, and a maneuver time the torque box can meet."""
        b = self.boundary
        q0, qf = euler321_to_quat(b.initial.rpy_rad), euler321_to_quat(b.final.rpy_rad)
        check_outside_keep_out(self.keep_out, q0, qf)
        check_slew_time(b.duration_s, self.spacecraft.inertia_matrix, np.full(3, self.spacecraft.torque_max_Nm), q0,
                        b.initial.rate_radps, qf, b.final.rate_radps, key=("boundary", "tf_s"), value=b.tf_s)
        return self


BYTES_PER_PATH_ENTRY = 85
"""Peak memory per entry of the dense path-constraint Jacobian (rows: 6 torque-box rows and one row per cone at
every node and check point; columns: the 3(N + 1) angles), in its copies, the subproblem and the solver's
factorisation. Measured at N = 192 to 600 with 0, 2 and 5 check points per interval (80 to 85 bytes); the paper's
case needs about 1.9 GiB at N = 600, 5 GiB at N = 1000 and 45 GiB at N = 3000."""


def estimate_size(spec: FlatAttitudeProblem) -> SizeEstimate:
    """Peak memory of a solve: :data:`BYTES_PER_PATH_ENTRY` per path-constraint Jacobian entry, plus the process."""
    d = spec.discretization
    variables = 3 * (d.nodes + 1)
    rows = (d.nodes + 1 + d.check_points_per_interval * d.nodes) * (6 + len(spec.keep_out))
    return SizeEstimate(PROCESS_BYTES + BYTES_PER_PATH_ENTRY * rows * variables, "discretization.nodes", d.nodes,
                        f"{variables} variables x {rows} path-constraint rows")
