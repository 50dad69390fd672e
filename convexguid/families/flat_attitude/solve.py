"""Plan, verify and summarise a ``flat_attitude`` problem (Cai, Zhu, Zeng 2018).

The SCP solves :class:`~convexguid.families.flat_attitude.program.FlatAttitudeProgram`; where the
interpolated plan breaks the torque box or a cone between the path points, the worst points are
added and the problem is solved again (up to :data:`MAX_REFINEMENTS` rounds). The planned torque
is then integrated with SciPy and every constraint checked on a dense grid.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from convexguid.families.flat_attitude.program import FlatAttitudeProblem, FlatAttitudeProgram, build_problem
from convexguid.rotations import euler321_to_quat, quat_to_euler321
from convexguid.scp.engine import IterationRecord, merge_results, solve_scp
from convexguid.scp.problem import SCPSettings
from convexguid.solution import Solution, Trajectory
from convexguid.verify import Verification, keep_out_angles_deg, propagate_attitude, verify_attitude_track


def torque_command(problem: FlatAttitudeProblem, x: np.ndarray) -> Callable[[float], np.ndarray]:
    """The planned torque as a function of time: barycentric interpolation of the node torques (eq. 21)."""
    u_nodes = problem.torques(x)
    grid, t0, scale = problem.grid, problem.t0, problem.time_scale

    def torque(t: float) -> np.ndarray:
        return (grid.interpolation_matrix(np.array([scale * (t - t0) - 1.0])) @ u_nodes)[0]

    return torque


def verify_plan(problem: FlatAttitudeProblem, x: np.ndarray, settings) -> tuple[Verification, Trajectory]:
    """Propagate the planned torque with SciPy and check torque, cones and the final state on a dense grid."""
    t_grid = np.linspace(problem.t0, problem.tf, settings.grid_points)
    q0 = euler321_to_quat(problem.rpy0)
    track = propagate_attitude(problem.inertia, torque_command(problem, x), q0, problem.rate0, t_grid,
                               settings.rtol, settings.atol, max_step=(problem.tf - problem.t0) / 200)
    cones = [(c.name, c.body_axis, c.inertial_dir, np.degrees(c.half_angle_rad)) for c in problem.cones]
    verification = verify_attitude_track(track, problem.torque_max, cones, euler321_to_quat(problem.rpyf),
                                         problem.ratef, settings.constraint_tol, settings.final_attitude_tol_rad,
                                         settings.final_rate_tol_radps)
    lam = problem.time_scale * (t_grid - problem.t0) - 1.0
    planned = problem.grid.interpolation_matrix(lam) @ x.reshape(-1, 3)
    columns = {}
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        columns[f"{axis}_planned_deg"] = np.degrees(planned[:, i])
    propagated = quat_to_euler321(track.q)
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        columns[f"{axis}_propagated_deg"] = np.degrees(propagated[:, i])
    for i in range(3):
        columns[f"omega{i + 1}_degps"] = np.degrees(track.omega[:, i])
    for i in range(3):
        columns[f"u{i + 1}_Nm"] = track.torque[:, i]
    for c in problem.cones:
        columns[f"keep_out_{c.name}_deg"] = keep_out_angles_deg(track.q, c.body_axis, c.inertial_dir)
    return verification, Trajectory(track.t, columns)


def node_table(problem: FlatAttitudeProblem, x: np.ndarray) -> Trajectory:
    """Euler angles, body rates and torques at the mapped CGL nodes (the circles of the paper's Figs. 1-3)."""
    z, rates, u = x.reshape(-1, 3), problem.body_rates(x), problem.torques(x)
    columns = {}
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        columns[f"{axis}_deg"] = np.degrees(z[:, i])
    for i in range(3):
        columns[f"omega{i + 1}_degps"] = np.degrees(rates[:, i])
    for i in range(3):
        columns[f"u{i + 1}_Nm"] = u[:, i]
    return Trajectory(problem.node_times, columns)


MAX_REFINEMENTS = 8
"""Rounds of adding path-constraint points where the interpolated plan breaks a bound."""


def worst_interpolated_points(problem: FlatAttitudeProblem, x: np.ndarray, settings) -> np.ndarray:
    """Grid points (in :math:`\\lambda`) where the interpolated plan breaks the torque box or a cone.

    The plan is interpolated on the verification grid (no integration needed); of every
    run of consecutive violating points the worst one is returned.
    """
    lam = np.linspace(-1.0, 1.0, settings.grid_points)
    interp = problem.grid.interpolation_matrix(lam)
    excess = np.max(np.abs(interp @ problem.torques(x)), axis=1) / problem.torque_max - 1.0
    z = interp @ x.reshape(-1, 3)
    for cone in problem.cones:
        excess = np.maximum(excess, cone.cos_angle(z) - np.cos(cone.half_angle_rad))
    bad = excess > REFINEMENT_TOLERANCE * settings.constraint_tol
    if not bad.any():
        return np.empty(0)
    runs = np.split(np.flatnonzero(bad), np.flatnonzero(np.diff(np.flatnonzero(bad)) > 1) + 1)
    return np.array([lam[run[np.argmax(excess[run])]] for run in runs])


REFINEMENT_TOLERANCE = 0.1
"""Refine until the interpolated plan meets its bounds to a tenth of the verification tolerance."""


def solve_flat_attitude(spec, log: Callable[[IterationRecord], None] | None = None) -> Solution:
    """Plan, verify and summarise a ``flat_attitude`` problem (see the module docstring)."""
    start = time.perf_counter()
    problem = build_problem(spec)
    program = FlatAttitudeProgram(problem)
    s = spec.solver
    settings = SCPSettings.from_spec(s)
    result = solve_scp(program, settings, log)
    for _ in range(MAX_REFINEMENTS):
        worst = worst_interpolated_points(problem, result.x, spec.verification)
        if result.status != "converged" or worst.size == 0:
            break
        problem = replace(problem, extra_points=problem.extra_points + tuple(worst))
        program = FlatAttitudeProgram(problem)
        result = merge_results(result, solve_scp(program, settings, log, x0=result.x))
    verification, dense = verify_plan(problem, result.x, spec.verification)
    u = problem.torques(result.x)
    min_sep = min((float(dense.columns[f"keep_out_{c.name}_deg"].min()) for c in problem.cones), default=None)
    return Solution(
        problem=spec.name, family=spec.family, method=spec.method, status=result.status,
        objective=result.objective, iterations=result.iterations, size=program.size(),
        wall_time_s=time.perf_counter() - start, solver=s.backend, message=result.message,
        verification=verification, history=result.history, nodes=node_table(problem, result.x), dense=dense,
        extras={"energy": result.objective, "max_torque_Nm": float(np.abs(u).max()),
                "min_separation_deg": min_sep, "map_alpha": problem.grid.alpha,
                "max_constraint_violation_nodes": result.max_violation},
        timing=result.timing(),
    )
