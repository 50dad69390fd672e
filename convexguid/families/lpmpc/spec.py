"""Problem family ``lpmpc``: a planned attitude nominal flown closed loop by LPMPC and by the LQR baselines.

The nominal is another problem file (any planned attitude family whose dense trajectory carries the
quaternion, the body rates and the torque: ``quaternion_attitude``), solved and dense-verified first; its
spacecraft, torque box, final time and target come from it. Noise and disturbance readings: every
``*_std_*`` key is a standard deviation; the Monte Carlo initial errors are given as variances
(``*_var_*``, deg^2 and (deg/s)^2), this project's reading of the paper's ``N(0, 10)`` and ``N(0, 5)``
(docs/parameters.md).

References
----------
Feng Y., Chen W., Yang L., "Fuel-optimal attitude maneuver using linear pseudo-spectral model predictive
control method", J. Beijing Univ. Aeronautics and Astronautics 44(10), 2018, Sec. 3 (Tables 1-4).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from convexguid.spec.common import (
    InputLink,
    NonEmptyStr,
    NonNegativeFloat,
    PositiveFloat,
    ProblemBase,
    Reference,
    ResultLink,
    SpecModel,
    Vector3,
    spec_error,
)


class NominalSource(SpecModel):
    """``problem``: the nominal's problem file (relative to this file); ``set``: overrides applied to it.

    ``tf_from``: the nominal's final time is a figure of another case's result (``{problem, figure}``, resolved
    by the commands into ``tf_s``, :mod:`convexguid.validation.links`, which then replaces the nominal's own
    ``boundary.tf_s`` or ``boundary.tf_from``)."""

    problem: NonEmptyStr
    set: list[str] = Field(default_factory=list)
    tf_s: PositiveFloat | None = None
    tf_from: ResultLink | None = None


class TrackingSimulation(SpecModel):
    """Fixed-step RK4 with the command and the disturbance held over each step; ``seed`` fixes every draw."""

    dt_s: PositiveFloat = 0.01
    seed: Annotated[int, Field(ge=0)] = 2018


class Disturbance(SpecModel):
    """``gaussian``: a torque per axis drawn every step with standard deviation ``torque_std_Nm`` (0: none);
    ``guo2011``: Guo, Li, Ma's deterministic Sec. 4 torque (``torque_std_Nm`` unused)."""

    model: Literal["gaussian", "guo2011"] = "gaussian"
    torque_std_Nm: NonNegativeFloat = 0.05


class Sensors(SpecModel):
    """Gaussian noise on the 3-2-1 Euler angles and the body rates (standard deviations)."""

    euler_std_deg: NonNegativeFloat = 0.05
    rate_std_degps: NonNegativeFloat = 0.01


class InitialError(SpecModel):
    """Error of the true initial state from the nominal's: 3-2-1 Euler angles and body rates."""

    euler_deg: Vector3 = (0.0, 0.0, 0.0)
    rate_degps: Vector3 = (0.0, 0.0, 0.0)


class LpmpcSettingsSpec(SpecModel):
    """The LPMPC law: ``nodes`` LGR points, the update-check interval, thresholds on the predicted terminal
    deviation (MRP, dimensionless; rate, deg/s), and the correction (``closed_form``: eqs. 45-56;
    ``box_qp``: the same energy objective with the torque box at the nodes, solved by ``backend``;
    ``least_change``: the smallest correction, for a nominal whose path constraints are active)."""

    nodes: Annotated[int, Field(ge=3, le=40)] = 8
    check_interval_s: PositiveFloat = 2.0
    threshold_mrp: PositiveFloat = 0.01
    threshold_rate_degps: PositiveFloat = 0.005
    correction: Literal["closed_form", "box_qp", "least_change"] = "closed_form"
    backend: str = "clarabel"


class LqrSettingsSpec(SpecModel):
    """Weights :math:`Q = q I_6`, :math:`R = r I_3` of the LQR baselines, one tracking and one direct law per r."""

    q: PositiveFloat = 100.0
    r: list[PositiveFloat] = Field(default_factory=lambda: [0.01, 0.1])


