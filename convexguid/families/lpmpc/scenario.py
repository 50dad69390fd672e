"""The flight scenario of an ``lpmpc`` problem: the verified nominal in MRPs, the plant, the laws, the runs.

:func:`~convexguid.families.lpmpc.solve.build_scenario` solves the nominal's problem file through the planner the
family's hook is given (so it is planned and dense-verified like every plan) and samples its dense trajectory on the
simulation grid.
:func:`fly_all` flies every law from one initial error; :func:`fly_monte_carlo_run` flies LPMPC and LQR
tracking from one seeded random initial error (a picklable top-level function for the process pool).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from convexguid.dynamics.mrp_attitude import shortest_mrp
from convexguid.errors import SpecError
from convexguid.families.lpmpc.lqr import LqrRegulator, LqrTracker
from convexguid.families.lpmpc.tracker import LpmpcSettings, LpmpcTracker
from convexguid.families.lpmpc.tracking import DisturbanceTorque, Flight, Nominal, Sensors, fly
from convexguid.rotations import (
    euler321_to_quat,
    mrp_to_quat,
    quat_angle_between,
    quat_to_euler321,
    quat_to_mrp,
)
from convexguid.solution import Solution


@dataclass(frozen=True)
class Scenario:
    """Everything a run needs, picklable: the nominal on the simulation grid, the plant, the laws' settings."""

    nominal: Nominal
    inertia: np.ndarray
    u_max: np.ndarray
    target: np.ndarray
    sensors: Sensors
    disturbance: DisturbanceTorque
    lpmpc: LpmpcSettings
    lqr_q: float
    lqr_r: tuple[float, ...]
    forbidden: tuple[tuple[str, np.ndarray, float], ...] = ()
    """The nominal problem's forbidden attitudes: (name, scalar-last quaternion, least angle in deg as its file
    states it, before any padding of ``nominal.set``)."""

    def initial_state(self, euler_error_deg: np.ndarray, rate_error_degps: np.ndarray) -> np.ndarray:
        """The nominal's initial state with an error in its 3-2-1 Euler angles and body rates."""
        x0 = self.nominal.x[0]
        rpy = quat_to_euler321(mrp_to_quat(x0[:3])) + np.radians(euler_error_deg)
        return np.concatenate([shortest_mrp(quat_to_mrp(euler321_to_quat(rpy))), x0[3:] + np.radians(rate_error_degps)])

    def laws(self, with_direct: bool = True) -> list:
        """LPMPC, then for each r: LQR tracking and (``with_direct``) LQR direct."""
        out: list = [LpmpcTracker(self.nominal, self.target, self.inertia, self.u_max, self.lpmpc)]
        for r in self.lqr_r:
            out.append(LqrTracker(f"lqr_tracking_r{r:g}", self.nominal, self.inertia, self.lqr_q, r))
            if with_direct:
                out.append(LqrRegulator(f"lqr_direct_r{r:g}", self.target, self.inertia, self.lqr_q, r))
        return out


def nominal_from_solution(solution: Solution, dt: float) -> Nominal:
    """The nominal's dense trajectory (quaternion, rates, torque columns) sampled every ``dt`` in MRPs."""
    cols = solution.dense.columns if solution.dense is not None else {}
    needed = [f"q{i}" for i in (1, 2, 3, 4)] + [f"omega{i}_degps" for i in (1, 2, 3)] + [f"u{i}_Nm" for i in (1, 2, 3)]
    missing = [c for c in needed if c not in cols]
    if missing:
        raise SpecError(f"nominal {solution.problem}: its dense trajectory lacks {', '.join(missing)}; the tracker "
                        "needs a planned attitude family with quaternion, rate and torque columns "
                        "(e.g. quaternion_attitude)")
    t_plan = solution.dense.t
    steps = max(1, int(round((t_plan[-1] - t_plan[0]) / dt)))
    t = np.linspace(t_plan[0], t_plan[-1], steps + 1)
    q = np.column_stack([np.interp(t, t_plan, cols[f"q{i}"]) for i in (1, 2, 3, 4)])
    omega = np.radians(np.column_stack([np.interp(t, t_plan, cols[f"omega{i}_degps"]) for i in (1, 2, 3)]))
    u = np.column_stack([np.interp(t, t_plan, cols[f"u{i}_Nm"]) for i in (1, 2, 3)])
    return Nominal(t, np.hstack([shortest_mrp(quat_to_mrp(q)), omega]), u)


