r"""Path-transfer fast attitude planner under keep-out cones and torque/rate boxes (Wang, Xu, Li; seed 003).

Three stages (paper Sec. 2): a *reference path* (eigenaxis slew, eqs. 15-21), a *relaxed path* whose node
count makes the torque and rate boxes hold (eqs. 22-28), and a *path transfer* walk that evaluates every
keep-out cone with :math:`f = e^{\cos\alpha - \cos\bar\theta} - 1` (eq. 31) and applies one of three actions
(eq. 32): none, circumvent (rotate about the cone axis, eqs. 33-37), back off and circumvent. The way-points
are joined by eigenaxis legs, each flown rest to rest with a bounded time law.

Quaternions are scalar-last ``[x, y, z, w]``, Hamilton product, body relative to inertial; rates are body
rates in rad/s. The keep-out constraint is :math:`b^T C_{BI}(q) r_i \le \cos\bar\theta_i` (eq. 8).

Reconstructions (the extracted text lost eqs. 1-37 and Table 1; each choice below is ours):

R1 (eqs. 16-21) error quaternion :math:`q_e = q_0^* \otimes q_f`, negated when :math:`q_{e,w} < 0` (the
   "unwinding" fix of eqs. 18-19), axis :math:`e = q_{e,v}/|q_{e,v}|` (body frame), angle
   :math:`\Phi = 2\,\mathrm{atan2}(|q_{e,v}|, q_{e,w})`; nodes :math:`q(k) = q_0 \otimes \delta q^{k-1}`.
R2 (time law; absent from the text) each leg uses :math:`\theta(t)` with a trapezoidal rate (ramp fraction
   f of T at each end). For a body-fixed axis :math:`\omega = \dot\theta e` and
   :math:`u = I e\,\ddot\theta + \dot\theta^2\, e\times I e` (full inertia, gyroscopic term included), so
   :math:`\max|\omega_i| = \Phi\max|e_i|/((1-f)T)` and
   :math:`\max|u_i| = K(f)/T^2,\ K(f) = \max_i(|(Ie)_i|\Phi/(f(1-f)) + |(e\times Ie)_i|\Phi^2/(1-f)^2)`
   (exact peaks of the two ramps and the coast). f is chosen on a grid to minimise the shortest feasible T.
R3 (eq. 23) :math:`J_u(n) = \max|u_i|/u_{max} - 1`, :math:`J_\omega(n) = \max|\omega_i|/\omega_{max} - 1`
   on the reference path of n nodes spaced by the node period :math:`\Delta t`.
R4 (eqs. 24-25) the text says torque and rate act on the node spacing "by the same law, to different
   degrees": under time scaling :math:`\omega \propto 1/N` and :math:`u \propto 1/N^2` exactly, so
   :math:`J = \max(J_\omega, \sqrt{1 + J_u} - 1)` and :math:`N = \lceil\lambda (J + 1)(n - 1)\rceil + 1`,
   with :math:`\lambda \ge 1` the paper's weight. With :math:`\lambda = 1` N is the smallest feasible count.
R5 (eq. 26-28) the walk evaluates nodes uniformly spaced in angle, :math:`\Phi/(N-1)`; the trajectory
   nodes are uniform in time (:math:`\Delta t`), so each leg lasts :math:`(N-1)\Delta t`.
R6 (eqs. 31-32) f < 0 outside the cone, f > 0 inside (the text's sign). A cone is *threatened* at the first
   sample where the boresight is inside the neighbourhood :math:`\alpha < \bar\theta + m + \nu`, approaching
   (f increasing) and the rest of the leg would get closer than :math:`\bar\theta + m` (margin m,
   neighbourhood width :math:`\nu`). Let node k close that sample's node interval. If no sample of the
   interval is closer than :math:`\bar\theta + m` (to any cone): circumvent from node k; otherwise (too
   close or inside, f > 0 included) back off to node k-1 and circumvent from there.
R7 (eqs. 33-35) the text: rotate "about an axis" built from h, "the direction vector at the node in body
   axes" of an inertial vector (eq. 35). We read :math:`h = C_{BI}(q_s) r` (cone axis in body axes) and the
   rotation :math:`q_s \otimes [\sin(\phi/2) h, \cos(\phi/2)]`, which keeps the boresight-to-cone angle
   constant: the boresight slides round the cone at its clearance (the only reading in which the rotation
   itself provably respects the cone). :math:`|\phi|` grows by ``arc_step_rad`` (both senses, up to pi)
   until the arc keeps every other cone's margin and the eigenaxis rejoin to :math:`q_f` keeps
   :math:`\bar\theta + m` from this cone (ties: fewer other cones threatened, then less total angle); the
   walk restarts from the arc end (eqs. 36-37 join the transfer leg to the relaxed path after it). We rejoin
   :math:`q_f` rather than the old path's exit node: the arc also rolls the body, so we do not expect that
   node to be nearer (not measured).
R8 margins: for a cone whose start or end boresight lies within 2m of its edge the required margin is
   halved clearance, :math:`m_i = \min(m, (\alpha_0-\bar\theta)/2, (\alpha_f-\bar\theta)/2)`.

Legs stop at every way-point (rest to rest), and going round a cone that the slew crosses near its centre
takes large rotations (seed-003 scenario: 34 deg, a 114 deg arc, a 180 deg rejoin; 113 s against 42.5 s for
the infeasible eigenaxis slew). It is a feasible baseline and initial guess, not a time-optimal plan.

References
----------
Wang Z., Xu R., Li C., fast large-angle attitude maneuver planning based on a path-transfer strategy,
Beijing Institute of Technology (seed text 003; journal details were not in the extracted text), eqs. (8),
(12)-(13), (15)-(37). Hablani H. B., "Attitude commands avoiding bright objects and maintaining communication
with ground station", J. Guid. Control Dyn. 22(6), 1999 (tangent paths around a cone, cited in the paper).
"""

