"""Quaternion attitude planning under keep-out/keep-in cones, torque and rate boxes and forbidden attitudes.

State :math:`x = (q, \\omega)` (scalar-last quaternion, body relative to inertial; body rate), control
the body torque :math:`u`, full rigid-body dynamics with a full inertia matrix:

.. math::

    \\dot q = \\tfrac12\\, q \\otimes [\\omega, 0], \\qquad
    \\dot\\omega = I^{-1}(u - \\omega \\times I\\omega).

**Transcription.** Hermite-Simpson collocation on ``K`` equal intervals
(:mod:`convexguid.transcription.hermite_simpson`, shared with the rendezvous family), node
variables :math:`(q_k, \\omega_k, u_k)` and, for minimum time, the final time :math:`t_f` with
:math:`h = t_f/K`. Chosen over first-order hold with exact discretization because the defects
and their Jacobians are closed-form (no integration of the linearized dynamics each SCP
iteration), the method is fourth-order accurate, the free final time enters through
:math:`h` exactly as the burn durations do in the rendezvous family, and the Jacobians are
sparse (each defect touches two nodes and :math:`t_f`).

**Unit quaternion.** No norm constraint is imposed: the kinematics preserve
:math:`|q|` exactly in continuous time and Hermite-Simpson keeps it to
:math:`O(h^4)` per interval (the drift is reported as ``max_quaternion_norm_error``); adding
:math:`|q_k| = 1` on top of the defects would over-determine the discrete system. The cone
maps use the quadratic form :math:`C(q)` without normalization. The verification
propagates the true dynamics and renormalizes.

**Constraints.** Torque and rate boxes at the nodes (each torque axis with its own bound; the torque
is interpolated linearly between nodes, so its box holds everywhere); keep-out cones
:math:`b^T C_{BI}(q_k) r \\le \\cos(\\theta + m)` and keep-in cones
:math:`b^T C_{BI}(q_k) r \\ge \\cos(\\alpha - m)` at the nodes and at the Hermite-Simpson
interval midpoints (the rate box too, at the midpoints), with a margin :math:`m` that
is raised when the dense check finds the path cutting a cone's edge between nodes; the
forbidden attitude :math:`|q_b \\cdot q| \\le \\cos((\\theta_m + m)/2)`, two rows per node and midpoint.

**Objectives.** Minimum time (:math:`\\min t_f`) or minimum energy at fixed :math:`t_f`
(:math:`\\int |u|^2 dt` by Simpson's rule on the linear torque, as least-squares residuals).
The objective's value at the initial guess (``objective_scale``) sets the unit of the
exact-penalty weight (``scp_settings`` in :mod:`convexguid.families.quaternion_attitude.solve`),
so one weight serves a 0.04 N^2 m^2 s energy and a 100 s slew alike.

References
----------
Wang, Xu, Li, path-transfer planning for large-angle attitude maneuvers under multiple
constraints (seed 003), quaternion model and pointing constraint :math:`b^T C(q) r \\le \\cos\\theta`.
Guo, Li, Ma 2011 (seed 001), eq. (7): the forbidden-attitude distance.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from convexguid.dynamics.rigid_body import euler_torque
from convexguid.dynamics.torque import LinearTorque
from convexguid.geometry import PointingCone, eigenaxis_rotation
from convexguid.rotations import axis_angle_to_quat, quat_conjugate, quat_multiply, quat_rate_matrix, skew
from convexguid.scp.problem import (
    ConstraintBlock,
    Evaluation,
    LinearConstraints,
    OutputConstraints,
    ProgramSize,
)
from convexguid.transcription.hermite_simpson import hermite_simpson_defects

NX, NU = 7, 3
NODE = NX + NU


def cone_cosine(cone: PointingCone, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:math:`c = b^T C_{BI}(q) r` on rows of ``q`` (unnormalised quadratic form) and its gradient in q.

    .. math:: c = (w^2 - v^Tv)\\, b^Tr + 2 (b^Tv)(v^Tr) - 2w\\, v^T(r\\times b)
    """
    b, r = cone.body_axis, cone.inertial_dir
    v, w = q[:, :3], q[:, 3]
    br, rxb = b @ r, np.cross(r, b)
    c = (w**2 - np.sum(v * v, 1)) * br + 2 * (v @ b) * (v @ r) - 2 * w * (v @ rxb)
    grad_v = -2 * v * br + 2 * np.outer(v @ r, b) + 2 * np.outer(v @ b, r) - 2 * w[:, None] * rxb
    grad_w = 2 * w * br - 2 * (v @ rxb)
    return c, np.column_stack([grad_v, grad_w])


