"""The LPMPC tracking law (Feng, Chen, Yang 2018, Sec. 2.3, steps 4-6), generic over the nominal it flies.

Between checks the law flies the nominal torque. Every ``check_interval_s`` it predicts the terminal
deviation from the target analytically: the nominal's own miss plus :math:`K_x \\delta x_0` (eq. 42,
prediction method 1; the nominal's miss is zero until a correction leaves the linearization residual).
Only if a component exceeds its threshold does it integrate the nonlinear model from the measured
state under the nominal torque (method 2). If that trajectory still misses the target by more than the
threshold, it becomes the new nominal and the energy-optimal correction of
:mod:`convexguid.families.lpmpc.controller` is added to the torque, interpolated between the LGR points (eq. 24)
with :math:`\\delta u_0 = 0`. The corrected torque is then integrated once more, so that the nominal
states and torques stay consistent for the next prediction (the paper keeps the state trajectory of the
uncorrected torque).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from convexguid.dynamics.mrp_attitude import mrp_error_matrices
from convexguid.families.lpmpc.controller import (
    box_constrained_correction,
    energy_optimal_correction,
    least_change_correction,
    terminal_map,
)
from convexguid.families.lpmpc.tracking import Nominal, integrate, interp_rows
from convexguid.transcription.lgr import RadauGrid


@dataclass(frozen=True)
class LpmpcSettings:
    """``nodes`` N (LGR points); thresholds on the predicted terminal deviation (MRP, rad/s); the correction:
    energy-optimal (eqs. 45-56), then the box QP if that leaves the torque box (``box_constrained``), or the
    least change of the torque (``least_change``, for nominals with active path constraints)."""

    nodes: int
    check_interval_s: float
    threshold_mrp: float
    threshold_radps: float
    box_constrained: bool = False
    backend: str = "clarabel"
    least_change: bool = False

    @property
    def thresholds(self) -> np.ndarray:
        return np.array([self.threshold_mrp] * 3 + [self.threshold_radps] * 3)


@dataclass(frozen=True)
class Check:
    """One update check: the analytic prediction, and the correction if one fired."""

    t: float
    predicted: np.ndarray
    corrected: bool
    miss: np.ndarray | None = None
    leaves_box: bool = False
    prediction_time_s: float = 0.0
    correction_time_s: float = 0.0
    integration_time_s: float = 0.0


@dataclass
class LpmpcTracker:
    """Flies ``nominal`` (a copy is corrected in place) to ``target`` = [MRP, rates]."""

    nominal: Nominal
    target: np.ndarray
    inertia: np.ndarray
    u_max: np.ndarray
    settings: LpmpcSettings
    name: str = "lpmpc"
    checks: list[Check] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.nominal = Nominal(self.nominal.t, self.nominal.x.copy(), self.nominal.u.copy())
        self.inertia_inv = np.linalg.inv(self.inertia)
        self._next_check = float(self.nominal.t[0])

    @property
    def corrections(self) -> int:
        return sum(c.corrected for c in self.checks)

    def command(self, t: float, measured: np.ndarray) -> np.ndarray:
        tf = float(self.nominal.t[-1])
        if t >= self._next_check - 1e-9 and tf - t > 1e-6:
            self._check(t, measured)
            self._next_check += self.settings.check_interval_s
        return self.nominal.control(t)

    def _map(self, t: float, states_at: callable):
        grid = RadauGrid(self.settings.nodes, t, float(self.nominal.t[-1]))
        A, B = mrp_error_matrices(states_at(grid.times), self.inertia, self.inertia_inv)
        return grid, terminal_map(grid, A, B)

    def _check(self, t: float, measured: np.ndarray) -> None:
        s, nominal = self.settings, self.nominal
        c0 = time.perf_counter()
        _, tmap = self._map(t, nominal.state)
        # the nominal's own miss (nonzero after a correction: the linear model is not exact) plus K_x dx0
        predicted = nominal.x[-1] - self.target + tmap.predict(measured - nominal.state(t))
        c1 = time.perf_counter()
        if np.all(np.abs(predicted) <= s.thresholds):
            self.checks.append(Check(t, predicted, False, prediction_time_s=c1 - c0))
            return
        k = nominal.index(t)
        grid_t = nominal.t[k:].copy()
        grid_t[0] = t
        flown = integrate(measured, grid_t, nominal.u[k:], self.inertia, self.inertia_inv)
        miss = flown[-1] - self.target
        c2 = time.perf_counter()
        if np.all(np.abs(miss) <= s.thresholds):
            self.checks.append(Check(t, predicted, False, miss, prediction_time_s=c1 - c0,
                                     integration_time_s=c2 - c1))
            return
        grid, tmap = self._map(t, lambda times: interp_rows(grid_t, flown, times))
        u_nodes = nominal.control(grid.times[1:])
        du = (least_change_correction(tmap, miss, u_nodes.shape[1]) if s.least_change
              else energy_optimal_correction(tmap, u_nodes, miss))
        leaves = bool(np.any(np.abs(u_nodes + du) > self.u_max * (1 + 1e-9)))
        if s.box_constrained and leaves:
            boxed = box_constrained_correction(tmap, u_nodes, miss, self.u_max, s.backend)
            du = du if boxed is None else boxed
        c3 = time.perf_counter()
        du_all = np.vstack([np.zeros((1, du.shape[1])), du])  # delta u_0 = 0: the command stays continuous
        nominal.u[k:] += grid.control_interpolation(grid_t) @ du_all
        nominal.x[k:] = integrate(measured, grid_t, nominal.u[k:], self.inertia, self.inertia_inv)
        self.checks.append(Check(t, predicted, True, miss, leaves, c1 - c0, c3 - c2,
                                 c2 - c1 + time.perf_counter() - c3))