from __future__ import annotations

import math
import time
from bisect import bisect_right
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from convexguid.checks import inertia_matrix, positive, unit_vector
from convexguid.dynamics.rigid_body import euler_torque
from convexguid.dynamics.torque import TorqueCommand
from convexguid.errors import ConvexGuidError, SpecError
from convexguid.geometry import PointingCone, eigenaxis_path, eigenaxis_rotation
from convexguid.rotations import axis_angle_to_quat, quat_multiply, quat_rotate, quat_to_dcm

__all__ = [
    "ACTIONS", "PathSegment", "PathTransferError", "PathTransferProblem",
    "PathTransferResult", "bound_evaluation", "eigenaxis_path", "eigenaxis_rotation", "multicone_scenario",
    "plan_path_transfer", "pointing_evaluation", "relaxed_node_count",
]

ACTIONS = ("none", "circumvent", "back_off_circumvent")
"""Transfer action set of eq. (32), ordered by severity."""

_RAMP_GRID = np.linspace(0.005, 0.5, 400)


class PathTransferError(ConvexGuidError, RuntimeError):
    """The walk found no circumvent arc, or needed more than ``max_actions`` actions."""


def pointing_evaluation(angle: ArrayLike, half_angle: ArrayLike) -> NDArray:
    r"""Pointing-constraint evaluation :math:`f = \exp(\cos\alpha - \cos\bar\theta) - 1` (paper eq. 31).

    ``angle`` is the boresight-to-cone-axis angle :math:`\alpha`, ``half_angle`` :math:`\bar\theta` (rad).
    f < 0: outside the cone (constraint met); f > 0: inside, larger is deeper; f is decreasing in
    :math:`\alpha` on :math:`[0, \pi]`.
    """
    return np.expm1(np.cos(angle) - np.cos(half_angle))


