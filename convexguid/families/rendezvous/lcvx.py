"""Method ``lcvx``: minimum burn time by lossless convexification on a fixed zero-order-hold grid.

The nonconvex thrust set :math:`\\{0\\} \\cup \\{|u| = 1\\}` (engine off, or on at full
thrust) is relaxed with a slack throttle :math:`\\Gamma`:

.. math::

    \\min \\sum_{k=0}^{K-1} \\Gamma_k\\,\\Delta t
    \\quad\\text{s.t.}\\quad X_{k+1} = \\Phi X_k + \\Gamma_d u_k,\\quad
    |u_k| \\le \\Gamma_k \\le 1,\\quad X_0 = X_{init},\\; X_K = X_f,

with the exact zero-order-hold pair :math:`\\Phi = e^{A\\Delta t}`,
:math:`\\Gamma_d = \\int_0^{\\Delta t} e^{As} B\\,ds`. It is a second-order cone program;
the states are eliminated, :math:`X_K = \\Phi^K X_0 + \\sum_k \\Phi^{K-1-k}\\Gamma_d u_k`, leaving
:math:`K(n_u + 1)` variables, one dense block of :math:`n_x` equalities, :math:`K` cones and
:math:`K` bounds. For a controllable linear system the relaxation is lossless in continuous
time (the optimal :math:`\\Gamma` is bang-off-bang and :math:`|u| = \\Gamma`); on a grid, the
steps that contain a switch keep an intermediate throttle, which is reported. Being
convex, its optimum is global for the grid: no arc structure or initial guess needed.

References
----------
Acikmese B., Ploen S. R., "Convex programming approach to powered descent guidance
for Mars landing", J. Guidance, Control, and Dynamics 30(5), 2007 (lossless convexification).
Wang H., Tang G., J. National Univ. of Defense Technology 25(5), 2003 (the problem).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram, make_backend
from convexguid.dynamics.clohessy_wiltshire import cw_zoh
from convexguid.families.rendezvous.case import BurnArc, Rendezvous, RendezvousPlan, ThrustPlan, state_columns
from convexguid.families.rendezvous.figures import LcvxPlanFigures
from convexguid.scp.problem import ProgramSize
from convexguid.solution import Trajectory

ON_THRESHOLD = 0.01
"""Throttle above which a step counts as burning; below 1 - this it counts as intermediate."""


def lcvx_program(case: Rendezvous, steps: int) -> tuple[ConicProgram, np.ndarray, np.ndarray]:
    """The condensed SOCP; variables ``[u_0, Gamma_0, u_1, Gamma_1, ...]``. Also returns ``Phi, Gamma_d``."""
    nu, nx = case.nu, case.nx
    dt = case.duration / steps
    phi, gam = cw_zoh(case.mean_motion, case.accel, dt, case.dim)
    width = nu + 1
    # terminal map: column block k is Phi^(K-1-k) Gamma_d
    blocks = np.empty((steps, nx, nu))
    blocks[-1] = gam
    for k in range(steps - 2, -1, -1):
        blocks[k] = phi @ blocks[k + 1]
    terminal = np.zeros((nx, steps * width))
    for k in range(steps):
        terminal[:, k * width: k * width + nu] = blocks[k]
    free_drift = np.linalg.matrix_power(phi, steps) @ case.x0
    # rows scaled to unit norm so position (m) and velocity (m/s) rows weigh alike
    row_scale = 1.0 / np.maximum(np.linalg.norm(terminal, axis=1), 1e-300)
    eq = sp.csr_matrix(terminal * row_scale[:, None])
    throttle = sp.csr_matrix((np.ones(steps), (np.arange(steps), np.arange(steps) * width + nu)),
                             shape=(steps, steps * width))
    soc = -sp.eye(steps * width, format="csr")
    perm = np.concatenate([np.arange(steps)[:, None] * width + nu,
                           np.arange(steps)[:, None] * width + np.arange(nu)], axis=1).ravel()
    soc = soc[perm]  # each cone: (Gamma_k, u_k)
    A = sp.vstack([eq, throttle, soc], format="csc")
    b = np.concatenate([row_scale * (case.xf - free_drift), np.ones(steps), np.zeros(steps * width)])
    q = np.zeros(steps * width)
    q[np.arange(steps) * width + nu] = dt
    P = sp.csc_matrix((steps * width, steps * width))
    return ConicProgram(P, q, A, b, Cones(zero=nx, nonneg=steps, soc=(width,) * steps)), phi, gam


def burn_structure(grid: np.ndarray, throttle: np.ndarray) -> tuple[BurnArc, ...]:
    """Burns as runs of steps with :math:`\\Gamma > 0.01`; partial steps at either end count by their throttle.

    A run over steps ``i..j`` starts at :math:`t_{i+1} - \\Gamma_i\\Delta t` and ends at
    :math:`t_j + \\Gamma_j\\Delta t`: the equivalent full-thrust burn placed against the
    rest of the run.
    """
    on = throttle > ON_THRESHOLD
    dt = np.diff(grid)
    arcs, k = [], 0
    while k < on.size:
        if not on[k]:
            k += 1
            continue
        j = k
        while j + 1 < on.size and on[j + 1]:
            j += 1
        start = grid[k + 1] - throttle[k] * dt[k] if j > k else grid[k]
        end = grid[j] + throttle[j] * dt[j] if j > k else grid[k] + throttle[k] * dt[k]
        arcs.append(BurnArc(float(start), float(end)))
        k = j + 1
    return tuple(arcs)


def solve_lcvx(case: Rendezvous, steps: int, backend: str = "clarabel") -> RendezvousPlan:
    """Solve the SOCP with ``backend`` (must take second-order cones) and read the burns off the throttle."""
    program, phi, gam = lcvx_program(case, steps)
    solver = make_backend(backend, program, tolerance=1e-9)
    res = solver.solve()
    nu, width = case.nu, case.nu + 1
    size = ProgramSize(program.num_variables, program.cones.zero, program.cones.nonneg + len(program.cones.soc))
    timing = {"solver_s": res.solve_time_s}
    grid = np.linspace(case.t0, case.tf, steps + 1)
    if not res.usable:
        status = "infeasible" if res.status == "infeasible" else "solver_error"
        message = (f"no thrust history with |a u| <= {case.accel:g} m/s^2 reaches the target in "
                   f"{case.duration:g} s (the lcvx SOCP is primal infeasible)" if status == "infeasible"
                   else f"backend {backend} returned {res.status}")
        empty = Trajectory(grid, {})
        return RendezvousPlan(status, message, float("nan"), res.iterations, size, (), ThrustPlan((), nu), empty,
                              timing, LcvxPlanFigures(solver_iterations=res.iterations), [], solver.name)
    z = res.x.reshape(steps, width)
    u, throttle = z[:, :nu], z[:, nu]
    states = np.empty((steps + 1, case.nx))
    states[0] = case.x0
    for k in range(steps):
        states[k + 1] = phi @ states[k] + gam @ u[k]
    intermediate = (throttle > ON_THRESHOLD) & (throttle < 1 - ON_THRESHOLD)
    burning = throttle > ON_THRESHOLD
    figures = LcvxPlanFigures(
        solver_iterations=res.iterations,
        grid_steps=steps,
        intermediate_throttle_share=float(intermediate.sum() / max(burning.sum(), 1)),
        intermediate_throttle_steps=int(intermediate.sum()),
        lossless_gap_max=float(np.max(throttle - np.linalg.norm(u, axis=1))),
    )
    u_nodes = np.vstack([u, np.zeros(nu)])
    nodes = Trajectory(grid, {**state_columns(case.dim, states, u_nodes, case.accel),
                              "throttle": np.append(throttle, 0.0)})
    return RendezvousPlan("converged", "global optimum of the lossless convexification (one SOCP)",
                          float(throttle.sum() * case.duration / steps), res.iterations, size,
                          burn_structure(grid, throttle), ThrustPlan.from_steps(grid, u, threshold=1e-9), nodes,
                          timing, figures, [], solver.name)
