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
linearizes :math:`u(\\zeta)` (Gauss-Newton on the energy) and the cone maps each iteration;
:mod:`convexguid.families.flat_attitude.solve` runs it, verifies the plan and refines the path points.

References
----------
Cai W., Zhu Y., Zeng P., "Differentially flat method of attitude maneuver trajectory
planning for space vehicles under multiple constraints", J. Dynamics and Control 16(1),
2018, DOI 10.6052/1672-6553-2018-005, eqs. (1)-(5), (10)-(12), (26), (29)-(31).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property, partial

import numpy as np
import scipy.sparse as sp

from convexguid.dynamics.rigid_body import euler_torque
from convexguid.families.flat_attitude.row_derivatives import RowDerivative
from convexguid.geometry import PointingCone
from convexguid.rotations import euler321_body_rates, euler321_rates_from_body, euler321_to_dcm
from convexguid.scp.problem import (
    ConstraintBlock,
    Evaluation,
    LinearConstraints,
    OutputBlock,
    OutputConstraints,
    ProgramSize,
)
from convexguid.transcription import MappedChebyshev


def cone_cosine(cone: PointingCone, rpy: np.ndarray) -> np.ndarray:
    """:math:`r_B^T C_{BI}(\\zeta) r_I` at each row of ``rpy`` (3-2-1 Euler angles; complex-safe)."""
    return cone.cos_angle(euler321_to_dcm(rpy))


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
    omega = euler321_body_rates(z, zd)
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
    cones: tuple[PointingCone, ...]
    grid: MappedChebyshev
    check_points_per_interval: int = 2
    extra_points: tuple[float, ...] = ()
    cone_margin_rad: float = 0.0
    """Extra clearance demanded of every cone at the path points (set by the dense check's repairs)."""
    torque_margin: float = 0.0
    """Amount the torque box is tightened at the path points (set by the dense check's repairs)."""

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
        return euler321_body_rates(z, zd)


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
        return _cubic_hermite(p.t0, p.tf, (np.asarray(p.rpy0), np.asarray(p.rpyf)), rates, p.node_times).ravel()

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
        return self._outputs

    @cached_property
    def _outputs(self) -> OutputConstraints:
        p = self.problem
        interp = sp.kron(sp.csr_matrix(p.path_interpolation), sp.eye(3), format="csr")
        rows = interp.shape[0]
        M = sp.vstack([interp, -interp], format="csr")
        return OutputConstraints(M, np.full(2 * rows, p.torque_max - p.torque_margin),
                                 (OutputBlock("torque_Nm", slice(0, 2 * rows), "N m"),))

    def _torque_jacobian(self, z: np.ndarray, zd: np.ndarray, zdd: np.ndarray) -> np.ndarray:
        """Torque Jacobian from the local partials :math:`A_k, B_k, C_k` of eq. (12) (exact: CasADi's of the same map).

        .. math:: \\partial u_k/\\partial\\zeta_j = A_k\\delta_{kj} + s B_k D_{kj} + s^2 C_k D^{(2)}_{kj}
        """
        partials = self._torque_partials(np.hstack([z, zd, zdd]))
        local = [partials[:, :, 3 * i: 3 * i + 3] for i in range(3)]
        d1, d2 = self._scaled_differentiation
        # jac[k, a, j, b]: each entry one product (the outer products einsum("kab,kj->kajb") forms, broadcast)
        jac = local[1][:, :, None, :] * d1[:, None, :, None]
        jac += local[2][:, :, None, :] * d2[:, None, :, None]
        idx = np.arange(self.num_nodes)
        jac[idx, :, idx, :] += local[0]
        return jac.reshape(self.num_variables, self.num_variables)

    @cached_property
    def _scaled_differentiation(self) -> tuple[np.ndarray, np.ndarray]:
        """:math:`s D` and :math:`s^2 D^{(2)}`: the rates and accelerations at the nodes from the angles (eq. 23)."""
        p, s = self.problem, self.problem.time_scale
        return s * p.grid.d1, s * s * p.grid.d2

    def evaluate(self, x: np.ndarray, jacobians: bool = True) -> Evaluation:
        p = self.problem
        z, zd, zdd = p.flat_derivatives(x)
        u = flat_torque(p.inertia, z, zd, zdd)
        z_path = p.path_interpolation @ z
        blocks = tuple(ConstraintBlock(f"keep_out_{cone.name}", cone_cosine(cone, z_path)
                                       - np.cos(cone.half_angle_rad + p.cone_margin_rad), None, "cos")
                       for cone in p.cones)
        values = Evaluation(u.ravel(), None, blocks)
        return self.with_jacobians(x, values) if jacobians else values

    def with_jacobians(self, x: np.ndarray, values: Evaluation) -> Evaluation:
        """``values`` (:meth:`evaluate` at ``x`` without Jacobians) with the torque's and the cones' Jacobians."""
        p = self.problem
        z, zd, zdd = p.flat_derivatives(x)
        path = p.path_interpolation
        z_path = path @ z
        blocks = []
        for jacobian, block in zip(self._cone_jacobians, values.inequalities, strict=True):
            local = jacobian(z_path)[:, 0, :]
            blocks.append(replace(block, jacobian=(local[:, None, :] * path[:, :, None]).reshape(path.shape[0], -1)))
        return replace(values, residual_jacobian=self._torque_jacobian(z, zd, zdd), inequalities=tuple(blocks))

    def lagrangian_hessian(self, x: np.ndarray, weights) -> np.ndarray:
        """The curvature :math:`\\sum_k \\omega_k^T \\nabla^2 u_k + \\sum_p \\mu_p \\nabla^2 c_p` of the torques
        (eq. 12) and the cone constraints (eq. 31), assembled from their local Hessians.

        Each torque depends on its node's :math:`(\\zeta_k, \\dot\\zeta_k, \\ddot\\zeta_k) = S_k \\zeta`, linear in the
        design vector (:math:`S_k` the node's row of the identity, of :math:`s D` and of :math:`s^2 D^{(2)}`), so
        :math:`\\nabla^2 (\\omega_k^T u_k) = S_k^T G_k S_k` with :math:`G_k` the 9 x 9 Hessian of
        :math:`\\omega_k^T \\Gamma_u`; likewise each cone at a path point through the interpolation row. The local
        Hessians are exact (:class:`RowDerivative`: CasADi's second derivatives of the same maps)."""
        p, n1 = self.problem, self.num_nodes
        z, zd, zdd = p.flat_derivatives(x)
        omega = np.asarray(weights.residual, dtype=float).reshape(n1, 3)
        local = self._torque_hessian(np.hstack([z, zd, zdd]), omega)
        H = _sandwiched(self._node_rows, local)
        path = p.path_interpolation
        z_path, start = path @ z, 0
        for hessian in self._cone_hessians:
            mu = np.asarray(weights.inequality[start: start + path.shape[0]], dtype=float)
            start += path.shape[0]
            if np.any(mu):
                H += _sandwiched(path[:, None, :], hessian(z_path, mu[:, None]))
        return 0.5 * (H + H.T)

    def _torque_derivative(self, kind: str) -> RowDerivative:
        p = self.problem
        return RowDerivative(lambda a, b, c: flat_torque(p.inertia, a, b, c), (3, 3, 3), 3, self.num_nodes, kind)

    def _cone_derivatives(self, kind: str) -> tuple[RowDerivative, ...]:
        rows = self.problem.path_interpolation.shape[0]
        return tuple(RowDerivative(partial(cone_cosine, cone), (3,), 1, rows, kind) for cone in self.problem.cones)

    @cached_property
    def _torque_partials(self) -> RowDerivative:
        return self._torque_derivative("jacobian")

    @cached_property
    def _torque_hessian(self) -> RowDerivative:
        return self._torque_derivative("hessian")

    @cached_property
    def _cone_jacobians(self) -> tuple[RowDerivative, ...]:
        return self._cone_derivatives("jacobian")

    @cached_property
    def _cone_hessians(self) -> tuple[RowDerivative, ...]:
        return self._cone_derivatives("hessian")

    @cached_property
    def _node_rows(self) -> np.ndarray:
        """:math:`S_k`: each node's angle, rate and acceleration (rows) from the node angles, ``(node, 3, node)``."""
        d1, d2 = self._scaled_differentiation
        return np.stack([np.eye(self.num_nodes), d1, d2], axis=1)