def _torque_coefficient(inertia: NDArray, axis: NDArray, angle: float, ramp: NDArray) -> NDArray:
    """K(f) of R2: the peak body torque of a leg of duration T is K(f) / T**2 (vectorised over f)."""
    i_e = inertia @ axis
    p, g = np.abs(i_e)[:, None], np.abs(np.cross(axis, i_e))[:, None]
    return np.max(p * angle / (ramp * (1 - ramp)) + g * angle**2 / (1 - ramp) ** 2, axis=0)


def bound_evaluation(inertia: NDArray, axis: NDArray, angle: float, ramp: float, duration: float,
                     torque_max: float, rate_max: float) -> tuple[float, float]:
    r"""Torque and rate evaluation functions :math:`(J_u, J_\omega)` of eq. (23) (reconstruction R3).

    For an eigenaxis leg about the body axis ``axis`` through ``angle`` rad flown in ``duration`` s with the
    trapezoidal law of ramp fraction ``ramp`` (R2): :math:`J > 0` means the bound is broken.
    """
    j_rate = angle * np.max(np.abs(axis)) / ((1 - ramp) * duration * rate_max) - 1
    j_torque = _torque_coefficient(inertia, axis, angle, np.array([ramp]))[0] / (duration**2 * torque_max) - 1
    return float(j_torque), float(j_rate)


def relaxed_node_count(j_torque: float, j_rate: float, reference_nodes: int, weight: float = 1.0) -> int:
    r"""Relaxed node count :math:`N = \lceil\lambda(J+1)(n-1)\rceil + 1`, :math:`J = \max(J_\omega,
    \sqrt{1+J_u}-1)` (eqs. 24-25, reconstruction R4)."""
    scale = max(1 + j_rate, math.sqrt(max(1 + j_torque, 0.0)))
    return max(2, math.ceil(weight * scale * (reference_nodes - 1)) + 1)