class MonteCarlo(SpecModel):
    """``runs`` seeded runs of LPMPC against LQR tracking with the first ``lqr.r``; initial errors drawn from
    :math:`N(0, \\sigma^2)` with the variances given; ``workers`` processes (0: every core)."""

    runs: Annotated[int, Field(ge=1)]
    euler_var_deg2: NonNegativeFloat = 10.0
    rate_var_degps2: NonNegativeFloat = 5.0
    workers: Annotated[int, Field(ge=0)] = 0


class ClosedLoopChecks(SpecModel):
    """What the LPMPC run must meet to pass: final attitude error (deg) and final rate error (deg/s)."""

    final_angle_deg: PositiveFloat = 1.0
    final_rate_degps: PositiveFloat = 0.2


class PaperRow(SpecModel):
    """One law's row of the paper's Table 2 (final 3-2-1 Euler angles, rates, energy); ``controller`` names
    the matching law here (``lpmpc``, ``lqr_tracking_r<r>``, ``lqr_direct_r<r>``)."""

    controller: NonEmptyStr
    final_euler_deg: Vector3
    final_rate_degps: Vector3
    energy_N2m2s: PositiveFloat


class PaperSpread(SpecModel):
    """A mean and standard deviation as printed in the paper's Table 3."""

    mean: float
    std: NonNegativeFloat


class PaperTables(SpecModel):
    """The paper's published figures for this case, rendered beside ours (its scenario differs: compare
    ratios and orders of magnitude). ``table3_*``: six items (roll, pitch, yaw deg; omega 1-3 deg/s);
    ``table4_command_ms`` / ``table4_run_s``: by law (``lqr``, ``lpmpc_n8``, ...)."""

    table2: list[PaperRow] = Field(default_factory=list)
    table3_lpmpc: Annotated[list[PaperSpread], Field(min_length=6, max_length=6)] | None = None
    table3_lqr: Annotated[list[PaperSpread], Field(min_length=6, max_length=6)] | None = None
    table4_command_ms: dict[str, PositiveFloat] = Field(default_factory=dict)
    table4_run_s: dict[str, PositiveFloat] = Field(default_factory=dict)
    energy_saving: float | None = None


class LpmpcProblem(ProblemBase):
    """An ``lpmpc`` problem file (see ``problems/feng2018_lpmpc_*.yaml``)."""

    family: Literal["lpmpc"]
    method: Literal["simulate"] = "simulate"  # type: ignore[assignment]
    nominal: NominalSource
    simulation: TrackingSimulation = Field(default_factory=TrackingSimulation)
    disturbance: Disturbance = Field(default_factory=Disturbance)
    sensors: Sensors = Field(default_factory=Sensors)
    initial_error: InitialError = Field(default_factory=InitialError)
    lpmpc: LpmpcSettingsSpec = Field(default_factory=LpmpcSettingsSpec)
    lqr: LqrSettingsSpec = Field(default_factory=LqrSettingsSpec)
    monte_carlo: MonteCarlo | None = None
    checks: ClosedLoopChecks = Field(default_factory=ClosedLoopChecks)
    timing_nodes: list[Annotated[int, Field(ge=3, le=40)]] = Field(default_factory=list)
    """LGR point counts whose update time (prediction + correction) is measured on the single case."""
    paper: PaperTables | None = None
    reference: Reference | None = None

    @model_validator(mode="after")
    def _consistent(self) -> LpmpcProblem:
        if self.monte_carlo is not None and not self.lqr.r:
            raise spec_error("is empty, but the Monte Carlo flies LQR tracking with its first weight",
                             "give at least one r, e.g. [0.01]", key=("lqr", "r"), value=[])
        if self.nominal.tf_s is not None and self.nominal.tf_from is not None:
            raise spec_error("{here}nominal.tf_s and {here}nominal.tf_from are both set", "give one of them",
                             key=("nominal", "tf_from"), value=self.nominal.tf_from.model_dump())
        return self

    def input_links(self) -> tuple[InputLink, ...]:
        """``nominal.tf_from`` while unresolved: it gives ``nominal.tf_s``."""
        link = self.nominal.tf_from
        return () if link is None else (InputLink("nominal.tf_s", "nominal.tf_from", link),)
