"""Flat-output attitude planning (Cai, Zhu, Zeng 2018).

The Euler angles :math:`\\zeta = (\\varphi, \\theta, \\psi)` of the 3-2-1 sequence are
flat outputs of the rigid body: rates and torques follow from them and their time
derivatives (eqs. 10-12), so the differential equations disappear and the decision
variables are :math:`\\zeta` at the :math:`N+1` mapped CGL nodes (99 for :math:`N = 32`).

.. math::

    \\omega = E(\\zeta)\\dot\\zeta, \\qquad
    \\dot\\omega = E(\\zeta)\\ddot\\zeta + \\dot E(\\zeta,\\dot\\zeta)\\dot\\zeta,
    \\qquad u = I\\dot\\omega + \\omega\\times I\\omega,

    J = \\frac{t_f - t_0}{2} \\sum_k w^c_k g'(\\tau_k)\\, \\|u(\\lambda_k)\\|^2 \\quad \\text{(eq. 26)},

subject to the boundary attitudes and rates (eq. 29), :math:`|u_i| \\le u_{max}` (eq. 30)
and :math:`r_B^T C_{BI}(\\zeta) r_I \\le \\cos\\beta` for every keep-out cone (eq. 31).
Path constraints are imposed at the nodes and at ``check_points_per_interval``
interpolated points between them, where the cone is most at risk. The SCP engine
linearizes :math:`u(\\zeta)` (Gauss-Newton on the energy) and the cone maps each iteration.

References
----------
Cai W., Zhu Y., Zeng P., "Differentially flat method of attitude maneuver trajectory
planning for space vehicles under multiple constraints", J. Dynamics and Control 16(1),
2018, DOI 10.6052/1672-6553-2018-005, eqs. (1)-(5), (10)-(12), (26), (29)-(31).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import CubicHermiteSpline

from convexguid.dynamics.rigid_body import euler_torque
from convexguid.rotations import (
    euler321_rates_from_body,
    euler321_rates_matrix,
    euler321_to_dcm,
    euler321_to_quat,
    quat_to_euler321,
)
from convexguid.scp.derivatives import pointwise_jacobian
from convexguid.scp.engine import IterationRecord, merge_results, solve_scp
from convexguid.scp.problem import (
    ConstraintBlock,
    Evaluation,
    LinearConstraints,
    OutputBlock,
    OutputConstraints,
    ProgramSize,
    SCPSettings,
)
from convexguid.solution import Solution, Trajectory
from convexguid.transcription import MappedChebyshev
from convexguid.verify import Verification, keep_out_angles_deg, propagate_attitude, verify_attitude_track


@dataclass(frozen=True)
class KeepOutCone:
    """Body axis ``body_axis`` must stay more than ``half_angle_rad`` from inertial ``inertial_dir`` (unit vectors)."""

    name: str
    body_axis: np.ndarray
    inertial_dir: np.ndarray
    half_angle_rad: float

    def cos_angle(self, rpy: np.ndarray) -> np.ndarray:
        """:math:`r_B^T C_{BI}(\\zeta) r_I` at each row of ``rpy`` (complex-safe)."""
        return np.einsum("i,nij,j->n", self.body_axis, euler321_to_dcm(rpy), self.inertial_dir)


def euler321_body_acceleration(z: np.ndarray, zd: np.ndarray, zdd: np.ndarray) -> np.ndarray:
    """Body angular acceleration from Euler angles and their derivatives, Cai et al. eq. (11).

    Rows of ``z``, ``zd``, ``zdd`` are (roll, pitch, yaw) values, rates and accelerations.
    """
    p, t = z[:, 0], z[:, 1]
    pd, td, yd = zd[:, 0], zd[:, 1], zd[:, 2]
    pdd, tdd, ydd = zdd[:, 0], zdd[:, 1], zdd[:, 2]
    sp, cp, st, ct = np.sin(p), np.cos(p), np.sin(t), np.cos(t)
    return np.stack([
        pdd - ydd * st - td * yd * ct,
        tdd * cp - pd * td * sp + ydd * sp * ct + pd * yd * cp * ct - td * yd * sp * st,
        -tdd * sp - pd * td * cp + ydd * cp * ct - pd * yd * sp * ct - td * yd * cp * st,
    ], axis=1)


def flat_torque(inertia: np.ndarray, z: np.ndarray, zd: np.ndarray, zdd: np.ndarray) -> np.ndarray:
    """Torque as a function of the flat outputs, eq. (12): :math:`u = \\Gamma_u(\\zeta, \\dot\\zeta, \\ddot\\zeta)`."""
    omega = np.einsum("nij,nj->ni", euler321_rates_matrix(z), zd)
    return euler_torque(inertia, omega, euler321_body_acceleration(z, zd, zdd))


@dataclass(frozen=True)
class FlatAttitudeProblem:
    """Energy-optimal rest-to-rest (or rate-to-rate) slew in flat outputs, SI units throughout."""

    name: str
    inertia: np.ndarray
    torque_max: float
    t0: float
    tf: float
    rpy0: np.ndarray
    rate0: np.ndarray
    rpyf: np.ndarray
    ratef: np.ndarray
    cones: tuple[KeepOutCone, ...]
    grid: MappedChebyshev
    check_points_per_interval: int = 2
    extra_points: tuple[float, ...] = ()

    @property
    def time_scale(self) -> float:
        """:math:`d\\lambda/dt = 2/(t_f - t_0)` from eq. (17)."""
        return 2.0 / (self.tf - self.t0)

    @cached_property
    def node_times(self) -> np.ndarray:
        return self.grid.times(self.t0, self.tf)

    @cached_property
    def path_interpolation(self) -> np.ndarray:
        """Rows: the nodes, then the check points between them and the refinement points (``extra_points``)."""
        lam = np.concatenate([self.grid.check_points(self.check_points_per_interval), self.extra_points])
        return np.vstack([np.eye(self.grid.n + 1), self.grid.interpolation_matrix(lam)])

    def flat_derivatives(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Node values of :math:`\\zeta, \\dot\\zeta, \\ddot\\zeta` from the design vector (eq. 23)."""
        z = x.reshape(-1, 3)
        s = self.time_scale
        return z, s * (self.grid.d1 @ z), s * s * (self.grid.d2 @ z)

    def torques(self, x: np.ndarray) -> np.ndarray:
        return flat_torque(self.inertia, *self.flat_derivatives(x))

    def body_rates(self, x: np.ndarray) -> np.ndarray:
        z, zd, _ = self.flat_derivatives(x)
        return np.einsum("nij,nj->ni", euler321_rates_matrix(z), zd)


