r"""Problem family ``potential_function``: closed-loop slew with forbidden-attitude avoidance (Guo, Li, Ma 2011).

A reaction-wheel spacecraft is steered from ``boundary.initial`` to the inertially fixed ``boundary.command`` by
the potential-function + backstepping controller of
:class:`~convexguid.families.potential_function.controller.PotentialFunctionController`, keeping its Euler-axis angle
:math:`\theta_b` to ``boundary.forbidden`` above ``gains.theta_m_deg``. The run is a simulation, not a plan:
:func:`convexguid.families.potential_function.runner.simulate_problem` integrates it.

Quaternions are scalar-last ``[x, y, z, w]``, Hamilton product, body relative to inertial (the convention of
:mod:`convexguid.rotations` and of the paper). **Non-unit input:** a quaternion whose norm is within
:data:`convexguid.spec.common.QUATERNION_NORM_TOL` of 1 is normalised (papers print 3-4 digits, e.g.
Table 1's ``[0, 0, 0.707, 0.707]``); any other norm is rejected, because it is a typo rather than rounding.

Gains are *fixed* (``g``, ``s``, ``mu`` given) or *adaptive* (``u_mu_Nm``, ``u_s_Nm``, ``u_g_Nm``, ``mu_min``,
``s_max``, ``g_max`` given; eqs. 26-30, then ``g``, ``s``, ``mu`` must be absent). ``w_max_degps`` needs adaptive
gains and ``theta_lm_deg`` (the local-minimum escape, eqs. 31-32) needs ``spacecraft.torque_max_Nm``.

References
----------
Guo Yanning, Li Chuanjiang, Ma Guangfu, "Spacecraft autonomous attitude maneuver control by potential function
method", Acta Aeronautica et Astronautica Sinica 32(3), 457-464, 2011 (Sec. 2-4, Table 1).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import BeforeValidator, Field, model_validator

from convexguid.errors import SpecError
from convexguid.families.potential_function.controller import PotentialFunctionGains
from convexguid.rotations import quat_angle_between
from convexguid.sizes import PROCESS_BYTES, SizeEstimate
from convexguid.spec.attitude import Spacecraft
from convexguid.spec.common import (
    PositiveFloat,
    ProblemBase,
    Reference,
    SpecModel,
    UnitQuaternion,
    Vector3,
    readonly,
    spec_error,
)

MAX_STEPS = 1_000_000
"""Largest accepted ``t_final_s / dt_s`` (a guard against a step size typed in the wrong unit)."""

ADAPTIVE_KEYS = ("u_mu_Nm", "u_s_Nm", "u_g_Nm", "mu_min", "s_max", "g_max")
"""Gain keys that together select the adaptive gains of eqs. 26-30."""

FIXED_KEYS = ("g", "s", "mu")
"""Gain keys of the fixed-gain controller (eq. 19)."""


AngleDeg = Annotated[float, Field(gt=0, lt=180)]
"""An angle in (0, 180) deg."""


def _angle_list(v: object) -> tuple[object, ...]:
    if not isinstance(v, (list, tuple)):
        raise spec_error("expected a list of angles", "give a YAML list of angles in (0, 180) deg", value=v)
    return tuple(v)


class QuaternionAttitude(SpecModel):
    """An attitude. ``quaternion_xyzw``: scalar-last quaternion of the body relative to inertial."""

    quaternion_xyzw: UnitQuaternion

    @property
    def quaternion(self) -> np.ndarray:
        """Unit quaternion ``[x, y, z, w]`` (read-only)."""
        return readonly(np.array(self.quaternion_xyzw))


class InitialState(QuaternionAttitude):
    """Initial attitude and body rate. ``rate_degps``: body angular rate in body axes, deg/s."""

    rate_degps: Vector3 = (0.0, 0.0, 0.0)

    @property
    def rate_radps(self) -> np.ndarray:
        """Body angular rate, rad/s (read-only)."""
        return readonly(np.radians(self.rate_degps))


class PotentialBoundary(SpecModel):
    """Initial state, inertially fixed command attitude and optional forbidden attitude (None: none, Fig. 5)."""

    initial: InitialState
    command: QuaternionAttitude
    forbidden: QuaternionAttitude | None = None


class ReactionWheelSpacecraft(Spacecraft):
    """Rigid spacecraft with reaction wheels.

    Attributes
    ----------
    inertia_kgm2 : tuple of tuple of float
        Inertia matrix, kg m^2 (3 principal moments or a 3x3 matrix in YAML).
    torque_max_Nm : float or None
        Per-axis wheel torque limit :math:`u_{max}`, N m; the commanded torque is clipped to it. None (the
        default): no limit.
    """

    torque_max_Nm: PositiveFloat | None = None  # type: ignore[assignment]


class PotentialGains(SpecModel):
    """Controller gains of Guo et al. (2011); angles in deg, torques in N m.

    Attributes
    ----------
    g, s, mu : float or None
        Fixed gains of eq. 19 (required for fixed gains, absent for adaptive gains).
    eta : float
        Scale of the repulsive potential, eq. 12.
    theta_m_deg : float
        Smallest allowed Euler angle to the forbidden attitude, in (0, 180).
    theta_0_deg : float
        Influence angle of the forbidden attitude (existence condition 3), ``theta_m_deg < theta_0_deg <= 180``.
    u_mu_Nm, u_s_Nm, u_g_Nm, mu_min, s_max, g_max : float or None
        Torque budgets and gain bounds of the adaptive gains, eqs. 24-28 (all or none).
    w_max_degps : float or None
        Rate limit of eq. 30, deg/s (adaptive gains only).
    theta_lm_deg : float or None
        Axis-alignment angle of the local-minimum escape, eq. 31 (needs ``spacecraft.torque_max_Nm``).
    """

    g: PositiveFloat | None = None
    s: PositiveFloat | None = None
    mu: PositiveFloat | None = None
    eta: PositiveFloat
    theta_m_deg: AngleDeg
    theta_0_deg: Annotated[float, Field(gt=0, le=180)]
    u_mu_Nm: PositiveFloat | None = None
    u_s_Nm: PositiveFloat | None = None
    u_g_Nm: PositiveFloat | None = None
    mu_min: PositiveFloat | None = None
    s_max: PositiveFloat | None = None
    g_max: PositiveFloat | None = None
    w_max_degps: PositiveFloat | None = None
    theta_lm_deg: AngleDeg | None = None

    @model_validator(mode="after")
    def _consistent(self) -> PotentialGains:
        if self.theta_0_deg <= self.theta_m_deg:
            raise spec_error(f"must be greater than {{here}}theta_m_deg = {self.theta_m_deg!r}",
                             "give an influence angle larger than the forbidden-zone angle (the paper uses "
                             "1.2 theta_m)", key=("theta_0_deg",), value=self.theta_0_deg)
        given = [k for k in ADAPTIVE_KEYS if getattr(self, k) is not None]
        if given and len(given) < len(ADAPTIVE_KEYS):
            missing = [k for k in ADAPTIVE_KEYS if getattr(self, k) is None]
            raise spec_error("missing for the adaptive gains", f"give all of {', '.join(ADAPTIVE_KEYS)} "
                             "(adaptive gains, eqs. 26-30) or none of them (fixed gains)", key=(missing[0],),
                             value=None)
        unwanted = [k for k in FIXED_KEYS if getattr(self, k) is not None] if self.adaptive else []
        if unwanted:
            raise spec_error("is a fixed gain, but the adaptive gains are given (u_mu_Nm, ...)",
                             "remove g, s and mu: eqs. 26-30 compute them", key=(unwanted[0],),
                             value=getattr(self, unwanted[0]))
        missing_fixed = [k for k in FIXED_KEYS if getattr(self, k) is None] if not self.adaptive else []
        if missing_fixed:
            raise spec_error("missing for the fixed gains", f"give g, s and mu, or the adaptive gains "
                             f"{', '.join(ADAPTIVE_KEYS)}", key=(missing_fixed[0],), value=None)
        if self.w_max_degps is not None and not self.adaptive:
            raise spec_error("the rate limit is only used by the adaptive gains (eq. 30)",
                             f"remove it or give the adaptive gains {', '.join(ADAPTIVE_KEYS)}",
                             key=("w_max_degps",), value=self.w_max_degps)
        return self

    @property
    def adaptive(self) -> bool:
        """True when the adaptive gains of eqs. 26-30 are given."""
        return self.u_mu_Nm is not None


class SimulationSettings(SpecModel):
    """Fixed-step RK4 closed-loop simulation (zero-order-held torque, see
    :mod:`convexguid.families.potential_function.plant`).

    Attributes
    ----------
    t_final_s : float
        Simulated time, s.
    dt_s : float
        Integration step and control period, s (``dt_s <= t_final_s``).
    disturbance : str
        ``guo2011`` (the paper's Sec. 4 torque) or ``none``.
    """

    t_final_s: PositiveFloat
    dt_s: PositiveFloat
    disturbance: Literal["guo2011", "none"] = "guo2011"

    @model_validator(mode="after")
    def _steps(self) -> SimulationSettings:
        if self.dt_s > self.t_final_s:
            raise spec_error(f"must not exceed {{here}}t_final_s = {self.t_final_s!r}", "give a smaller step",
                             key=("dt_s",), value=self.dt_s)
        steps = round(self.t_final_s / self.dt_s)
        if steps > MAX_STEPS:
            raise spec_error(f"gives {steps} steps over {{here}}t_final_s = {self.t_final_s!r}",
                             f"give a step leading to at most {MAX_STEPS} steps", key=("dt_s",), value=self.dt_s)
        return self


class ThetaMSweep(SpecModel):
    """Family of runs over the forbidden-zone angle (Fig. 4).

    Attributes
    ----------
    theta_m_deg : tuple of float
        Forbidden-zone angles, deg, distinct, each in (0, 180).
    theta_0_ratio : float
        ``theta_0 = theta_0_ratio * theta_m`` for every case (> 1; the paper uses 1.2).
    """

    theta_m_deg: Annotated[tuple[AngleDeg, ...], BeforeValidator(_angle_list), Field(min_length=1)]
    theta_0_ratio: Annotated[float, Field(gt=1)] = 1.2

    @model_validator(mode="after")
    def _valid(self) -> ThetaMSweep:
        for i, theta_m in enumerate(self.theta_m_deg):
            if theta_m in self.theta_m_deg[:i]:
                raise spec_error("duplicate angle", "give distinct angles", key=("theta_m_deg", i), value=theta_m)
            if self.theta_0_ratio * theta_m > 180:
                raise spec_error(f"gives theta_0 = {{here}}theta_0_ratio * theta_m = "
                                 f"{self.theta_0_ratio * theta_m:g} deg > 180 deg",
                                 "give a smaller angle or ratio", key=("theta_m_deg", i), value=theta_m)
        return self

    def cases(self) -> list[tuple[float, float]]:
        """``(theta_m_deg, theta_0_deg)`` of every case."""
        return [(theta_m, self.theta_0_ratio * theta_m) for theta_m in self.theta_m_deg]


class PotentialFunctionProblem(ProblemBase):
    """A ``potential_function`` problem file (see ``problems/guo2011_*.yaml``).

    Cross-section checks: the command and the initial attitude lie outside the forbidden zone (Euler angle to
    the forbidden attitude greater than ``theta_m`` for the base gains and every sweep case),
    ``gains.theta_lm_deg`` needs ``spacecraft.torque_max_Nm``, and a sweep needs a forbidden attitude.
    """

    family: Literal["potential_function"]
    method: Literal["potential_function"] = "potential_function"  # type: ignore[assignment]
    spacecraft: ReactionWheelSpacecraft
    boundary: PotentialBoundary
    gains: PotentialGains
    simulation: SimulationSettings
    sweep: ThetaMSweep | None = None
    reference: Reference | None = None

    @model_validator(mode="after")
    def _consistent(self) -> PotentialFunctionProblem:
        if self.gains.theta_lm_deg is not None and self.spacecraft.torque_max_Nm is None:
            raise spec_error("the local-minimum escape torque (eq. 32) has magnitude spacecraft.torque_max_Nm, "
                             "which is null", "give spacecraft.torque_max_Nm or remove gains.theta_lm_deg",
                             key=("gains", "theta_lm_deg"), value=self.gains.theta_lm_deg)
        if self.sweep is not None and self.boundary.forbidden is None:
            raise spec_error("a theta_m sweep needs a forbidden attitude", "give boundary.forbidden or remove "
                             "sweep", key=("sweep",), value=None)
        if self.boundary.forbidden is not None:
            cases = [(("gains", "theta_m_deg"), self.gains.theta_m_deg)]
            if self.sweep is not None:
                cases += [(("sweep", "theta_m_deg", i), v) for i, v in enumerate(self.sweep.theta_m_deg)]
            forbidden = self.boundary.forbidden.quaternion
            for name in ("command", "initial"):
                attitude = getattr(self.boundary, name)
                angle = math.degrees(float(quat_angle_between(attitude.quaternion, forbidden)))
                for key, theta_m in cases:
                    if angle <= theta_m:
                        raise spec_error(
                            f"lies inside the forbidden zone: {angle:.6g} deg from boundary.forbidden, not more "
                            f"than {'.'.join(map(str, key))} = {theta_m:g} deg",
                            f"give a {name} attitude farther than theta_m from the forbidden one, or a smaller "
                            "theta_m", key=("boundary", name, "quaternion_xyzw"), value=list(attitude.quaternion_xyzw))
        for theta_m, theta_0 in self.cases():  # backstop: the controller accepts every case
            try:
                self.controller_gains(theta_m, theta_0)
            except SpecError as exc:
                raise spec_error(f"rejected by the controller: {exc}", "check the gains section",
                                 key=("gains",), value=None) from None
        return self

    def cases(self) -> list[tuple[float, float]]:
        """``(theta_m_deg, theta_0_deg)`` of the base run (``gains``) followed by the sweep cases, if any."""
        base = [(self.gains.theta_m_deg, self.gains.theta_0_deg)]
        return base + (self.sweep.cases() if self.sweep is not None else [])

    def controller_gains(self, theta_m_deg: float | None = None,
                         theta_0_deg: float | None = None) -> PotentialFunctionGains:
        """The controller's gains in SI units, with ``theta_m`` / ``theta_0`` replaced for a sweep case.

        In adaptive mode the unused fixed gains are set to the bounds ``g_max``, ``s_max``, ``mu_min``.
        """
        gains = self.gains
        theta_m = gains.theta_m_deg if theta_m_deg is None else theta_m_deg
        theta_0 = gains.theta_0_deg if theta_0_deg is None else theta_0_deg
        adaptive = {"u_mu": gains.u_mu_Nm, "u_s": gains.u_s_Nm, "u_g": gains.u_g_Nm, "mu_min": gains.mu_min,
                    "s_max": gains.s_max, "g_max": gains.g_max}
        return PotentialFunctionGains(
            g=gains.g_max if gains.adaptive else gains.g, s=gains.s_max if gains.adaptive else gains.s,
            mu=gains.mu_min if gains.adaptive else gains.mu, eta=gains.eta, theta_m=math.radians(theta_m),
            theta_0=math.radians(theta_0), **adaptive,
            w_max=None if gains.w_max_degps is None else math.radians(gains.w_max_degps),
            theta_lm=None if gains.theta_lm_deg is None else math.radians(gains.theta_lm_deg),
            u_max=self.spacecraft.torque_max_Nm)


BYTES_PER_STEP = 1_100
"""Memory kept per simulated step of one run (state, torque and the controller's record of the step; measured
1.06 kB at 10^4 and 10^5 steps). Every case of a sweep is kept until the figures are drawn."""


def estimate_size(spec: PotentialFunctionProblem) -> SizeEstimate:
    """Peak memory of a simulation: :data:`BYTES_PER_STEP` per step of every case (base run and sweep)."""
    steps, cases = round(spec.simulation.t_final_s / spec.simulation.dt_s) + 1, len(spec.cases())
    return SizeEstimate(PROCESS_BYTES + BYTES_PER_STEP * steps * cases, "simulation.dt_s", spec.simulation.dt_s,
                        f"{steps} steps x {cases} case{'s' if cases > 1 else ''}",
                        "give a larger simulation.dt_s, a shorter simulation.t_final_s or fewer sweep cases")
