"""Quaternion attitude planning under keep-out/keep-in cones, torque and rate boxes and forbidden attitudes.

State :math:`x = (q, \\omega)` (scalar-last quaternion, body relative to inertial; body rate), control
the body torque :math:`u`, full rigid-body dynamics with a full inertia matrix:

.. math::

    \\dot q = \\tfrac12\\, q \\otimes [\\omega, 0], \\qquad
    \\dot\\omega = I^{-1}(u - \\omega \\times I\\omega).

**Stated on convexguid.ocp.** :func:`attitude_problem` states the case as a :class:`convexguid.ocp.Problem` (the
framework a user states a problem in): states ``q1..q4``, ``w1..w3``, torques ``u1..u3``, the dynamics above as
CasADi expressions, the constraints below. :func:`transcribe_slew` transcribes it with the package's own
Hermite-Simpson program (:class:`convexguid.ocp.hermite_simpson.HermiteSimpsonProgram`, not a subclass) on ``K``
equal intervals with the torque linear between nodes, CasADi's exact sparse Jacobians and Lagrangian Hessian, and a
free final time through :math:`h = t_f/K`; a :class:`Slew` pairs that program with what it does not keep, the case
and the node margin, and reads its plans (node rows, times, torque). (Before, the family wrote the same NLP by hand
in numpy: 481 lines of this module, 299 once stated on convexguid.ocp; the figures of every problem file are
unchanged, validation/REPORT.md.)

**Unit quaternion.** No norm constraint is imposed: the kinematics preserve
:math:`|q|` exactly in continuous time and Hermite-Simpson keeps it to
:math:`O(h^4)` per interval (the drift is reported as ``max_quaternion_norm_error``); adding
:math:`|q_k| = 1` on top of the defects would over-determine the discrete system. The final attitude is the
vector part of the attitude error, :math:`\\operatorname{vec}(q_f^{-1} \\otimes q_K) = 0` (three affine rows: all
four components would fix the norm as well). The cone maps use the quadratic form :math:`C(q)` without
normalization. The verification propagates the true dynamics and renormalizes.

**Constraints.** Torque and rate boxes at the nodes (hard bounds; each torque axis with its own bound; the torque
is linear between nodes, so its box holds everywhere); keep-out cones
:math:`b^T C_{BI}(q) r \\le \\cos(\\theta + m)` and keep-in cones
:math:`b^T C_{BI}(q) r \\ge \\cos(\\alpha - m)` at the nodes and at the Hermite-Simpson
interval midpoints (the rate box too, at the midpoints), with a margin :math:`m` that
is raised when the dense check finds the path cutting a cone's edge between nodes (as the program's repair
margins, :func:`tightened`: the problem is stated and built once); the
forbidden attitude :math:`|q_b \\cdot q| \\le \\cos((\\theta_m + m)/2)`, two rows per node and midpoint.

**Objectives.** Minimum time (:math:`\\min t_f`) or minimum energy at fixed :math:`t_f`
(:math:`\\int |u|^2 dt` by Simpson's rule on the linear torque, as least-squares residuals).
The objective's value at the start sets the unit of the exact-penalty weight (``penalty_unit="objective"`` in
``scp_settings``, :mod:`convexguid.families.quaternion_attitude.solve`), so one weight serves a 0.04 N^2 m^2 s
energy and a 100 s slew alike.

References
----------
Wang, Xu, Li, path-transfer planning for large-angle attitude maneuvers under multiple
constraints (seed 003), quaternion model and pointing constraint :math:`b^T C(q) r \\le \\cos\\theta`.
Guo, Li, Ma 2011 (seed 001), eq. (7): the forbidden-attitude distance.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from convexguid.dynamics.rigid_body import euler_torque
from convexguid.dynamics.torque import LinearTorque
from convexguid.geometry import PointingCone, eigenaxis_rotation
from convexguid.ocp import Problem
from convexguid.ocp.attitude import rigid_body_dynamics
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.ocp.parts import Margins
from convexguid.rotations import axis_angle_to_quat, quat_conjugate, quat_multiply
from convexguid.scp.problem import ProgramSize

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
    """The default SCP start: eigenaxis node rows over the case's :math:`t_f` (or :func:`eigenaxis_time_guess`),
    moved off the eigenaxis by :func:`off_symmetry`."""
    tf_guess = case.tf or eigenaxis_time_guess(case)
    rows = eigenaxis_guess(case, case.t0 + np.linspace(0.0, tf_guess, intervals + 1))
    return off_symmetry(case, rows, tf_guess), tf_guess


SYMMETRY_OFFSET = 1e-6
"""Size of :func:`off_symmetry`'s offset, as a share of each variable's scale."""


def off_symmetry(case: AttitudeCase, rows: np.ndarray, tf_guess: float) -> np.ndarray:
    """``rows`` moved by a fixed pseudo-random offset of :data:`SYMMETRY_OFFSET` of each variable's scale.

    An eigenaxis slew lies on a symmetry of many slews (Betts': torques about y and z of either sign give the same
    time), and the SCP leaves it towards whichever mirror image the first asymmetry points to. Without an offset
    that was round-off: under 1e-12 changes of the inputs (seven draws), Betts' slew ended on three of its four
    mirror images, once on a 2.8% slower local optimum (29.4358 s). The offset is the same on every machine and ten
    orders above round-off, so it chooses: with it the same seven draws give one mirror image, 28.642493 s, in 35
    iterations every time; guo2011's minimum-time and minimum-energy slews and the multi-cone slew likewise give one
    answer and one iteration count each. It is far too small to move an optimum, but its direction picks the branch:
    over eight directions (generator seeds 1-8), guo2011 minimum time reached 85.32098 s every time (one direction
    tried before, seed 20261124, reached a 0.19% slower local optimum, 85.48297 s) and guo2011 minimum energy took
    23 to 70 iterations to the same optimum; seed 8 is the one kept.
    """
    scale = np.concatenate([np.ones(4), np.full(3, natural_rate(case, tf_guess)), case.torque_max])
    offset = np.random.default_rng(8).standard_normal(rows.shape) * scale * SYMMETRY_OFFSET
    return rows + offset


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


@dataclass(frozen=True)
class Slew:
    """A slew as the SCP plans it: ``program``, the plain Hermite-Simpson transcription of :func:`attitude_problem`,
    with the case it states (a repair's has a tightened rate bound) and the margin (rad) its node constraints are
    tightened by, neither of which the program keeps. The methods read a plan ``x`` of ``program``."""

    case: AttitudeCase
    margin: float
    program: HermiteSimpsonProgram

    @property
    def intervals(self) -> int:
        return self.program.N

    def nodes(self, x: np.ndarray) -> np.ndarray:
        """Node rows ``[q, omega, u]``, shape ``(K + 1, 10)``."""
        return np.hstack([self.program.states(x), self.program.node_controls(x)])

    def from_node_rows(self, x: np.ndarray) -> np.ndarray:
        """The program's vector from node rows ``[q, omega, u]`` flattened (and :math:`t_f` last when free), the
        layout of the IPOPT reference (:mod:`convexguid.families.quaternion_attitude.reference`)."""
        program, n1 = self.program, self.intervals + 1
        nodes = np.asarray(x[: n1 * NODE]).reshape(n1, NODE)
        return program.assemble(nodes[:, :NX], nodes[:, NX:], float(x[-1]) if program.free_time else self.case.tf)

    def times(self, x: np.ndarray) -> np.ndarray:
        return self.case.t0 + np.linspace(0.0, self.program.final_time(x), self.intervals + 1)

    def size(self) -> ProgramSize:
        lin = self.program.linear_constraints()
        return ProgramSize(self.program.num_variables, lin.A.shape[0] + NX * self.intervals,
                           lin.G.shape[0] + self.program.num_path)

    def torque_command(self, x: np.ndarray) -> LinearTorque:
        """Linear interpolation of the node torques (the transcription's control model); kinks at the nodes."""
        return LinearTorque(self.times(x), self.program.node_controls(x))


def tightened(slew: Slew, case: AttitudeCase, margin: float) -> Slew:
    """``slew`` with its node constraints tightened by ``margin`` (rad) and its rate box to ``case.rate_max``, as
    the repair margins of its own program (:meth:`~convexguid.ocp.transcription.Transcription.with_margins`: the
    symbolic build, its derivatives and the Hessian shared, not built again). Each row's margin is what moves its
    bound there: :math:`\\cos\\theta - \\cos(\\theta + m)` for a keep-out cone, :math:`\\cos(\\alpha - m) -
    \\cos\\alpha` for a keep-in cone, :math:`\\cos(\\theta_m/2) - \\cos((\\theta_m + m)/2)` for a forbidden
    attitude, and the rate bound's decrease for the rate box, at the nodes and between them (the rows
    :func:`~convexguid.ocp.hermite_simpson.with_bounds_between_nodes` adds), each divided as its rows are."""
    base, program = slew.case, slew.program
    if slew.margin:
        raise ValueError("tighten the untightened slew: margins replace, they do not add up")
    by_name = {}  # each path constraint's margin, by the name attitude_problem gives it
    for cone in base.cones:
        by_name[f"{cone.kind}_{cone.name}"] = (
            np.cos(cone.half_angle_rad) - np.cos(min(np.pi, cone.half_angle_rad + margin)) if cone.keep_out
            else np.cos(max(0.0, cone.half_angle_rad - margin)) - np.cos(cone.half_angle_rad))
    for fb in base.forbidden:
        by_name[f"forbidden_{fb.name}"] = by_name[f"forbidden_{fb.name}_opposite"] = (
            np.cos(fb.min_angle / 2) - np.cos(min(np.pi, fb.min_angle + margin) / 2))
    rate_cut = 0.0 if base.rate_max is None else base.rate_max - case.rate_max
    by_name |= {f"w{i + 1}_{side}_between_nodes": rate_cut for i in range(3) for side in ("max", "min")
                if base.rate_max is not None}
    # each row's margin in its own unit, divided as its rows are
    per_constraint = np.array([by_name[c.name] for c in program.problem.constraints], dtype=float)
    per_constraint = per_constraint / program.path_divisors
    bounds = np.zeros((program.N + 1, NX))
    bounds[:, 4:7] = rate_cut
    margins = Margins(per_constraint[[j for _, _, j in program.path_rows]], bounds.ravel())
    return Slew(case, margin, program.with_margins(margins))


def transcribe_slew(case: AttitudeCase, intervals: int, guess: np.ndarray, tf_guess: float,
                    margin: float = 0.0) -> Slew:
    """The case stated on :mod:`convexguid.ocp` (:func:`attitude_problem`, node constraints tightened by ``margin``,
    rad) and transcribed on ``intervals`` Hermite-Simpson intervals, starting from ``guess`` (node rows
    ``[q, omega, u]``) and ``tf_guess``. The body rates and their defects are scaled by :data:`RATE_SCALE_FACTOR`
    times :func:`natural_rate` over the guessed duration."""
    rate_scale = RATE_SCALE_FACTOR * natural_rate(case, tf_guess)
    guess = np.asarray(guess, dtype=float).reshape(intervals + 1, NODE)
    problem = attitude_problem(case, intervals, tf_guess, rate_scale)
    problem.initial_guess(guess[:, :NX], guess[:, NX:])
    slew = Slew(case, 0.0, HermiteSimpsonProgram(problem))
    return tightened(slew, case, margin) if margin else slew


def attitude_problem(case: AttitudeCase, intervals: int, tf_guess: float, rate_scale: float) -> Problem:
    """The slew as a :class:`convexguid.ocp.Problem` (see the module docstring): states ``q1..q4`` (scale 1),
    ``w1..w3`` (``rate_scale``, the rate box their bounds: hard at the nodes, penalized rows between them),
    torques ``u1..u3`` (their boxes, scaled by them); the final attitude as the quaternion error's vector part;
    each cone and forbidden attitude as path constraints (a repair tightens them and the rate box by the program's
    margins, :func:`tightened`)."""
    p = Problem(case.name)
    q = [p.state(f"q{i + 1}", initial=float(case.q0[i]), scale=1.0) for i in range(4)]
    rate_box = None if case.rate_max is None else (-case.rate_max, case.rate_max)
    w = [p.state(f"w{i + 1}", bounds=rate_box, initial=float(case.w0[i]), final=float(case.wf[i]), scale=rate_scale)
         for i in range(3)]
    u = [p.control(f"u{i + 1}", bounds=(-float(bound), float(bound)), scale=float(bound))
         for i, bound in enumerate(case.torque_max)]
    p.dynamics(rigid_body_dynamics(q, w, u, case.inertia))
    # vec(q_f^-1 (x) q_K) = 0: three rows (all four components would also fix the norm, which the dynamics carry)
    error = np.array([quat_multiply(quat_conjugate(case.qf), e)[:3] for e in np.eye(4)]).T
    p.boundary_constraint("final_attitude", ca.mtimes(ca.DM(error), ca.vertcat(*q)), at="final")
    attitude = ca.vertcat(*q)
    # the rows below in their own units (cosines, shares of rate_max): tightened() states its margins in them
    for cone in case.cones:
        cosine = cone_cosine_expression(attitude, cone)
        if cone.keep_out:
            p.path_constraint(f"{cone.kind}_{cone.name}", cosine - np.cos(cone.half_angle_rad), "cos", scale=1.0)
        else:
            p.path_constraint(f"{cone.kind}_{cone.name}", np.cos(cone.half_angle_rad) - cosine, "cos", scale=1.0)
    for fb in case.forbidden:
        # linear in q, but penalized like the cones: a guess may pass through the forbidden attitude
        bound = np.cos(fb.min_angle / 2)
        dot = ca.dot(ca.DM(fb.q), attitude)
        p.path_constraint(f"forbidden_{fb.name}", dot - bound, "cos", scale=1.0)
        p.path_constraint(f"forbidden_{fb.name}_opposite", -dot - bound, "cos", scale=1.0)
    if case.tf is None:
        p.final_time(bounds=(1e-3 * tf_guess, None), guess=tf_guess)
        p.minimize_time()
    else:
        p.final_time(fixed=case.tf)
        p.minimize_energy()
    p.transcription(intervals, "hermite-simpson", control="linear")
    return p


def cone_cosine_expression(q: ca.SX, cone: PointingCone) -> ca.SX:
    """:func:`cone_cosine` as a CasADi expression of the quaternion ``q`` (a column of four)."""
    b, r = ca.DM(cone.body_axis), ca.DM(cone.inertial_dir)
    v, w = q[:3], q[3]
    return ((w**2 - ca.dot(v, v)) * ca.dot(b, r) + 2 * ca.dot(v, b) * ca.dot(v, r)
            - 2 * w * ca.dot(v, ca.DM(np.cross(cone.inertial_dir, cone.body_axis))))