class FlatAttitudeProgram:
    """:class:`convexguid.scp.problem.NonconvexProgram` view of a :class:`FlatAttitudeProblem`."""

    def __init__(self, problem: FlatAttitudeProblem) -> None:
        self.problem = problem
        self.num_nodes = problem.grid.n + 1
        self.num_variables = 3 * self.num_nodes

    def size(self) -> ProgramSize:
        """The NLP of the paper: 3(N+1) angles, 12 boundary equalities, torque and cone inequalities."""
        n_path = self.problem.path_interpolation.shape[0]
        return ProgramSize(self.num_variables, self.linear_constraints().A.shape[0],
                           n_path * (6 + len(self.problem.cones)))

    def initial_guess(self) -> np.ndarray:
        """Cubic Hermite spline through the boundary attitudes and Euler rates (the paper's guess)."""
        p = self.problem
        rates = [euler321_rates_from_body(p.rpy0, p.rate0), euler321_rates_from_body(p.rpyf, p.ratef)]
        spline = CubicHermiteSpline([p.t0, p.tf], np.vstack([p.rpy0, p.rpyf]), np.vstack(rates))
        return spline(p.node_times).ravel()

    def variable_scale(self) -> np.ndarray:
        return np.ones(self.num_variables)

    def residual_weights(self) -> np.ndarray:
        """Clenshaw-Curtis weights of eq. (26), one per torque component."""
        p = self.problem
        return np.repeat(0.5 * (p.tf - p.t0) * p.grid.quadrature_weights, 3)

    def linear_cost(self) -> np.ndarray:
        return np.zeros(self.num_variables)

    @cached_property
    def _linear(self) -> LinearConstraints:
        """Boundary conditions, eq. (29): attitudes fixed; :math:`\\dot\\zeta = E^{-1}\\omega` at both ends."""
        p, n1 = self.problem, self.num_nodes
        rows, rhs = [], []
        for node, rpy, rate in ((0, p.rpy0, p.rate0), (n1 - 1, p.rpyf, p.ratef)):
            pick = np.zeros(n1)
            pick[node] = 1.0
            rows.append(np.kron(pick, np.eye(3)))
            rhs.append(rpy)
            rows.append(np.kron(p.time_scale * p.grid.d1[node], np.eye(3)))
            rhs.append(euler321_rates_from_body(rpy, rate))
        n = self.num_variables
        return LinearConstraints(np.vstack(rows), np.concatenate(rhs), np.zeros((0, n)), np.zeros(0))

    def linear_constraints(self) -> LinearConstraints:
        return self._linear

    def output_constraints(self) -> OutputConstraints:
        """Torque box, eq. (30), at the nodes and check points: :math:`|L u|_i \\le u_{max}`, linear in the torques."""
        p = self.problem
        interp = sp.kron(sp.csr_matrix(p.path_interpolation), sp.eye(3), format="csr")
        rows = interp.shape[0]
        M = sp.vstack([interp, -interp], format="csr")
        return OutputConstraints(M, np.full(2 * rows, p.torque_max),
                                 (OutputBlock("torque_Nm", slice(0, 2 * rows), "N m"),))

    def _torque_jacobian(self, z: np.ndarray, zd: np.ndarray, zdd: np.ndarray) -> np.ndarray:
        """Torque Jacobian from complex-step local partials :math:`A_k, B_k, C_k` of eq. (12).

        .. math:: \\partial u_k/\\partial\\zeta_j = A_k\\delta_{kj} + s B_k D_{kj} + s^2 C_k D^{(2)}_{kj}
        """
        p, s = self.problem, self.problem.time_scale

        def torque(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
            return flat_torque(p.inertia, a, b, c)

        local = [pointwise_jacobian(torque, (z, zd, zdd), i) for i in range(3)]
        jac = np.einsum("kab,kj->kajb", local[1], s * p.grid.d1)
        jac += np.einsum("kab,kj->kajb", local[2], s * s * p.grid.d2)
        idx = np.arange(self.num_nodes)
        jac[idx, :, idx, :] += local[0]
        return jac.reshape(self.num_variables, self.num_variables)

    def evaluate(self, x: np.ndarray, jacobians: bool = True) -> Evaluation:
        p = self.problem
        z, zd, zdd = p.flat_derivatives(x)
        u = flat_torque(p.inertia, z, zd, zdd)
        path = p.path_interpolation
        jac_u = self._torque_jacobian(z, zd, zdd) if jacobians else None
        blocks = []
        z_path = path @ z
        for cone in p.cones:
            values = cone.cos_angle(z_path) - np.cos(cone.half_angle_rad)
            jac = None
            if jacobians:
                local = pointwise_jacobian(cone.cos_angle, (z_path,), 0)
                jac = (local[:, None, :] * path[:, :, None]).reshape(path.shape[0], -1)
            blocks.append(ConstraintBlock(f"keep_out_{cone.name}", values, jac, "cos"))
        return Evaluation(u.ravel(), jac_u, tuple(blocks))


def build_problem(spec) -> FlatAttitudeProblem:
    """Turn a validated ``flat_attitude`` spec (:mod:`convexguid.spec.flat_attitude`) into SI arrays."""
    b = spec.boundary
    cones = tuple(KeepOutCone(c.name, c.body_axis_unit, c.inertial_dir_unit, c.half_angle_rad)
                  for c in spec.keep_out)
    grid = MappedChebyshev(spec.discretization.nodes, spec.discretization.map_epsilon)
    return FlatAttitudeProblem(spec.name, spec.spacecraft.inertia_matrix, spec.spacecraft.torque_max_Nm,
                               b.t0_s, b.tf_s, b.initial.rpy_rad, b.initial.rate_radps, b.final.rpy_rad,
                               b.final.rate_radps, cones, grid, spec.discretization.check_points_per_interval)


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