@dataclass(frozen=True, eq=False)
class PathTransferProblem:
    """Rest-to-rest planning problem and planner settings (SI units, rad; quaternions scalar-last, B rel. I).

    Parameters
    ----------
    inertia : (3, 3) symmetric positive definite inertia, kg m^2.
    boresight_body : camera boresight b in body axes (normalised here).
    q0, qf : initial and final attitude (normalised here).
    cones : keep-out :class:`~convexguid.geometry.PointingCone` s; the boresight must stay outside every one
        (eq. 8). Only their inertial directions and half-angles are used: the planner points ``boresight_body``.
    torque_max, rate_max : per-axis boxes :math:`|u_i| \\le u_{max}`, :math:`|\\omega_i| \\le \\omega_{max}`
        (eqs. 12-13), N m and rad/s.
    margin_rad : clearance m kept from every cone edge (R6, R8).
    neighborhood_rad : width :math:`\\nu` of the detection band beyond the margin (R6).
    node_period_s : time between trajectory nodes :math:`\\Delta t` (R5).
    reference_nodes : node count n of the reference path evaluated in eq. (25).
    node_weight : weight :math:`\\lambda \\ge 1` of eq. (25).
    check_step_rad : largest angular step of the dense cone checks between walk nodes.
    arc_step_rad : increment of the circumvent angle search (R7).
    max_actions : most transfer actions before PathTransferError.
    """

    inertia: NDArray
    boresight_body: NDArray
    q0: NDArray
    qf: NDArray
    cones: tuple[PointingCone, ...]
    torque_max: float
    rate_max: float
    margin_rad: float = math.radians(2.0)
    neighborhood_rad: float = math.radians(3.0)
    node_period_s: float = 0.5
    reference_nodes: int = 51
    node_weight: float = 1.0
    check_step_rad: float = math.radians(0.25)
    arc_step_rad: float = math.radians(1.0)
    max_actions: int = 12

    def __post_init__(self) -> None:
        object.__setattr__(self, "inertia", inertia_matrix(self.inertia))
        object.__setattr__(self, "boresight_body", unit_vector("boresight_body", self.boresight_body, 3))
        object.__setattr__(self, "q0", unit_vector("q0", self.q0, 4))
        object.__setattr__(self, "qf", unit_vector("qf", self.qf, 4))
        object.__setattr__(self, "cones", tuple(self.cones))
        if not all(isinstance(c, PointingCone) and c.keep_out for c in self.cones):
            raise SpecError("cones must be keep-out PointingCone instances, got "
                            f"{[(type(c).__name__, getattr(c, 'keep_out', None)) for c in self.cones]}")
        for name in ("torque_max", "rate_max", "neighborhood_rad", "node_period_s", "node_weight",
                     "check_step_rad", "arc_step_rad"):
            positive(name, getattr(self, name))
        if not (np.isfinite(self.margin_rad) and self.margin_rad >= 0):
            raise SpecError(f"margin_rad must be a non-negative finite angle, got {self.margin_rad!r}")
        if self.node_weight < 1 or int(self.reference_nodes) != self.reference_nodes or self.reference_nodes < 2 \
                or self.max_actions < 0:
            raise SpecError("node_weight must be >= 1, reference_nodes >= 2 and max_actions >= 0, got "
                            f"{self.node_weight!r}, {self.reference_nodes!r}, {self.max_actions!r}")
        for label, q in (("initial", self.q0), ("final", self.qf)):
            angles = self.cone_angles(q[None])[0]
            for cone, a in zip(self.cones, angles, strict=True):
                if a <= cone.half_angle_rad:
                    raise SpecError(f"{label} boresight is inside cone {cone.name!r}: {math.degrees(a):.3f} deg "
                                    f"from its axis, half-angle {math.degrees(cone.half_angle_rad):.3f} deg")

    @property
    def half_angles(self) -> NDArray:
        """Cone half-angles, rad, shape ``(C,)``."""
        return np.array([c.half_angle_rad for c in self.cones])

    def cone_angles(self, q: NDArray) -> NDArray:
        r"""Angles :math:`\arccos(b^T C_{BI}(q) r_i)` (rad) for quaternions ``(M, 4)``; shape ``(M, C)``."""
        if not self.cones:
            return np.zeros((len(q), 0))
        dirs = np.stack([c.inertial_dir for c in self.cones])
        cosines = np.einsum("i,mij,cj->mc", self.boresight_body, quat_to_dcm(q), dirs)
        return np.arccos(np.clip(cosines, -1.0, 1.0))

    def margins(self) -> NDArray:
        """Required clearance per cone, R8: ``min(m, (a0 - half)/2, (af - half)/2)``."""
        ends = self.cone_angles(np.stack([self.q0, self.qf])) - self.half_angles
        return np.minimum(self.margin_rad, 0.5 * ends.min(axis=0))


@dataclass(frozen=True, eq=False)
class PathSegment:
    """Eigenaxis leg flown rest to rest: :math:`q(t) = q_s \\otimes [\\sin(\\theta/2) e, \\cos(\\theta/2)]`.

    ``ramp_fraction`` is f of the trapezoidal law (R2); ``nodes`` the relaxed node count of eq. (25);
    ``duration_s = (nodes - 1) * node_period``; ``t_start_s`` the leg's start on the trajectory clock.
    """

    q_start: NDArray
    axis_body: NDArray
    angle_rad: float
    ramp_fraction: float
    nodes: int
    duration_s: float
    t_start_s: float


def _leg(problem: PathTransferProblem, q_start: NDArray, axis: NDArray, angle: float,
         t_start: float = 0.0) -> PathSegment:
    """Time law of one leg (R2-R4): best ramp fraction, then the relaxed node count of eq. (25)."""
    if angle <= 1e-12:
        return PathSegment(q_start, axis, 0.0, 0.5, 1, 0.0, t_start)
    t_rate = angle * np.max(np.abs(axis)) / ((1 - _RAMP_GRID) * problem.rate_max)
    t_torque = np.sqrt(_torque_coefficient(problem.inertia, axis, angle, _RAMP_GRID) / problem.torque_max)
    ramp = float(_RAMP_GRID[np.argmin(np.maximum(t_rate, t_torque))])
    t_ref = (problem.reference_nodes - 1) * problem.node_period_s
    j_torque, j_rate = bound_evaluation(problem.inertia, axis, angle, ramp, t_ref, problem.torque_max,
                                        problem.rate_max)
    nodes = relaxed_node_count(j_torque, j_rate, problem.reference_nodes, problem.node_weight)
    return PathSegment(q_start, axis, angle, ramp, nodes, (nodes - 1) * problem.node_period_s, t_start)