@dataclass(frozen=True)
class Forbidden:
    """Stay more than ``min_angle`` (Euler-axis angle) from ``q``: :math:`|q_b\\cdot q| \\le \\cos(\\theta_m/2)`."""

    name: str
    q: np.ndarray
    min_angle: float


@dataclass(frozen=True)
class AttitudeCase:
    """A slew in SI units; ``tf`` is ``None`` for minimum time.

    ``torque_max`` is the torque bound of each body axis (x, y, z), N m: given as one number or three, it is
    stored as a length-3 array. ``rate_max`` bounds every body-rate component, rad/s; None: no rate bound.
    """

    name: str
    inertia: np.ndarray
    torque_max: np.ndarray
    rate_max: float | None
    t0: float
    q0: np.ndarray
    w0: np.ndarray
    qf: np.ndarray
    wf: np.ndarray
    cones: tuple[PointingCone, ...] = ()
    forbidden: tuple[Forbidden, ...] = ()
    tf: float | None = None

    def __post_init__(self) -> None:
        box = np.broadcast_to(np.asarray(self.torque_max, dtype=float), (3,)).copy()
        box.setflags(write=False)
        object.__setattr__(self, "torque_max", box)

    @cached_property
    def inertia_inv(self) -> np.ndarray:
        return np.linalg.inv(self.inertia)


