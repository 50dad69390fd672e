"""Method ``lcvx``: minimum burn time by lossless convexification on a fixed zero-order-hold grid, stated on
:mod:`convexguid.ocp`.

The nonconvex thrust set :math:`\\{0\\} \\cup \\{|u| = 1\\}` (engine off, or on at full thrust) is relaxed with a
throttle :math:`\\Gamma` (Acikmese & Ploen 2007):

.. math::

    \\min \\sum_{k=0}^{K-1} \\Gamma_k\\,\\Delta t
    \\quad\\text{s.t.}\\quad X_{k+1} = \\Phi X_k + \\Gamma_d u_k,\\quad
    |u_k| \\le \\Gamma_k \\le 1,\\quad X_0 = X_{init},\\; X_K = X_f,

with the exact zero-order-hold pair :math:`\\Phi = e^{A\\Delta t}`,
:math:`\\Gamma_d = \\int_0^{\\Delta t} e^{As} B\\,ds`.
:func:`lcvx_problem` states it as a :class:`convexguid.ocp.Problem`: the states with their boundary values, the
thrust direction ``u`` held on each step, the flow :math:`\\Phi X + \\Gamma_d u` in closed form
(:func:`~convexguid.dynamics.clohessy_wiltshire.cw_stm_casadi`,
:func:`~convexguid.dynamics.clohessy_wiltshire.cw_hold_input_casadi`; transcription ``"flow"``), the cone
:math:`|u| \\le 1`, and the objective :math:`\\int |u|\\,dt` (``minimize_fuel(2)``: each step's slack
:math:`s_k \\ge |u_k|` is the throttle :math:`\\Gamma_k`, the cone keeps it within 1 at the optimum). Every map is
affine, so the engine solves it as the one convex program it is (one SCP iteration, its KKT conditions checked).
For a controllable linear system the relaxation is lossless in continuous time (the optimal :math:`\\Gamma` is
bang-off-bang and :math:`|u| = \\Gamma`); on a grid, the steps that contain a switch keep an intermediate throttle,
which is reported. Being convex, its optimum is global for the grid: no arc structure or initial guess needed.

References
----------
Acikmese B., Ploen S. R., "Convex programming approach to powered descent guidance
for Mars landing", J. Guidance, Control, and Dynamics 30(5), 2007 (lossless convexification).
Wang H., Tang G., J. National Univ. of Defense Technology 25(5), 2003 (the problem).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from convexguid.dynamics.clohessy_wiltshire import cw_hold_input_casadi, cw_stm_casadi
from convexguid.families.rendezvous.arc_phases import AXES, cw_states
from convexguid.families.rendezvous.case import BurnArc, Rendezvous, RendezvousPlan, ThrustPlan, state_columns
from convexguid.families.rendezvous.figures import LcvxPlanFigures
from convexguid.ocp import Problem
from convexguid.ocp.solve import program_size, transcribe
from convexguid.scp.engine import solve_scp
from convexguid.scp.problem import SCPSettings
from convexguid.solution import Trajectory

ITERATIVE_REFINEMENT = False
"""Clarabel's iterative refinement of its KKT solves, off for this one convex solve. Measured on the paper's 600
steps (best of three): solver time 0.090 -> 0.052 s coplanar, 0.132 -> 0.079 s in three dimensions, the burn time
within 2.5e-10 (coplanar) and 6.4e-11 (three dimensions) of the cvxpy statement's either way (1.1e-10, 5.3e-11 with
it)."""

COAST_THRUST = 1e-4
"""A step whose thrust magnitude is below this is flown as a coast (a thrust of 1e-4 over a step moves the final
state far less than the verification's tolerance). Measured on the paper files' 600 steps: the coast steps of the
solved program carry up to 1.5e-7 coplanar and 1.6e-6 in three dimensions (the interior-point solver's residue,
where a thrust that small costs nearly nothing), the partial steps at a switch 0.069 and more; flown at its residue,
every one of the 600 steps was a thrust segment of the plan, and its figures changed with the residue."""

ON_THRESHOLD = 0.01
"""Throttle above which a step counts as burning; below 1 - this it counts as intermediate."""


def lcvx_problem(case: Rendezvous, steps: int) -> Problem:
    """The relaxed problem on ``steps`` equal zero-order-hold steps (see the module docstring)."""
    p = Problem(f"{case.name} (lcvx)")
    d, x = case.dim, cw_states(p, case, case.x0, case.xf)
    u = ca.vertcat(*(p.control(f"u{axis}", bounds=(-1.0, 1.0), scale=1.0) for axis in AXES[:d]))
    A, B = case.matrices()
    rates = ca.mtimes(ca.sparsify(ca.DM(A)), x) + ca.mtimes(ca.sparsify(ca.DM(B)), u)
    p.dynamics({x[i]: rates[i] for i in range(case.nx)})
    after = (ca.mtimes(cw_stm_casadi(case.mean_motion, p.time, d), x)
             + ca.mtimes(cw_hold_input_casadi(case.mean_motion, case.accel, p.time, d), u))
    p.flow({x[i]: after[i] for i in range(case.nx)})
    p.cone_constraint("thrust", [u[i] for i in range(d)], 1.0)
    p.final_time(fixed=case.duration)
    p.minimize_fuel(2)
    p.transcription(steps, "flow")
    return p


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
    """Solve :func:`lcvx_problem` with the SCP engine on ``backend`` (one that takes second-order cones) and read the
    burns off the throttle."""
    program = transcribe(lcvx_problem(case, steps))
    result = solve_scp(program, SCPSettings(backend=backend, iterative_refinement=ITERATIVE_REFINEMENT))
    nu = case.nu
    size = program_size(program, result.x)
    timing = result.timing()
    grid = case.t0 + program.final_time(result.x) * program.node_shares()
    solver_iterations = sum(record.solver_iterations for record in result.history)
    if result.status != "converged":
        message = (f"no thrust history with |a u| <= {case.accel:g} m/s^2 reaches the target in {case.duration:g} s "
                   f"(the lcvx problem is infeasible: {result.message})" if result.status == "infeasible"
                   else result.message)
        return RendezvousPlan(result.status, message, float("nan"), result.iterations, size, (), ThrustPlan((), nu),
                              Trajectory(grid, {}), timing, LcvxPlanFigures(solver_iterations=solver_iterations), [],
                              result.solver)
    u = program.control_values(result.x)
    throttle = np.asarray(result.x[program.slack_start: program.slack_start + program.num_slacks])
    states = program.states(result.x)
    intermediate = (throttle > ON_THRESHOLD) & (throttle < 1 - ON_THRESHOLD)
    burning = throttle > ON_THRESHOLD
    figures = LcvxPlanFigures(
        solver_iterations=solver_iterations,
        grid_steps=steps,
        intermediate_throttle_share=float(intermediate.sum() / max(burning.sum(), 1)),
        intermediate_throttle_steps=int(intermediate.sum()),
        lossless_gap_max=float(np.max(throttle - np.linalg.norm(u, axis=1))),
    )
    u_nodes = np.vstack([u, np.zeros(nu)])
    nodes = Trajectory(grid, {**state_columns(case.dim, states, u_nodes, case.accel),
                              "throttle": np.append(throttle, 0.0)})
    return RendezvousPlan("converged", "global optimum of the lossless convexification (a convex program, solved "
                                       f"once: {result.message})", float(throttle.sum() * case.duration / steps),
                          result.iterations, size, burn_structure(grid, throttle),
                          ThrustPlan.from_steps(grid, u, threshold=COAST_THRUST), nodes, timing, figures, [],
                          result.solver)
