"""Summary figures of a ``potential_function`` simulation (:mod:`convexguid.families.potential_function.runner`)."""

from __future__ import annotations

from dataclasses import dataclass

from convexguid.solution import Figures, optional


@dataclass(frozen=True)
class RunFigures(Figures):
    """Figures of one simulated run (None where a time or angle does not exist, e.g. the band is never reached).

    Angles in deg, times in s, torques in N m, momentum in N m s, the energy integral in N^2 m^2 s.
    """

    theta_m_deg: float
    theta_0_deg: float
    maneuver_time_1deg_s: float | None
    maneuver_time_01deg_s: float | None
    min_theta_b_deg: float | None
    t_min_theta_b_s: float | None
    max_abs_torque_Nm: float
    max_abs_torque_unclipped_Nm: float
    max_rate_degps: float
    max_wheel_momentum_Nms: float
    energy_N2m2s: float
    final_error_deg: float
    final_rate_degps: float
    escape_time_s: float
    repulsion_time_s: float


@dataclass(frozen=True)
class SweepCaseFigures(RunFigures):
    """One case of a sweep: its run's figures, whether it reached the command and passed its checks."""

    reached: bool
    passed: bool


@dataclass(frozen=True)
class PotentialFunctionFigures(RunFigures):
    """Figures of the base run, and one :class:`SweepCaseFigures` per case with a ``sweep`` section."""

    sweep: tuple[SweepCaseFigures, ...] | None = optional()