def rigid_body_dynamics(inertia: np.ndarray, inertia_inv: np.ndarray):
    """``f(x, u)`` and its Jacobian on stacked rows, for :func:`hermite_simpson_defects`."""

    def f(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        q, w = x[:, :4], x[:, 4:]
        qdot = 0.5 * quat_multiply(q, np.column_stack([w, np.zeros(len(w))]))
        wdot = (u - np.cross(w, w @ inertia.T)) @ inertia_inv.T
        return np.hstack([qdot, wdot])

    def jac(x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q, w = x[:, :4], x[:, 4:]
        k = len(x)
        F = np.zeros((k, NX, NX))
        F[:, :4, :4] = 0.5 * quat_rate_matrix(w)
        # q (x) [w, 0] = [q_w w + q_v x w, -q_v . w]  =>  d/dw = [q_w I + [q_v x]; -q_v^T]
        F[:, :3, 4:] = 0.5 * (q[:, 3, None, None] * np.eye(3) + skew(q[:, :3]))
        F[:, 3, 4:] = -0.5 * q[:, :3]
        # d(w x Iw)/dw = [w x] I - [Iw x]
        F[:, 4:, 4:] = -inertia_inv @ (skew(w) @ inertia - skew(w @ inertia.T))
        G = np.zeros((k, NX, NU))
        G[:, 4:, :] = inertia_inv
        return F, G

    return f, jac


def eigenaxis_guess(case: AttitudeCase, times: np.ndarray) -> np.ndarray:
    """Rest-to-rest eigenaxis slew with a cubic angle profile :math:`\\Phi(3\\tau^2 - 2\\tau^3)`, as node rows."""
    axis, angle = eigenaxis_rotation(case.q0, case.qf)
    T = times[-1] - times[0]
    tau = (times - times[0]) / T
    phi = angle * (3 * tau**2 - 2 * tau**3)
    rate = angle * (6 * tau - 6 * tau**2) / T
    accel = angle * (6 - 12 * tau) / T**2
    q = quat_multiply(case.q0, axis_angle_to_quat(axis, phi))
    w = rate[:, None] * axis
    u = euler_torque(case.inertia, w, accel[:, None] * axis)
    return np.hstack([q, w, u])


def eigenaxis_start(case: AttitudeCase, intervals: int) -> tuple[np.ndarray, float]:
    """The default SCP start: eigenaxis node rows over the case's :math:`t_f` (or :func:`eigenaxis_time_guess`)."""
    tf_guess = case.tf or eigenaxis_time_guess(case)
    return eigenaxis_guess(case, case.t0 + np.linspace(0.0, tf_guess, intervals + 1)), tf_guess


def eigenaxis_time_guess(case: AttitudeCase) -> float:
    """Duration of a rest-to-rest eigenaxis slew that roughly respects both boxes (a starting :math:`t_f`).

    The guess follows a cubic angle profile, whose peak acceleration :math:`6\\theta/T^2` is 1.5 times
    that of bang-bang timing; :math:`T = \\sqrt{6\\theta/a}` keeps it at the torque box (gyroscopic terms
    aside, which a principal-axis or symmetric body does not have). The acceleration :math:`a` about the
    eigenaxis :math:`e` is the largest the tightest axis allows, :math:`\\min_i u_{max,i} / |(I e)_i|`.
    """
    axis, angle = eigenaxis_rotation(case.q0, case.qf)
    accel = float(np.min(case.torque_max / np.maximum(np.abs(case.inertia @ axis), 1e-12)))
    rate_limited = 0.0 if case.rate_max is None else 1.5 * angle * max(np.abs(axis).max(), 1e-12) / case.rate_max
    return float(max(np.sqrt(6 * angle / accel), rate_limited, 1e-3))


def natural_rate(case: AttitudeCase, duration: float) -> float:
    """The body-rate scale of a slew: the peak rate :math:`1.5\\theta/T` of the eigenaxis slew over ``duration``.

    A magnitude of the problem itself, not of its bounds: an absent or generous rate bound leaves it alone,
    and a rate bound that binds already lengthened ``duration`` (:func:`eigenaxis_time_guess`) until the
    eigenaxis slew respects it. Boundary rates count too; the floor keeps a zero slew well scaled.
    """
    _, angle = eigenaxis_rotation(case.q0, case.qf)
    boundary = float(max(np.abs(case.w0).max(), np.abs(case.wf).max()))
    return max(1.5 * angle / max(duration, 1e-9), boundary, 1e-6)


RATE_SCALE_FACTOR = 3.0
"""The rate scale in units of :func:`natural_rate`. A time-optimal slew's rates peak above the smooth eigenaxis
guess (bang-bang about the eigenaxis: 4/3 of it; off the eigenaxis higher), so the trust region must let them
move that far. Measured on 3 random minimum-time slews, guo2011 (energy, time), feng2018 and the multi-cone
files: factor 1 left two random slews at the iteration limit, 3 one (the same one as the bound-based scale
did), 10 two; iteration counts otherwise within the noise of one another."""


class QuaternionProgram:
    """:class:`convexguid.scp.problem.NonconvexProgram` of the Hermite-Simpson transcription."""

    def __init__(self, case: AttitudeCase, intervals: int, guess: np.ndarray, tf_guess: float,
                 margin: float = 0.0) -> None:
        self.case, self.K, self.margin = case, intervals, margin
        self.free_time = case.tf is None
        self.num_nodes = intervals + 1
        self.num_variables = self.num_nodes * NODE + (1 if self.free_time else 0)
        self._guess = np.concatenate([guess.ravel(), [tf_guess] if self.free_time else []])
        self._tf_guess = tf_guess
        self._f, self._jac = rigid_body_dynamics(case.inertia, case.inertia_inv)
        self._patterns: dict[tuple[tuple[int, ...], bytes], tuple[np.ndarray, np.ndarray]] = {}
        self.objective_scale = tf_guess if self.free_time else self._guess_energy(guess)

    # --- layout ---
    def nodes(self, x: np.ndarray) -> np.ndarray:
        return x[: self.num_nodes * NODE].reshape(self.num_nodes, NODE)

    def final_time(self, x: np.ndarray) -> float:
        return float(x[-1]) if self.free_time else float(self.case.tf)

    def times(self, x: np.ndarray) -> np.ndarray:
        return self.case.t0 + np.linspace(0.0, self.final_time(x), self.num_nodes)

    def _cols(self, node: int, part: slice) -> np.ndarray:
        return node * NODE + np.arange(NODE)[part]

    # --- NonconvexProgram ---
    def initial_guess(self) -> np.ndarray:
        return self._guess.copy()

    @cached_property
    def rate_scale(self) -> float:
        """Scale of the body rates and of their defects, rad/s (:func:`natural_rate` over the guessed duration)."""
        return RATE_SCALE_FACTOR * natural_rate(self.case, self._tf_guess)

    def variable_scale(self) -> np.ndarray:
        c = self.case
        node = np.concatenate([np.ones(4), np.full(3, self.rate_scale), c.torque_max])
        return np.concatenate([np.tile(node, self.num_nodes), [self._tf_guess] if self.free_time else []])

    @cached_property
    def _energy_rows(self) -> sp.csr_matrix | None:
        """Simpson's rule for :math:`\\int|u|^2`: rows :math:`\\sqrt{h/6}\\,u_k` (twice at interior nodes) and
        :math:`\\sqrt{4h/6}\\,(u_k + u_{k+1})/2`; weights folded into :meth:`residual_weights`."""
        if self.free_time:
            return None
        rows, cols, vals = [], [], []
        r = 0
        for k in range(self.num_nodes):
            for i in range(3):
                rows.append(r + i)
                cols.append(k * NODE + NX + i)
                vals.append(1.0)
            r += 3
        for k in range(self.K):
            for i in range(3):
                for node in (k, k + 1):
                    rows.append(r + i)
                    cols.append(node * NODE + NX + i)
                    vals.append(0.5)
            r += 3
        return sp.coo_matrix((vals, (rows, cols)), shape=(r, self.num_variables))

    def _simpson_weights(self) -> np.ndarray:
        h = self.case.tf / self.K
        node_w = np.full(self.num_nodes, 2 * h / 6)
        node_w[[0, -1]] = h / 6
        return np.concatenate([np.repeat(node_w, 3), np.full(3 * self.K, 4 * h / 6)])

    def _guess_energy(self, guess: np.ndarray) -> float:
        """Energy of the initial guess (at least 1e-3 of the energy with every torque at the largest axis bound)."""
        energy = float(self._simpson_weights() @ (self._energy_rows @ guess.ravel()) ** 2)
        return max(energy, 1e-3 * 3 * float(np.max(self.case.torque_max))**2 * self.case.tf)

    def residual_weights(self) -> np.ndarray:
        return np.zeros(0) if self.free_time else self._simpson_weights()

    def linear_cost(self) -> np.ndarray:
        c = np.zeros(self.num_variables)
        if self.free_time:
            c[-1] = 1.0
        return c

    @cached_property
    def _linear(self) -> LinearConstraints:
        """Boundary conditions, and the rate and torque boxes at the nodes.

        The start is the whole state :math:`(q_0, \\omega_0)`. The end is the rate and the attitude error's vector
        part, :math:`\\operatorname{vec}(q_f^{-1} \\otimes q_K) = 0`: three rows, linear in :math:`q_K`. Fixing all four
        components of :math:`q_K` would fix its norm as well, which the dynamics already carry from :math:`q_0`
        (to the transcription's accuracy): one nearly dependent row, whose multiplier grows without bound as the
        iterates converge.
        """
        c, n = self.case, self.num_variables
        A = np.zeros((2 * NX - 1, n))
        A[np.arange(NX), self._cols(0, slice(0, NX))] = 1.0
        error = np.array([quat_multiply(quat_conjugate(c.qf), e)[:3] for e in np.eye(4)]).T
        A[NX: NX + 3][:, self._cols(self.K, slice(0, 4))] = error
        A[NX + 3 + np.arange(3), self._cols(self.K, slice(4, NX))] = 1.0
        b = np.concatenate([c.q0, c.w0, np.zeros(3), c.wf])
        # the rate and torque boxes, +-1 per row: built sparse (a dense matrix grows as the square of the nodes)
        cols, signs, h = [], [], []
        for k in range(self.num_nodes):
            rate_box = ((slice(4, 7), np.full(3, c.rate_max)),) if c.rate_max is not None else ()
            for part, bound in (*rate_box, (slice(7, 10), c.torque_max)):
                for sign in (1.0, -1.0):
                    cols.append(self._cols(k, part))
                    signs.append(np.full(3, sign))
                    h.append(bound)
        if self.free_time:
            cols.append([n - 1])
            signs.append([-1.0])
            h.append([-1e-3 * self._tf_guess])
        cols, signs = np.concatenate(cols), np.concatenate(signs)
        G = sp.coo_matrix((signs, (np.arange(cols.size), cols)), shape=(cols.size, n))
        return LinearConstraints(A, b, G, np.concatenate(h))

    def linear_constraints(self) -> LinearConstraints:
        return self._linear

    def output_constraints(self) -> OutputConstraints:
        return OutputConstraints.none(0 if self.free_time else self._energy_rows.shape[0])

    def size(self) -> ProgramSize:
        lin = self.linear_constraints()
        rates = 6 * self.K if self.case.rate_max is not None else 0
        n_path = (self.num_nodes + self.K) * (len(self.case.cones) + 2 * len(self.case.forbidden)) + rates
        return ProgramSize(self.num_variables, lin.A.shape[0] + NX * self.K, lin.G.shape[0] + n_path)

    def evaluate(self, x: np.ndarray, jacobians: bool = True) -> Evaluation:
        nodes = self.nodes(x)
        if self.free_time:
            residuals, res_jac = np.zeros(0), sp.coo_matrix((0, self.num_variables))
        else:
            residuals, res_jac = self._energy_rows @ x, self._energy_rows
        K, tf = self.K, self.final_time(x)
        xs, us = nodes[:, :NX], nodes[:, NX:]
        hs = hermite_simpson_defects(self._f, self._jac, xs[:-1], us[:-1], xs[1:], us[1:], np.full(K, tf / K))
        mid = hs.midpoint
        mid_jac = self._interval_local(mid) if jacobians else None
        inequalities = self._cone_blocks(nodes[:, :4], mid.values[:, :4], mid_jac, jacobians)
        inequalities += self._forbidden_blocks(nodes[:, :4], mid.values[:, :4], mid_jac, jacobians)
        if self.case.rate_max is not None:
            inequalities += (self._midpoint_rate_block(mid.values[:, 4:], mid_jac, jacobians),)
        return Evaluation(residuals, res_jac if jacobians else None, inequalities, (self._defects(hs, jacobians),))

    # --- constraint blocks ---
    def _interval_local(self, parts) -> np.ndarray:
        """Per-interval Jacobian ``(K, rows, cols)`` over [node k, node k+1, t_f] from HS partials ``parts``."""
        blocks = [np.concatenate([parts.d_x0, parts.d_u0, parts.d_x1, parts.d_u1], axis=2)]
        if self.free_time:
            blocks.append(parts.d_h[:, :, None] / self.K)
        return np.concatenate(blocks, axis=2)

    @cached_property
    def _structure(self) -> tuple[np.ndarray, np.ndarray]:
        """Masks ``(rows, cols)`` of the entries of the per-interval defect and midpoint-state Jacobians that can
        be nonzero.

        Read from the Hermite-Simpson partials at a random point: an entry that is not identically zero is
        nonzero there with probability one. The rate defects do not depend on the quaternions, for instance,
        and ``q' = Omega(w) q / 2`` has no diagonal. Keeping only these entries keeps explicit zeros out of the
        convex solver's KKT system (about a third of its factorisation time on the multi-cone case).
        """
        rng = np.random.default_rng(20110601)
        K = self.K
        xs, us = rng.standard_normal((2, K, NX)), rng.standard_normal((2, K, NU))
        hs = hermite_simpson_defects(self._f, self._jac, xs[0], us[0], xs[1], us[1], rng.uniform(0.5, 2.0, K))
        return (np.any(self._interval_local(hs) != 0, axis=0),
                np.any(self._interval_local(hs.midpoint) != 0, axis=0))

    def _interval_pattern(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) of the entries in ``mask`` (per-interval rows x [node k, node k+1, t_f]), every interval."""
        key = (mask.shape, mask.tobytes())
        if key in self._patterns:
            return self._patterns[key]
        c = np.concatenate([np.arange(2 * NODE), [2 * NODE] if self.free_time else []]).astype(int)
        r_local, c_local = np.nonzero(mask)
        offsets = np.arange(self.K)[:, None]
        rows = (offsets * mask.shape[0] + r_local).ravel()
        cols = np.where(c[c_local] < 2 * NODE, offsets * NODE + c[c_local], self.num_variables - 1).ravel()
        self._patterns[key] = rows, cols
        return self._patterns[key]

    def _interval_matrix(self, local: np.ndarray, mask: np.ndarray) -> sp.coo_matrix:
        """The per-interval Jacobians ``local`` (``(K, rows, cols)``) as a sparse matrix of the entries in ``mask``."""
        rows, cols = self._interval_pattern(mask)
        shape = (self.K * local.shape[1], self.num_variables)
        return sp.coo_matrix((local[:, mask].ravel(), (rows, cols)), shape=shape)

    def _quaternion_rows(self, count: int) -> np.ndarray:
        """Mask of ``count`` rows that each combine the midpoint quaternion's partials (a cone or a dot product)."""
        return np.repeat(np.any(self._structure[1][:4], axis=0, keepdims=True), count, axis=0)

    @cached_property
    def _defect_scale(self) -> np.ndarray:
        return np.tile(1.0 / np.concatenate([np.ones(4), np.full(3, self.rate_scale)]), self.K)

    def _defects(self, hs, jacobians: bool) -> ConstraintBlock:
        """Hermite-Simpson defects, scaled by the state scales (quaternion 1, rate :attr:`rate_scale`)."""
        values = hs.values.ravel() * self._defect_scale
        jac = None
        if jacobians:
            jac = self._interval_matrix(self._interval_local(hs) * self._defect_scale.reshape(self.K, NX, 1),
                                        self._structure[0])
        return ConstraintBlock("dynamics_defects", values, jac, "scaled")

    def _midpoint_rate_block(self, w_mid: np.ndarray, mid_jac: np.ndarray | None, jacobians: bool) -> ConstraintBlock:
        """The rate box at the interval midpoints, :math:`\\pm\\omega_c/\\omega_{max} - 1 \\le 0` (nodes: hard rows)."""
        w_max = self.case.rate_max
        values = np.concatenate([w_mid, -w_mid], axis=1).ravel() / w_max - 1.0
        jac = None
        if jacobians:
            d_w = mid_jac[:, 4:7, :] / w_max
            rate = self._structure[1][4:7]
            jac = self._interval_matrix(np.concatenate([d_w, -d_w], axis=1), np.concatenate([rate, rate]))
        return ConstraintBlock("rate_midpoints", values, jac, "of rate_max")

    def _forbidden_blocks(self, q: np.ndarray, q_mid: np.ndarray, mid_jac: np.ndarray | None,
                          jacobians: bool) -> tuple[ConstraintBlock, ...]:
        """:math:`\\pm q_b \\cdot q - \\cos((\\theta_m + m)/2) \\le 0` per forbidden attitude, nodes and midpoints.

        Linear in :math:`q`, but penalized like the cones rather than hard: an initial guess may pass
        through the forbidden attitude (the eigenaxis slew of Guo et al.'s case does), and a hard row
        would make the first subproblem infeasible inside the trust region.
        """
        blocks = []
        n1 = self.num_nodes
        rows = np.repeat(np.arange(2 * n1), 4)
        cols = np.tile(np.arange(n1)[:, None] * NODE + np.arange(4), (2, 1)).ravel()
        for fb in self.case.forbidden:
            bound = np.cos(min(np.pi, fb.min_angle + self.margin) / 2)
            signed = np.array([1.0, -1.0])
            values = (signed[:, None] * (q @ fb.q)[None, :]).ravel() - bound
            values_mid = (signed[None, :] * (q_mid @ fb.q)[:, None]).ravel() - bound
            jac = jac_mid = None
            if jacobians:
                jac = sp.coo_matrix((np.outer(np.repeat(signed, n1), fb.q).ravel(), (rows, cols)),
                                    shape=(2 * n1, self.num_variables))
                d_dot = np.einsum("j,kjc->kc", fb.q, mid_jac[:, :4, :])
                jac_mid = self._interval_matrix(signed[None, :, None] * d_dot[:, None, :], self._quaternion_rows(2))
            blocks.append(ConstraintBlock(f"forbidden_{fb.name}", values, jac, "cos"))
            blocks.append(ConstraintBlock(f"forbidden_{fb.name}_midpoints", values_mid, jac_mid, "cos"))
        return tuple(blocks)

    def _cone_blocks(self, q: np.ndarray, q_mid: np.ndarray, mid_jac: np.ndarray | None,
                     jacobians: bool) -> tuple[ConstraintBlock, ...]:
        """Each cone at the nodes and at the interval midpoints (values in cosine units)."""
        blocks = []
        n1 = self.num_nodes
        rows = np.repeat(np.arange(n1), 4)
        cols = (np.arange(n1)[:, None] * NODE + np.arange(4)).ravel()
        for cone in self.case.cones:
            kind = cone.kind
            if cone.keep_out:
                bound, sign = np.cos(min(np.pi, cone.half_angle_rad + self.margin)), 1.0
            else:
                bound, sign = np.cos(max(0.0, cone.half_angle_rad - self.margin)), -1.0
            c, grad = cone_cosine(cone, q)
            c_mid, grad_mid = cone_cosine(cone, q_mid)
            jac = jac_mid = None
            if jacobians:
                jac = sp.coo_matrix((sign * grad.ravel(), (rows, cols)), shape=(n1, self.num_variables))
                jac_mid = self._interval_matrix(sign * np.einsum("kj,kjc->kc", grad_mid, mid_jac[:, :4, :])[:, None],
                                                self._quaternion_rows(1))
            blocks.append(ConstraintBlock(f"{kind}_{cone.name}", sign * (c - bound), jac, "cos"))
            blocks.append(ConstraintBlock(f"{kind}_{cone.name}_midpoints", sign * (c_mid - bound), jac_mid, "cos"))
        return tuple(blocks)

    # --- reading a solution ---
    def torque_command(self, x: np.ndarray) -> LinearTorque:
        """Linear interpolation of the node torques (the transcription's control model); kinks at the nodes."""
        return LinearTorque(self.times(x), self.nodes(x)[:, NX:])
