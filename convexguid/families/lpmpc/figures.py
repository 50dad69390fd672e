"""Summary figures of an ``lpmpc`` simulation: the nominal, each run, the LPMPC updates, the Monte Carlo."""

from __future__ import annotations

from dataclasses import dataclass

from convexguid.solution import Figures, compute_time_figure, optional


@dataclass(frozen=True)
class ControllerRun:
    """One closed-loop run (a row of the paper's Table 2).

    ``final_*``: the 3-2-1 Euler angles (deg) and body rates (deg/s) at t_f; ``energy_N2m2s``: the integral of
    the squared applied torque; ``command_time_s``: the law's compute time over the run; ``corrections`` and
    ``checks``: LPMPC updates that fired / update checks made (None for the LQR laws).
    """

    controller: str
    final_euler_deg: tuple[float, float, float]
    final_rate_degps: tuple[float, float, float]
    final_angle_error_deg: float
    final_rate_error_degps: float
    energy_N2m2s: float
    command_time_s: float
    run_time_s: float
    corrections: int | None = None
    checks: int | None = None


@dataclass(frozen=True)
class Spread:
    """Mean and (population) standard deviation of one quantity over the Monte Carlo runs."""

    mean: float
    std: float


@dataclass(frozen=True)
class MonteCarloFigures:
    """The Monte Carlo of LPMPC against LQR tracking (the paper's Tables 3-4 and Figs. 5-8).

    Terminal values are per item (roll, pitch, yaw in deg; omega 1-3 in deg/s), as in Table 3. ``saving``
    is the per-run energy saving of LPMPC against LQR tracking, (E_lqr - E_lpmpc) / E_lqr.
    """

    runs: int
    workers: int
    wall_time_s: float
    runs_per_s: float
    lpmpc_terminal: tuple[Spread, ...]
    lqr_terminal: tuple[Spread, ...]
    lpmpc_angle_error_deg: Spread
    lqr_angle_error_deg: Spread
    lpmpc_energy_N2m2s: Spread
    lqr_energy_N2m2s: Spread
    saving: Spread
    saving_range: tuple[float, float]
    runs_lpmpc_saves_energy: int
    corrections_per_run: Spread
    corrections_range: tuple[int, int]
    lpmpc_run_time_s: Spread
    lqr_run_time_s: Spread
    closed_form_leaves_box_runs: int
    per_run: tuple[dict, ...]


@dataclass(frozen=True)
class LpmpcFigures(Figures):
    """Figures of an ``lpmpc`` simulation.

    Attributes
    ----------
    nominal_problem, nominal_status : str
        The nominal plan's problem name and status (``converged`` means dense-verified).
    nominal_energy_N2m2s : float or None
        The nominal's energy integral on its dense check.
    runs : list of ControllerRun
        The single case: LPMPC and every LQR law from the same initial error, noise and disturbance.
    lpmpc_energy_N2m2s, lpmpc_final_angle_error_deg, lpmpc_final_rate_error_degps : float or None
        The LPMPC row of ``runs``, repeated for the report's key figures.
    corrections, update_checks, closed_form_leaves_box : int or None
        LPMPC corrections fired, update checks made, and corrections whose closed form leaves the torque box.
    prediction_time_median_ms, correction_time_median_ms, integration_time_median_ms : float or None
        Per update: analytic prediction (eq. 42), correction (KKT or QP), method-2 integrations.
    update_time_ms : dict of str to float
        Median compute time of one update (:mod:`convexguid.families.lpmpc.timing`): ``lqr``, ``lpmpc_n<N>``
        for the file's ``timing_nodes``, and ``integration`` (method 2 over the whole horizon).
    monte_carlo : MonteCarloFigures or None
        Present when the problem file has a ``monte_carlo`` section.
    maneuver_time_s : float or None
        The nominal's (and so every flight's) duration, s.
    min_forbidden_angle_deg : float or None
        Smallest angle of the LPMPC flight to a forbidden attitude of the nominal's problem, deg (if it has any).
    """

    nominal_problem: str
    nominal_status: str
    nominal_energy_N2m2s: float | None = None
    runs: tuple[ControllerRun, ...] = ()
    lpmpc_energy_N2m2s: float | None = None
    lpmpc_final_angle_error_deg: float | None = None
    lpmpc_final_rate_error_degps: float | None = None
    corrections: int | None = None
    update_checks: int | None = None
    closed_form_leaves_box: int | None = None
    prediction_time_median_ms: float | None = compute_time_figure()
    correction_time_median_ms: float | None = compute_time_figure()
    integration_time_median_ms: float | None = compute_time_figure()
    update_time_ms: dict[str, float] | None = optional()
    monte_carlo: MonteCarloFigures | None = optional()
    maneuver_time_s: float | None = None
    min_forbidden_angle_deg: float | None = optional()
