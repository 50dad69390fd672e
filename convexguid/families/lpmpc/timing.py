"""Compute time of one command update: LQR (one Riccati solve) against LPMPC (eq. 42 prediction + correction).

An LPMPC update here is what the law computes at a check that fires, minus the nonlinear integrations:
the error matrices at the LGR points, :math:`K_x` and :math:`K_u`, the analytic prediction and the
closed-form correction (the paper's 59 ms at N = 8). The method-2 integration from the measured state
is timed separately. Medians over ``repeat`` calls at the nominal's first point.
"""

from __future__ import annotations

import time

import numpy as np

from convexguid.dynamics.mrp_attitude import mrp_error_matrices
from convexguid.families.lpmpc.controller import energy_optimal_correction, terminal_map
from convexguid.families.lpmpc.lqr import lqr_gain
from convexguid.families.lpmpc.scenario import Scenario
from convexguid.families.lpmpc.tracking import integrate
from convexguid.transcription.lgr import RadauGrid


def median_ms(call, repeat: int) -> float:
    """Median wall time of ``repeat`` calls of ``call``, ms."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(1e3 * np.median(times))


def update_times_ms(scenario: Scenario, nodes: list[int], repeat: int = 50) -> dict[str, float]:
    """``{"lqr": ..., "lpmpc_n8": ..., ..., "integration": ...}``: median milliseconds per update."""
    nominal, inertia = scenario.nominal, scenario.inertia
    inertia_inv = np.linalg.inv(inertia)
    x0, tf = nominal.x[0], float(nominal.t[-1])
    miss = 1e-3 * np.ones(6)
    Q, R = scenario.lqr_q * np.eye(6), scenario.lqr_r[0] * np.eye(3)

    def lqr_update():
        A, B = mrp_error_matrices(x0, inertia, inertia_inv)
        return nominal.u[0] - lqr_gain(A, B, Q, R) @ (x0 - nominal.x[0])

    out = {"lqr": median_ms(lqr_update, repeat)}
    for n in nodes:
        def lpmpc_update(n=n):
            grid = RadauGrid(n, float(nominal.t[0]), tf)
            A, B = mrp_error_matrices(nominal.state(grid.times), inertia, inertia_inv)
            tmap = terminal_map(grid, A, B)
            tmap.predict(np.zeros(6))
            return energy_optimal_correction(tmap, nominal.control(grid.times[1:]), miss)

        out[f"lpmpc_n{n}"] = median_ms(lpmpc_update, repeat)
    out["integration"] = median_ms(lambda: integrate(x0, nominal.t, nominal.u, inertia, inertia_inv),
                                    max(3, repeat // 10))
    return out