def _sandwiched(rows: np.ndarray, local: np.ndarray) -> np.ndarray:
    """:math:`\\sum_k (S_k \\otimes I_3)^T G_k (S_k \\otimes I_3)` for maps :math:`S_k` ``rows`` ``(k, q, n)`` of the
    node angles and local Hessians :math:`G_k` ``local`` ``(k, 3q, 3q)`` (index: row of :math:`S_k` times 3 plus
    axis); the design vector is the node angles, node-major. The Kronecker factor's zeros are never multiplied:
    :math:`W_k = G_k (S_k \\otimes I_3)` per node, then one product over nodes and rows, a third of the work of
    the Kronecker form."""
    k, q, n = rows.shape
    # W[k, (r, a, b), j] = sum_t G_k[(r, a), (t, b)] S_k[t, j]
    per_row = local.reshape(k, q, 3, q, 3).transpose(0, 1, 2, 4, 3).reshape(k, 9 * q, q) @ rows
    # H[i, (a, b, j)] = sum_{k, r} S_k[r, i] W[k, (r, a, b), j]
    H = rows.reshape(k * q, n).T @ per_row.reshape(k * q, 9 * n)
    return H.reshape(n, 3, 3, n).transpose(0, 1, 3, 2).reshape(3 * n, 3 * n)


def build_problem(spec) -> FlatAttitudeProblem:
    """Turn a validated ``flat_attitude`` spec (:mod:`convexguid.families.flat_attitude.spec`) into SI arrays."""
    b = spec.boundary
    cones = tuple(PointingCone.from_spec(c) for c in spec.keep_out)
    grid = MappedChebyshev(spec.discretization.nodes, spec.discretization.map_epsilon)
    return FlatAttitudeProblem(spec.name, spec.spacecraft.inertia_matrix, spec.spacecraft.torque_max_Nm,
                               b.t0_s, b.tf_s, b.initial.rpy_rad, b.initial.rate_radps, b.final.rpy_rad,
                               b.final.rate_radps, cones, grid, spec.discretization.check_points_per_interval)


def _cubic_hermite(t0: float, t1: float, values: tuple[np.ndarray, np.ndarray],
                   slopes: list[np.ndarray], times: np.ndarray) -> np.ndarray:
    """The cubic through ``values`` with derivatives ``slopes`` at ``t0`` and ``t1``, at ``times`` (one row each).

    The Hermite basis :math:`h_{00} = 2s^3 - 3s^2 + 1`, :math:`h_{10} = s^3 - 2s^2 + s`, :math:`h_{01} = -2s^3 + 3s^2`,
    :math:`h_{11} = s^3 - s^2` with :math:`s = (t - t_0)/(t_1 - t_0)`; slopes are per unit time.
    """
    h = t1 - t0
    s = ((np.asarray(times, dtype=float) - t0) / h)[:, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * values[0] + h10 * h * slopes[0] + h01 * values[1] + h11 * h * slopes[1]
