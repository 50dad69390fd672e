"""Closed-loop flight of an attitude plan in MRPs: nominal trajectories, the plant, noise and disturbances.

The plant is the nonlinear rigid body of :mod:`convexguid.dynamics.mrp_attitude`, integrated by fixed-step
RK4 with the commanded torque (clipped to the actuator box) plus a disturbance torque held over each
step. A controller sees the state through the sensors: 3-2-1 (Z-Y-X) Euler angles and body rates with
Gaussian noise, converted to MRPs (Feng, Chen, Yang 2018, Sec. 3.1). Energy is
:math:`\\int |u|^2 dt` of the applied torque.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from convexguid.dynamics.disturbance import guo2011_disturbance
from convexguid.dynamics.mrp_attitude import rk4_step, shortest_mrp
from convexguid.progress import report
from convexguid.rotations import euler321_to_quat, mrp_to_quat, quat_to_euler321, quat_to_mrp


@dataclass(frozen=True)
class Nominal:
    """A nominal trajectory sampled on a uniform grid ``t``: MRP states ``x`` (n, 6) and torques ``u`` (n, 3).

    Between samples the state and the torque are interpolated linearly.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray

    def index(self, t: float) -> int:
        return int(np.clip(np.searchsorted(self.t, t - 1e-12), 0, self.t.size - 1))

    def state(self, t: float | np.ndarray) -> np.ndarray:
        return interp_rows(self.t, self.x, t)

    def control(self, t: float | np.ndarray) -> np.ndarray:
        return interp_rows(self.t, self.u, t)


def interp_rows(grid: np.ndarray, values: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    """Every column of ``values`` (sampled on ``grid``) interpolated linearly at ``t``."""
    t = np.asarray(t, dtype=float)
    return np.stack([np.interp(t, grid, values[:, k]) for k in range(values.shape[1])], -1)


def integrate(x0: np.ndarray, t: np.ndarray, u: np.ndarray, inertia: np.ndarray, inertia_inv: np.ndarray
              ) -> np.ndarray:
    """States on the grid ``t`` from ``x0`` under torques ``u`` held over each step (RK4), MRPs kept short."""
    x = np.empty((t.size, 6))
    x[0] = x0
    for k in range(t.size - 1):
        x[k + 1] = rk4_step(x[k], u[k], t[k + 1] - t[k], inertia, inertia_inv)
        x[k + 1, :3] = shortest_mrp(x[k + 1, :3])
    return x


@dataclass(frozen=True)
class Sensors:
    """Gaussian noise on the 3-2-1 Euler angles (rad) and the body rates (rad/s), standard deviations."""

    euler_std_rad: float
    rate_std_radps: float

    def measure(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        q = mrp_to_quat(x[:3])
        rpy = quat_to_euler321(q) + rng.normal(0.0, self.euler_std_rad, 3)
        sigma = shortest_mrp(quat_to_mrp(euler321_to_quat(rpy)))
        return np.concatenate([sigma, x[3:] + rng.normal(0.0, self.rate_std_radps, 3)])


@dataclass(frozen=True)
class DisturbanceTorque:
    """The disturbance torque held over a step starting at ``t``: Gaussian per axis (``model = "gaussian"``,
    standard deviation ``std_Nm``) or Guo, Li, Ma's deterministic Sec. 4 torque (``model = "guo2011"``)."""

    model: str = "gaussian"
    std_Nm: float = 0.0

    def __call__(self, t: float, rng: np.random.Generator) -> np.ndarray:
        if self.model == "guo2011":
            return guo2011_disturbance(t)
        return rng.normal(0.0, self.std_Nm, 3)


class Controller(Protocol):
    """A tracking or regulating law: a torque command from the time and the measured state."""

    name: str

    def command(self, t: float, measured: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class Flight:
    """One closed-loop run on the grid ``t``: true states, applied torques, energy, compute time of the law."""

    controller: str
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    energy: float
    command_time_s: float
    wall_time_s: float

    @property
    def final_euler_deg(self) -> np.ndarray:
        return np.degrees(quat_to_euler321(mrp_to_quat(self.x[-1, :3])))

    @property
    def final_rate_degps(self) -> np.ndarray:
        return np.degrees(self.x[-1, 3:])


def fly(controller: Controller, x0: np.ndarray, t: np.ndarray, inertia: np.ndarray, u_max: np.ndarray,
        sensors: Sensors, disturbance: DisturbanceTorque, rng: np.random.Generator) -> Flight:
    """Fly ``controller`` from the true state ``x0`` over the grid ``t`` (command and disturbance held per step)."""
    start = time.perf_counter()
    inertia_inv = np.linalg.inv(inertia)
    x = np.empty((t.size, 6))
    u = np.zeros((t.size, 3))
    x[0] = x0
    command_time = 0.0
    for k in range(t.size - 1):
        report(f"{controller.name} flight step", k, t.size - 1)
        measured = sensors.measure(x[k], rng)
        c0 = time.perf_counter()
        u[k] = np.clip(controller.command(float(t[k]), measured), -u_max, u_max)
        command_time += time.perf_counter() - c0
        d = disturbance(float(t[k]), rng)
        x[k + 1] = rk4_step(x[k], u[k] + d, t[k + 1] - t[k], inertia, inertia_inv)
        x[k + 1, :3] = shortest_mrp(x[k + 1, :3])
    u[-1] = u[-2]
    energy = float(np.sum(np.sum(u[:-1] ** 2, axis=1) * np.diff(t)))
    return Flight(controller.name, t, x, u, energy, command_time, time.perf_counter() - start)