def _dense(q_start: NDArray, axis: NDArray, angle: float, step: float, intervals: int = 1) -> NDArray:
    """Attitudes along a leg: ``intervals`` equal node intervals, each cut so the step is at most ``step``."""
    per = max(1, math.ceil(angle / (intervals * step)))
    return quat_multiply(q_start, axis_angle_to_quat(axis, np.linspace(0.0, angle, intervals * per + 1)))


def _levels(problem: PathTransferProblem) -> tuple[NDArray, NDArray, NDArray]:
    """Per cone (R6, R8): clearance floor (half-angle + margin), and f at the band edge and at the floor."""
    half = problem.half_angles
    floor = half + problem.margins()
    return floor, pointing_evaluation(floor + problem.neighborhood_rad, half), pointing_evaluation(floor, half)


def _first_threat(f: NDArray, f_band: NDArray, f_floor: NDArray, per: int) -> tuple[int, int, bool] | None:
    """(cone, closing node k, too close) of the first threatened sample of a leg, or None (R6)."""
    future = np.maximum.accumulate(f[::-1], axis=0)[::-1]
    approaching = np.zeros_like(f, dtype=bool)
    approaching[1:] = f[1:] > f[:-1]
    hit = (f > f_band) & approaching & (future > f_floor)
    rows = np.flatnonzero(hit.any(axis=1))
    if rows.size == 0:
        return None
    j = int(rows[0])
    cone = int(np.argmax(np.where(hit[j], f[j], -np.inf)))
    k = -(-j // per)
    return cone, k, bool(np.any(f[(k - 1) * per + 1:k * per + 1] > f_floor))


def _circumvent(problem: PathTransferProblem, floor: NDArray, q_s: NDArray, cone: int) -> tuple[NDArray, float]:
    """Axis (body) and angle of the arc about the cone axis h = C_BI(q_s) r (eqs. 33-35, R7).

    The rejoin must clear this cone by 1e-4 rad more than the floor so that the walk, sampling it on its
    own node grid, does not flag the same cone again.
    """
    h = quat_rotate(q_s, problem.cones[cone].inertial_dir)
    others = np.arange(len(problem.cones)) != cone
    for phi in np.arange(1, int((math.pi - 1e-6) / problem.arc_step_rad) + 1) * problem.arc_step_rad:
        best: tuple[tuple[int, float], NDArray] | None = None
        for axis in (h, -h):
            arc = _dense(q_s, axis, phi, problem.check_step_rad)
            if np.any(problem.cone_angles(arc)[:, others] < floor[others]):
                continue
            r_axis, r_angle = eigenaxis_rotation(arc[-1], problem.qf)
            rejoin = problem.cone_angles(_dense(arc[-1], r_axis, r_angle, problem.check_step_rad)).min(axis=0)
            if rejoin[cone] < floor[cone] + 1e-4:
                continue
            cost = (int(np.sum(rejoin < floor)), phi + r_angle)
            if best is None or cost < best[0]:
                best = (cost, axis)
        if best is not None:
            return best[1], float(phi)
    raise PathTransferError(f"no circumvent arc around cone {problem.cones[cone].name!r} clears the other cones")


def _walk(problem: PathTransferProblem) -> tuple[list[tuple[NDArray, NDArray, float]], list[tuple[int, str]]]:
    """Path-transfer walk (eqs. 29-37): eigenaxis legs and the (cone, action) log."""
    floor, f_band, f_floor = _levels(problem)
    q_c, legs, log = problem.q0, [], []
    for _ in range(problem.max_actions + 1):
        axis, angle = eigenaxis_rotation(q_c, problem.qf)
        if angle <= 1e-12:
            return legs, log
        nodes = _leg(problem, q_c, axis, angle).nodes
        samples = _dense(q_c, axis, angle, problem.check_step_rad, nodes - 1)
        per = (len(samples) - 1) // (nodes - 1)
        f = pointing_evaluation(problem.cone_angles(samples), problem.half_angles)
        threat = _first_threat(f, f_band, f_floor, per)
        if threat is None:
            legs.append((q_c, axis, angle))
            return legs, log
        cone, k, too_close = threat
        k_start = k - 1 if too_close else k
        q_s = samples[k_start * per]
        legs.append((q_c, axis, angle * k_start / (nodes - 1)))
        arc_axis, phi = _circumvent(problem, floor, q_s, cone)
        legs.append((q_s, arc_axis, phi))
        log.append((cone, ACTIONS[2] if too_close else ACTIONS[1]))
        q_c = quat_multiply(q_s, axis_angle_to_quat(arc_axis, phi))
    raise PathTransferError(f"path transfer needed more than max_actions={problem.max_actions} actions")


def _trapezoid(local: NDArray, seg_T: NDArray, ramp: NDArray, angle: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Angle, rate and acceleration of the trapezoidal-rate law (R2) at local times in [0, T]."""
    tr = ramp * seg_T
    v = angle / np.where(seg_T > 0, seg_T * (1 - ramp), 1.0)
    a = v / np.where(tr > 0, tr, 1.0)
    t = np.clip(local, 0.0, seg_T)
    up, down = t < tr, t > seg_T - tr
    coast = 0.5 * v * tr + v * (t - tr)
    theta = np.where(up, 0.5 * a * t**2, np.where(down, angle - 0.5 * a * (seg_T - t) ** 2, coast))
    rate = np.where(up, a * t, np.where(down, a * (seg_T - t), v))
    accel = np.where(up, a, np.where(down, -a, 0.0))
    return theta, rate, accel


@dataclass(frozen=True, eq=False)
class PathTransferResult:
    r"""Planned rest-to-rest trajectory (quaternions scalar-last, body relative to inertial).

    ``waypoints`` are q0, the transfer way-points and the final attitude (sign-continuous, so the last one is
    :math:`\pm q_f`); ``segments`` the timed legs between them.
    ``t, q, omega, torque`` are on the node grid (period ``node_period_s``); :meth:`sample` evaluates the
    closed-form law on any grid. ``actions`` holds one of :data:`ACTIONS` per cone (the most severe action
    applied to it); ``action_log`` lists ``(cone name, action)`` in walk order. ``cone_min_angle_deg`` and
    ``reference_min_angle_deg`` are the per-cone smallest boresight angles of the plan and of the eigenaxis
    slew (dense geometric check); ``min_cone_margin_deg`` is the smallest angle minus half-angle of the plan.
    """

    waypoints: NDArray
    actions: tuple[str, ...]
    action_log: tuple[tuple[str, str], ...]
    segments: tuple[PathSegment, ...]
    t: NDArray
    q: NDArray
    omega: NDArray
    torque: NDArray
    maneuver_time_s: float
    planning_time_s: float
    min_cone_margin_deg: float
    cone_min_angle_deg: tuple[float, ...]
    reference_min_angle_deg: tuple[float, ...]
    reference_maneuver_time_s: float
    inertia: NDArray = field(repr=False)

    def sample(self, t: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
        """Attitude ``(M, 4)``, body rate ``(M, 3)`` and torque ``(M, 3)`` at times ``t`` (scalar -> 1-D).

        Before 0 and after the maneuver the body rests at the end attitudes with zero torque; at a
        way-point the next leg's torque is returned (right-continuous), except at the final time.
        """
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        segs = self.segments
        if not segs:
            out = (np.tile(self.waypoints[0], (tt.size, 1)), np.zeros((tt.size, 3)), np.zeros((tt.size, 3)))
        else:
            starts = np.array([s.t_start_s for s in segs])
            idx = np.clip(np.searchsorted(starts, tt, side="right") - 1, 0, len(segs) - 1)
            get = np.array([[s.duration_s, s.ramp_fraction, s.angle_rad] for s in segs])[idx]
            axis = np.stack([s.axis_body for s in segs])[idx]
            theta, rate, accel = _trapezoid(tt - starts[idx], get[:, 0], get[:, 1], get[:, 2])
            accel = np.where((tt < 0) | (tt > self.maneuver_time_s), 0.0, accel)
            q = quat_multiply(np.stack([s.q_start for s in segs])[idx], axis_angle_to_quat(axis, theta))
            omega = rate[:, None] * axis
            out = (q, omega, euler_torque(self.inertia, omega, accel[:, None] * axis))
        return tuple(o[0] for o in out) if np.ndim(t) == 0 else out

    def torque_at(self, t: float) -> NDArray:
        r"""Closed-form planned torque at one time (N m), as :meth:`sample` gives it, in plain float arithmetic.

        On a leg about body axis :math:`e`, :math:`u = \ddot\theta\, I e + \dot\theta^2\, e \times I e`
        (law R2), with the leg's :math:`I e` and :math:`e \times I e` computed once (:attr:`_torque_legs`).
        """
        t = float(t)
        legs = self._torque_legs
        if not legs:
            return np.zeros(3)
        k = min(max(bisect_right(self._leg_starts, t) - 1, 0), len(legs) - 1)
        start, duration, ramp_time, rate_coast, accel, inertia_axis, gyro = legs[k]
        local = min(max(t - start, 0.0), duration)
        if local < ramp_time:
            rate, acc = accel * local, accel
        elif local > duration - ramp_time:
            rate, acc = accel * (duration - local), -accel
        else:
            rate, acc = rate_coast, 0.0
        if t < 0.0 or t > self.maneuver_time_s:
            acc = 0.0
        rate2 = rate * rate
        return np.array([acc * a + rate2 * g for a, g in zip(inertia_axis, gyro, strict=True)])

    @cached_property
    def _torque_legs(self) -> tuple[tuple, ...]:
        r"""Per leg: start, duration, ramp time, coast rate, ramp acceleration, :math:`Ie`, :math:`e\times Ie`.

        The ramp and coast values as :func:`_trapezoid` forms them.
        """
        legs = []
        for s in self.segments:
            ramp_time = s.ramp_fraction * s.duration_s
            rate = s.angle_rad / (s.duration_s * (1 - s.ramp_fraction)) if s.duration_s > 0 else s.angle_rad
            accel = rate / ramp_time if ramp_time > 0 else rate
            inertia_axis = self.inertia @ s.axis_body
            legs.append((s.t_start_s, s.duration_s, ramp_time, rate, accel, tuple(inertia_axis.tolist()),
                         tuple(np.cross(s.axis_body, inertia_axis).tolist())))
        return tuple(legs)

    @cached_property
    def _leg_starts(self) -> list[float]:
        return [s.t_start_s for s in self.segments]

    def torque_command(self) -> TorqueCommand:
        """The planned torque for :func:`convexguid.verification.propagate_attitude`: :meth:`torque_at`, with the
        times where it jumps (:attr:`breakpoints_s`) and :meth:`sample` for many times."""
        return TorqueCommand(self.torque_at, self.breakpoints_s, sample=lambda t: self.sample(t)[2])

    @property
    def breakpoints_s(self) -> NDArray:
        """Times where the torque jumps (leg starts, ramp ends and starts, final time): put grid nodes there.

        A linear interpolant of the torque on a grid that straddles these times reproduces the plan; on the
        plain node grid it smears every jump over one node period and the open-loop attitude drifts.
        """
        pts = [(s.t_start_s, s.t_start_s + s.ramp_fraction * s.duration_s,
                s.t_start_s + (1 - s.ramp_fraction) * s.duration_s) for s in self.segments]
        return np.unique(np.append(np.ravel(pts), self.maneuver_time_s))


def plan_path_transfer(problem: PathTransferProblem) -> PathTransferResult:
    """Plan a keep-out-safe, torque- and rate-bounded rest-to-rest slew by path transfer (paper Sec. 2).

    Stages: eigenaxis reference path (eqs. 15-21), relaxed node count (eqs. 22-28), path-transfer walk
    (eqs. 29-37); each resulting leg is timed by the law R2 with the node count of eq. (25). The wall time
    of the whole call is ``planning_time_s``. Raises PathTransferError if the walk does not converge.
    """
    start = time.perf_counter()
    legs, log = _walk(problem)
    segments, waypoints, t0 = [], [problem.q0], 0.0
    for _, axis, angle in legs:
        if angle > 1e-12:
            segments.append(_leg(problem, waypoints[-1], axis, angle, t0))
            t0 += segments[-1].duration_s
            waypoints.append(quat_multiply(waypoints[-1], axis_angle_to_quat(axis, angle)))
    severity = [max((ACTIONS.index(a) for c, a in log if c == i), default=0) for i in range(len(problem.cones))]
    dense = [_dense(s.q_start, s.axis_body, s.angle_rad, problem.check_step_rad) for s in segments]
    plan_min = problem.cone_angles(np.concatenate(dense or [problem.q0[None]])).min(axis=0)
    axis, angle = eigenaxis_rotation(problem.q0, problem.qf)
    ref_min = problem.cone_angles(_dense(problem.q0, axis, angle, problem.check_step_rad)).min(axis=0)
    n_nodes = int(round(t0 / problem.node_period_s)) + 1
    result = PathTransferResult(
        waypoints=np.stack(waypoints), actions=tuple(ACTIONS[s] for s in severity),
        action_log=tuple((problem.cones[c].name, a) for c, a in log), segments=tuple(segments),
        t=np.arange(n_nodes) * problem.node_period_s, q=np.empty((0, 4)), omega=np.empty((0, 3)),
        torque=np.empty((0, 3)), maneuver_time_s=t0, planning_time_s=0.0,
        min_cone_margin_deg=float(np.degrees(np.min(plan_min - problem.half_angles, initial=np.inf))),
        cone_min_angle_deg=tuple(np.degrees(plan_min).tolist()),
        reference_min_angle_deg=tuple(np.degrees(ref_min).tolist()),
        reference_maneuver_time_s=_leg(problem, problem.q0, axis, angle).duration_s, inertia=problem.inertia)
    q, omega, torque = result.sample(result.t)
    return replace(result, q=q, omega=omega, torque=torque, planning_time_s=time.perf_counter() - start)


def multicone_scenario(**overrides: object) -> PathTransferProblem:
    """The project's seed-003 scenario (paper Table 1 was lost; docs/parameters.md), with overrides.

    Boresight body +z; inertia diag(10, 12, 15) kg m^2; 0.1 N m; 3 deg/s; identity to a 160 deg rotation about
    (1, -1, 0.5); four bright bodies with half-angles 20, 15, 12, 20 deg. ``overrides`` go to
    :func:`dataclasses.replace` (e.g. ``cones=...`` or ``node_period_s=5.0``).
    """
    bodies = (
        ("body1", (-0.466, -0.688, 0.556), 20.0), ("body2", (-0.244, -0.911, -0.333), 15.0),
        ("body3", (0.3, 0.2, 0.93), 12.0), ("body4", (-0.8, -0.2, 0.2), 20.0))
    problem = PathTransferProblem(
        inertia=np.diag([10.0, 12.0, 15.0]), boresight_body=np.array([0.0, 0.0, 1.0]),
        q0=np.array([0.0, 0.0, 0.0, 1.0]), qf=axis_angle_to_quat([1.0, -1.0, 0.5], math.radians(160.0)),
        cones=tuple(PointingCone(n, np.array([0.0, 0.0, 1.0]), np.array(d), math.radians(a)) for n, d, a in bodies),
        torque_max=0.1, rate_max=math.radians(3.0))
    return replace(problem, **overrides) if overrides else problem