def resolve_nominal_path(spec) -> Path:
    """The nominal's problem file, relative to the ``lpmpc`` file (or the working directory for a dict spec)."""
    path = Path(spec.nominal.problem)
    if not path.is_absolute() and spec.source != "<dict>":
        path = Path(spec.source).parent / path
    if not path.exists():
        raise SpecError(f"{spec.source}: nominal.problem: no such file (got {spec.nominal.problem!r}); give a "
                        "problem file path relative to this file")
    return path


def attitude_error_deg(x: np.ndarray, target: np.ndarray) -> float:
    """Euler-axis angle between the attitude of ``x`` and the target's, deg."""
    return float(np.degrees(quat_angle_between(mrp_to_quat(x[:3]), mrp_to_quat(target[:3]))))


def rate_error_degps(x: np.ndarray, target: np.ndarray) -> float:
    return float(np.degrees(np.linalg.norm(x[3:] - target[3:])))


def fly_all(scenario: Scenario, x0: np.ndarray, seed: int) -> list[tuple[Flight, object]]:
    """Every law from ``x0``, each with the same noise and disturbance draws (one generator per law, one seed)."""
    out = []
    for law in scenario.laws():
        flight = fly(law, x0, scenario.nominal.t, scenario.inertia, scenario.u_max, scenario.sensors,
                     scenario.disturbance, np.random.default_rng(seed))
        out.append((flight, law))
    return out


def fly_monte_carlo_run(scenario: Scenario, seed: np.random.SeedSequence, euler_std_deg: float,
                        rate_std_degps: float, stride: int) -> dict:
    """One Monte Carlo run: a random initial error, then LPMPC and LQR tracking (first r) with the same draws.

    Returns plain numbers and the histories every ``stride`` steps (for the envelopes).
    """
    rng = np.random.default_rng(seed)  # reads the seed's state, does not spawn from it: the same run every time
    euler_error = rng.normal(0.0, euler_std_deg, 3)
    rate_error = rng.normal(0.0, rate_std_degps, 3)
    flight_seed = int(rng.integers(2**63))
    x0 = scenario.initial_state(euler_error, rate_error)
    lpmpc, lqr = scenario.laws(with_direct=False)[:2]
    run = {"euler_error_deg": euler_error.tolist(), "rate_error_degps": rate_error.tolist()}
    for key, law in (("lpmpc", lpmpc), ("lqr", lqr)):
        flight = fly(law, x0, scenario.nominal.t, scenario.inertia, scenario.u_max, scenario.sensors,
                     scenario.disturbance, np.random.default_rng(flight_seed))
        run[key] = {"final_euler_deg": flight.final_euler_deg.tolist(),
                    "final_rate_degps": flight.final_rate_degps.tolist(),
                    "angle_error_deg": attitude_error_deg(flight.x[-1], scenario.target),
                    "rate_error_degps": rate_error_degps(flight.x[-1], scenario.target),
                    "energy_N2m2s": flight.energy, "run_time_s": flight.wall_time_s,
                    "euler_deg": np.degrees(quat_to_euler321(mrp_to_quat(flight.x[::stride, :3]))),
                    "rate_degps": np.degrees(flight.x[::stride, 3:])}
        if law is lpmpc:
            run[key]["corrections"] = law.corrections
            run[key]["leaves_box"] = int(sum(c.leaves_box for c in law.checks))
    return run
