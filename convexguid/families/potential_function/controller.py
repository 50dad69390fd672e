r"""Potential-function + backstepping attitude controller with forbidden-attitude avoidance (Guo, Li, Ma 2011).

The controller steers a reaction-wheel spacecraft to an inertially fixed command attitude :math:`q_c` while keeping
the Euler-axis angle :math:`\theta_b` to one forbidden attitude :math:`q_b` above :math:`\theta_m`. An attractive
potential :math:`V_a` (eq. 8) and a repulsive potential :math:`V_r` (eqs. 12-13, switched on only while the three
existence conditions of eqs. 9-11 hold) define a virtual rate command :math:`\omega_c` (eq. 16), which the torque
law of eq. 19 tracks by backstepping. Optionally the gains :math:`\mu, s, g` adapt to torque and rate limits
(eqs. 24-30), and a switching law escapes the local minimum of the potential (eqs. 31-32).

Conventions are those of :mod:`convexguid.rotations`: quaternions are scalar-last ``[x, y, z, w]``, Hamilton
product, body relative to inertial, rates in body axes (rad/s), angles in radians. The paper uses the same
kinematics (its eq. 4 is :math:`\dot q = \tfrac12 q \otimes [\omega, 0]`) and scalar-last quaternions, so no
sign changes are needed.

Corrections and reconstructions of the published text (each also noted where it is used):

* **Condition 3** is printed as :math:`\theta_{be} > \theta_0`. The sentence before it says that when
  :math:`\theta_{be} > \theta_0` the rotation toward the command does *not* enter the forbidden set, and the
  condition is meant to switch the repulsion *on*; the printed inequality therefore has its direction reversed.
  Simulated as printed, the repulsion never acts on the paper's own scenario (the forbidden attitude lies exactly
  on the slew path, :math:`\theta_{be} = 0`) and the attitude passes straight through the forbidden one. This
  module uses :math:`\theta_{be} < \theta_0`.
* The **"q_4" in eqs. 19 and 22** is the scalar part :math:`e_4` of the error quaternion (it comes from
  :math:`\dot e` of eq. 6 in the derivative of :math:`\omega_c`, eq. 18).
* **Eq. 9** is garbled in the extraction as a product of two cross-product matrices; the unit vector along
  the intersection OA of the two rotation planes is :math:`i_{OA} = a_e \times a_b / \|a_e \times a_b\|`.
* **Eqs. 1-2** read :math:`\dot I \omega` in the extraction; the physics is :math:`I \dot\omega`.
* The command is written :math:`q_c` in Sec. 2 and :math:`q_e` in eq. 5 / Table 1; :math:`\theta_c` in
  condition 1 is the error angle :math:`\theta_e`; :math:`u_{pm}` in Sec. 4 is :math:`u_{\mu m}`.
* The forbidden quaternion :math:`b` is sign-normalised to :math:`b_4 \ge 0`, so that :math:`V_r` measures the
  physical (principal) distance to the forbidden attitude whatever the sign of :math:`q_b`. The error quaternion
  :math:`e` is used as given (the paper's :math:`V_a` is not sign-invariant); its angle :math:`\theta_e` is the
  rotation that :math:`\omega_c` performs, in :math:`[0, 2\pi]`.

References
----------
Guo Yanning, Li Chuanjiang, Ma Guangfu, "Spacecraft autonomous attitude maneuver control by potential function
method", Acta Aeronautica et Astronautica Sinica 32(3), 457-464, 2011 (eqs. 4-32, Table 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from convexguid.checks import inertia_matrix, positive, unit_vector
from convexguid.errors import SpecError
from convexguid.rotations import cross3, quat_conjugate, quat_multiply

__all__ = [
    "PotentialFunctionGains", "ControlInfo", "PotentialFunctionController", "error_quaternion",
    "attractive_potential", "barrier_offset", "repulsive_potential", "angle_to_plane",
    "guo2011_fixed_gains", "guo2011_adaptive_gains",
]

_AXIS_TOL = 1e-12
"""Vector-part norm below which an Euler axis (and hence conditions 3 and 31) is undefined."""


def error_quaternion(q: ArrayLike, q_ref: ArrayLike) -> NDArray:
    r"""Attitude of the body relative to a reference attitude, :math:`e = q_{ref}^* \otimes q` (eq. 5).

    The paper's eq. 5 writes this as a 4x4 matrix of the reference components times q; expanding
    :math:`q_{ref}^* \otimes q` with the Hamilton product gives exactly that matrix. The same function gives the
    forbidden quaternion :math:`b = q_b^* \otimes q`. Both obey :math:`\dot e = \tfrac12 e \otimes [\omega, 0]`
    (eqs. 6-7) for a fixed reference. Complex input is supported.
    """
    return quat_multiply(quat_conjugate(q_ref), q)


def attractive_potential(e: ArrayLike) -> complex | float:
    r"""Attractive potential of eq. 8, zero only at :math:`e = [0, 0, 0, 1]`.

    .. math:: V_a = e^T e + (1 - e_4)^2 \;(= 2 - 2 e_4 \text{ for a unit } e), \qquad \dot V_a = \omega^T e

    ``e`` is the scalar-last error quaternion; complex input is supported (complex-step derivatives).
    """
    e = np.asarray(e)
    return e[:3] @ e[:3] + (1 - e[3]) ** 2


def barrier_offset(theta_m: float) -> float:
    r"""Minimum-distance offset of eq. 13, :math:`\lambda_b = 2 - 2\cos(\theta_m / 2)`.

    It equals :math:`b^Tb + (1 - b_4)^2` on the boundary :math:`\theta_b = \theta_m` of the forbidden set.
    """
    return 2.0 - 2.0 * math.cos(theta_m / 2)


def repulsive_potential(b: ArrayLike, eta: float, theta_m: float) -> complex | float:
    r"""Repulsive potential of eq. 12 *without* the existence switch (the controller applies conditions 1-3).

    .. math::
        V_r = \frac{1}{\eta\,[b^Tb + (1 - b_4)^2 - \lambda_b]}, \qquad \dot V_r = -\eta V_r^2\, \omega^T b

    With :math:`b_4 = \cos(\theta_b/2) \ge 0` the bracket is :math:`2\cos(\theta_m/2) - 2\cos(\theta_b/2)`,
    positive outside the forbidden set and zero on its boundary, where :math:`V_r \to \infty`. Complex input is
    supported.
    """
    b = np.asarray(b)
    return 1.0 / (eta * (b[:3] @ b[:3] + (1 - b[3]) ** 2 - barrier_offset(theta_m)))


def angle_to_plane(a_e: NDArray, b: NDArray) -> float:
    r"""Angle :math:`\theta_{be}` of eqs. 9-11 between OB and the rotation plane of the slew toward the command.

    .. math::
        i_{OA} = \frac{a_e \times a_b}{\|a_e \times a_b\|}, \quad i_{OB} = A_b^{-1} i_{OA}, \quad
        \theta_{be} = \frac{\pi}{2} - \arccos|a_e^T i_{OB}|

    OA is the intersection of the planes normal to the Euler axes :math:`a_e` (error) and :math:`a_b`
    (forbidden); rotating it through :math:`\theta_b` about :math:`a_b` (the rotation :math:`A_b = C(b)` of the
    body relative to the forbidden attitude) gives OB. The extraction prints eq. 9 as a product of two
    cross-product matrices; the vector cross product is meant. By spherical trigonometry the result equals
    :math:`\arcsin(\sin\theta_b \sin\varphi)`, :math:`\varphi` the angle between the axes (independent of the
    sense of rotation by :math:`A_b` or its inverse). When the axes are parallel OA is undefined and the limit
    :math:`\theta_{be} = 0` is returned: the forbidden attitude lies on the great circle of the slew.

    Parameters
    ----------
    a_e : ndarray, shape (3,)
        Unit Euler axis of the error quaternion.
    b : ndarray, shape (4,)
        Unit forbidden quaternion (scalar-last); its axis and the rotation matrix :math:`A_b` are taken from it.
    """
    a_b = b[:3] / np.linalg.norm(b[:3])
    n = cross3(a_e, a_b)
    norm_n = np.linalg.norm(n)
    if norm_n < _AXIS_TOL:
        return 0.0
    i_oa, bv, b4 = n / norm_n, b[:3], b[3]
    # A_b^{-1} i_OA = C(b)^T i_OA with C of convexguid.rotations.quat_to_dcm, written out for speed
    i_ob = (b4 * b4 - bv @ bv) * i_oa + 2 * (bv @ i_oa) * bv + 2 * b4 * cross3(bv, i_oa)
    return math.pi / 2 - math.acos(min(1.0, abs(float(a_e @ i_ob))))


@dataclass(frozen=True)
class PotentialFunctionGains:
    r"""Gains and limits of the potential-function controller (Guo et al. 2011, Sec. 2-3); angles in radians.

    Parameters
    ----------
    g, s, mu : float
        Backstepping gain :math:`g` (eq. 19), virtual-rate gain :math:`s` (eq. 16) and rate-error weight
        :math:`\mu` (eq. 17). Used as given in fixed-gain mode; ignored in adaptive mode.
    eta : float
        Scale factor :math:`\eta` of the repulsive potential (eq. 12).
    theta_m : float
        Smallest allowed Euler angle to the forbidden attitude, :math:`0 < \theta_m < \pi`.
    theta_0 : float
        Influence angle of the forbidden attitude in condition 3, :math:`\theta_m < \theta_0 \le \pi`.
    u_mu, u_s, u_g : float or None
        Torque budgets :math:`u_{\mu m}, u_{sm}, u_{gm}` (N m) of eq. 24. Giving them (all three, together with
        ``mu_min``, ``s_max``, ``g_max``) selects adaptive mode, eqs. 26-28/30.
    mu_min, s_max, g_max : float or None
        Gain bounds of eqs. 26-28.
    w_max : float or None
        Rate limit :math:`\omega_{max}` (rad/s) of eq. 30 (adaptive mode only); None for no rate limit.
    theta_lm : float or None
        Axis-alignment angle :math:`\theta_{lm}` of the local-minimum test, eq. 31; None disables the escape
        law. Requires ``u_max`` (the escape torque of eq. 32 has magnitude :math:`u_{max}`).
    u_max : float or None
        Torque limit (N m, per axis). The commanded torque is clipped to it (the paper's adaptive law keeps
        it inside :math:`u_{\mu m} + u_{sm} + u_{gm}` up to the neglected gyroscopic term, eq. 25); None for no
        limit.

    Raises
    ------
    SpecError
        For non-positive or non-finite gains or limits, :math:`\theta_0 \le \theta_m`, angles out of range, a
        partial set of adaptive parameters, ``w_max`` without adaptive mode or ``theta_lm`` without ``u_max``.
    """

    g: float
    s: float
    mu: float
    eta: float
    theta_m: float
    theta_0: float
    u_mu: float | None = None
    u_s: float | None = None
    u_g: float | None = None
    mu_min: float | None = None
    s_max: float | None = None
    g_max: float | None = None
    w_max: float | None = None
    theta_lm: float | None = None
    u_max: float | None = None

    def __post_init__(self) -> None:
        for name in ("g", "s", "mu", "eta", "theta_m", "theta_0"):
            positive(f"PotentialFunctionGains.{name}", getattr(self, name))
        adaptive = ("u_mu", "u_s", "u_g", "mu_min", "s_max", "g_max")
        given = [name for name in adaptive if getattr(self, name) is not None]
        if given and len(given) != len(adaptive):
            missing = sorted(set(adaptive) - set(given))
            raise SpecError(f"PotentialFunctionGains: adaptive mode needs all of {adaptive}; missing {missing}")
        for name in (*adaptive, "w_max", "theta_lm", "u_max"):
            if getattr(self, name) is not None:
                positive(f"PotentialFunctionGains.{name}", getattr(self, name))
        if self.theta_m >= math.pi:
            raise SpecError(f"PotentialFunctionGains.theta_m must be < pi rad, got {self.theta_m!r}")
        if not self.theta_m < self.theta_0 <= math.pi:
            raise SpecError(f"PotentialFunctionGains.theta_0 must satisfy theta_m < theta_0 <= pi, got theta_0 = "
                            f"{self.theta_0!r} with theta_m = {self.theta_m!r}")
        if self.w_max is not None and not self.adaptive:
            raise SpecError("PotentialFunctionGains.w_max is only used by the adaptive gains (eq. 30); "
                            "give u_mu, u_s, u_g, mu_min, s_max, g_max too or drop w_max")
        if self.theta_lm is not None and (self.u_max is None or self.theta_lm >= math.pi):
            raise SpecError(f"PotentialFunctionGains.theta_lm = {self.theta_lm!r} needs 0 < theta_lm < pi and a "
                            "torque limit u_max (the escape torque of eq. 32 has magnitude u_max)")

    @property
    def adaptive(self) -> bool:
        """True when the gains adapt to the torque and rate limits (eqs. 26-30)."""
        return self.u_mu is not None


@dataclass(frozen=True)
class ControlInfo:
    r"""Diagnostics of one evaluation of :meth:`PotentialFunctionController.torque` (angles in radians).

    Attributes
    ----------
    potential_active : bool
        Whether the repulsive potential acts (conditions 1-3 all hold).
    escape_active : bool
        Whether the local-minimum escape torque of eq. 32 replaced the backstepping law.
    saturated : bool
        Whether the torque was clipped to ``u_max``.
    conditions : tuple of bool
        Existence conditions 1, 2, 3 (all False without a forbidden attitude).
    mu, s, g : float
        Gains in use (the adapted values in adaptive mode).
    theta_e, theta_b, theta_be : float
        Error angle, Euler-axis angle to the forbidden attitude and the angle of eq. 11 (NaN if undefined).
    v_a, v_r : float
        Attractive and (switched) repulsive potentials.
    omega_c : ndarray, shape (3,)
        Virtual rate command :math:`\omega_c = -s(e - \eta V_r^2 b)` of eq. 16 (rad/s).
    u_unclipped : ndarray, shape (3,)
        Torque before clipping to ``u_max``.
    """

    potential_active: bool
    escape_active: bool
    saturated: bool
    conditions: tuple[bool, bool, bool]
    mu: float
    s: float
    g: float
    theta_e: float
    theta_b: float
    theta_be: float
    v_a: float
    v_r: float
    omega_c: NDArray
    u_unclipped: NDArray


def _ratio(num: float, den: float) -> float:
    """``num / den``, or infinity when ``den`` is zero (the bound it expresses is then inactive)."""
    return num / den if den > 0 else math.inf


class PotentialFunctionController:
    r"""Backstepping controller on the attractive/repulsive potential of Guo, Li, Ma (2011).

    The controller is **stateless**: every quantity, including the adaptive gains of eqs. 26-30, is a function
    of the current state only, so :meth:`torque` may be called at any time in any order. The time argument is
    unused (the command is inertially fixed).

    Parameters
    ----------
    inertia : array_like, shape (3, 3)
        Inertia matrix (kg m^2) used by the control law, symmetric positive definite.
    q_command : array_like, shape (4,)
        Command attitude :math:`q_c` (scalar-last, normalised here).
    gains : PotentialFunctionGains
        Gains and limits.
    q_forbidden : array_like, shape (4,), optional
        Forbidden attitude :math:`q_b`; None for none (then :math:`V_r \equiv 0` and eq. 19 reduces to the
        linear backstepping law of eq. 22, with a general :math:`\mu`).

    Raises
    ------
    SpecError
        For an inertia matrix that is not symmetric positive definite or an invalid quaternion.
    """

    def __init__(self, inertia: ArrayLike, q_command: ArrayLike, gains: PotentialFunctionGains,
                 q_forbidden: ArrayLike | None = None) -> None:
        inertia = inertia_matrix(inertia)
        if not isinstance(gains, PotentialFunctionGains):
            raise SpecError(f"gains must be a PotentialFunctionGains, got {type(gains).__name__}")
        self.inertia = inertia
        self.q_command = unit_vector("q_command", q_command, 4)
        self.q_forbidden = None if q_forbidden is None else unit_vector("q_forbidden", q_forbidden, 4)
        self.gains = gains
        # e = M q with the constant matrix of eq. 5 (error_quaternion is linear in q)
        self._m_command = error_quaternion(np.eye(4), self.q_command).T
        self._m_forbidden = None if self.q_forbidden is None else error_quaternion(np.eye(4), self.q_forbidden).T

    def existence_conditions(self, e: NDArray, b: NDArray, omega: NDArray) -> tuple[tuple[bool, bool, bool], float]:
        r"""Existence conditions 1-3 of the repulsive potential and the angle :math:`\theta_{be}` of eq. 11.

        1. :math:`\theta_b - \theta_m < \theta_e`: the forbidden set is nearer than the command.
        2. :math:`\omega^T b < 0`: the body rotates toward the forbidden attitude (:math:`\dot b_4 > 0`).
        3. :math:`\theta_{be} < \theta_0`: the slew toward the command passes within the influence angle of
           the forbidden attitude. **Corrected**: the paper prints :math:`\theta_{be} > \theta_0`, which
           contradicts its own preceding sentence and, simulated, lets the attitude pass through :math:`q_b`.

        Parameters
        ----------
        e, b : ndarray, shape (4,)
            Error quaternion and forbidden quaternion with :math:`b_4 \ge 0`.
        omega : ndarray, shape (3,)
            Body rate (rad/s).

        Returns
        -------
        conditions : tuple of bool
            Conditions 1, 2, 3.
        theta_be : float
            Angle of eq. 11 (NaN when the error axis is undefined, i.e. at the command; condition 3 then
            fails).
        """
        theta_e, theta_b = _angle(e), _angle(b)
        c1 = theta_b - self.gains.theta_m < theta_e
        c2 = bool(omega @ b[:3] < 0)
        norm_ev = np.linalg.norm(e[:3])
        if norm_ev < _AXIS_TOL or np.linalg.norm(b[:3]) < _AXIS_TOL:
            return (c1, c2, False), math.nan
        theta_be = angle_to_plane(e[:3] / norm_ev, b)
        return (c1, c2, theta_be < self.gains.theta_0), theta_be

    def torque(self, t: float, q: ArrayLike, omega: ArrayLike,
               h_w: ArrayLike | None = None) -> tuple[NDArray, ControlInfo]:
        r"""Control torque :math:`u_c` (N m, body axes) and diagnostics.

        With :math:`R_{eb} = e - \eta V_r^2 b` (the gradient of :math:`V_a + V_r` with respect to a small body
        rotation, eq. 15) the virtual rate is :math:`\omega_c = -s R_{eb}` (eq. 16) and, with
        :math:`R_{\omega eb} = \omega + s R_{eb}`, the backstepping law of eqs. 19/23 is

        .. math::
            u_c = \omega^\times I\omega + \omega^\times h_w - g R_g - \mu^{-1} R_\mu - s R_s, \quad
            R_g = I R_{\omega eb}, \quad R_\mu = I R_{eb}, \\
            R_s = I\left[\tfrac12(e_4\omega - \omega^\times e) - \tfrac12\eta V_r^2 (b_4\omega - \omega^\times b)
                  + 2\eta^2 V_r^3 (\omega^T b)\, b\right],

        which makes :math:`\dot V_t = -s\|R_{eb}\|^2 - g\mu\|R_{\omega eb}\|^2 + \mu R_{\omega eb}^T I^{-1} u_d`
        (eq. 20). The paper prints :math:`q_4` in eq. 19 where the derivation (eq. 18) has :math:`e_4`.

        In adaptive mode (eqs. 26, 30, 28, evaluated in this order because :math:`R_g` contains :math:`s`)

        .. math::
            \mu = \max\left\{\frac{\|R_\mu\|_\infty}{u_{\mu m}}, \mu_{min}\right\}, \quad
            s = \min\left\{\frac{u_{sm}}{\|R_s\|_\infty}, \frac{\omega_{max}}{\|R_{eb}\|_\infty}, s_{max}\right\},
            \quad g = \min\left\{\frac{u_{gm}}{\|R_g\|_\infty}, g_{max}\right\}.

        If the repulsive potential is active and the Euler axes nearly coincide,
        :math:`a_e^T a_b > \cos\theta_{lm}` (eq. 31), the torque is replaced by (eq. 32)

        .. math:: u_c^* = u_{max}\,\mathrm{sgn}(\omega^T a_e^\times a_r)\,
                  \frac{a_e^\times a_r}{\|a_e^\times a_r\|_\infty},

        with :math:`a_r` the body axis least aligned with :math:`a_e` (lowest index on ties) and
        :math:`\mathrm{sgn}(0) = +1` (the paper leaves both open; with :math:`\mathrm{sgn}(0) = 0` a spacecraft
        at rest on the local minimum would receive no torque). The paper gates eq. 31 by the local-minimum
        situation "existence conditions hold and the axes are parallel"; the gate on the active potential also
        keeps the escape from firing near the command, where :math:`a_e` is undefined.

        Finally, with ``u_max`` set, each component is clipped to :math:`[-u_{max}, u_{max}]`.

        Inside the forbidden set (:math:`\theta_b < \theta_m`, which the barrier should prevent) eq. 12 is
        evaluated as is: :math:`V_r < 0`, but :math:`\eta V_r^2 b` still points out of the set. No state is
        rejected; :attr:`ControlInfo.theta_b` shows any violation.

        Parameters
        ----------
        t : float
            Time (s); unused.
        q : array_like, shape (4,)
            Attitude (scalar-last, body relative to inertial).
        omega : array_like, shape (3,)
            Body rate (rad/s).
        h_w : array_like, shape (3,), optional
            Wheel angular momentum (N m s, body axes); zero if omitted.

        Returns
        -------
        u : ndarray, shape (3,)
            Control torque on the body, :math:`u_c = -\dot h_w`.
        info : ControlInfo
            Diagnostics.
        """
        gains, inertia = self.gains, self.inertia
        q = np.asarray(q, dtype=float)
        omega = np.asarray(omega, dtype=float)
        h_w = np.zeros(3) if h_w is None else np.asarray(h_w, dtype=float)
        e = self._m_command @ q
        ev, e4 = e[:3], e[3]
        v_r, bv, b4 = 0.0, np.zeros(3), 0.0
        conditions, theta_b, theta_be, active = (False, False, False), math.nan, math.nan, False
        if self._m_forbidden is not None:
            b = self._m_forbidden @ q
            b = -b if b[3] < 0 else b
            theta_b = _angle(b)
            conditions, theta_be = self.existence_conditions(e, b, omega)
            active = all(conditions)
            if active:
                bv, b4 = b[:3], b[3]
                v_r = float(repulsive_potential(b, gains.eta, gains.theta_m))
        k = gains.eta * v_r**2
        r_eb = ev - k * bv
        r_s = inertia @ (0.5 * (e4 * omega - cross3(omega, ev)) - 0.5 * k * (b4 * omega - cross3(omega, bv))
                         + 2 * gains.eta * k * v_r * (omega @ bv) * bv)
        r_mu = inertia @ r_eb
        if gains.adaptive:
            mu = max(_ratio(np.abs(r_mu).max(), gains.u_mu), gains.mu_min)
            s = min(_ratio(gains.u_s, np.abs(r_s).max()), gains.s_max,
                    _ratio(gains.w_max, np.abs(r_eb).max()) if gains.w_max is not None else math.inf)
        else:
            mu, s = gains.mu, gains.s
        r_g = inertia @ (omega + s * r_eb)
        g = min(_ratio(gains.u_g, np.abs(r_g).max()), gains.g_max) if gains.adaptive else gains.g
        u = cross3(omega, inertia @ omega + h_w) - g * r_g - r_mu / mu - s * r_s

        escape = False
        if active and gains.theta_lm is not None:
            a_e, a_b = ev / np.linalg.norm(ev), bv / np.linalg.norm(bv)
            if a_e @ a_b > math.cos(gains.theta_lm):
                escape = True
                u = self._escape_torque(a_e, omega)
        u_clipped = u if gains.u_max is None else np.clip(u, -gains.u_max, gains.u_max)
        info = ControlInfo(
            potential_active=active, escape_active=escape, saturated=bool(np.any(u_clipped != u)),
            conditions=conditions, mu=float(mu), s=float(s), g=float(g), theta_e=_angle(e), theta_b=theta_b,
            theta_be=theta_be, v_a=float(attractive_potential(e)), v_r=v_r, omega_c=-s * r_eb, u_unclipped=u)
        return u_clipped, info

    def _escape_torque(self, a_e: NDArray, omega: NDArray) -> NDArray:
        """Escape torque of eq. 32 (see :meth:`torque` for the choice of a_r and sgn(0))."""
        a_r = np.zeros(3)
        a_r[int(np.argmin(np.abs(a_e)))] = 1.0
        d = cross3(a_e, a_r)
        sign = 1.0 if omega @ d >= 0 else -1.0
        return self.gains.u_max * sign * d / np.abs(d).max()


def _angle(e: NDArray) -> float:
    r"""Rotation angle :math:`2\,\mathrm{atan2}(\|e_v\|, e_4) \in [0, 2\pi]` of a unit quaternion."""
    return 2.0 * math.atan2(float(np.linalg.norm(e[:3])), float(e[3]))


def guo2011_fixed_gains(theta_m: float = math.radians(10.0), theta_0: float | None = None) -> PotentialFunctionGains:
    r"""Fixed gains of Guo et al. (2011) Fig. 2: :math:`g = s = 1`, :math:`\mu = 20`, :math:`\eta = 120`, no limits.

    ``theta_0`` defaults to :math:`1.2\,\theta_m` (12 deg for the paper's :math:`\theta_m = 10` deg). No torque
    limit and no local-minimum escape ("without avoiding the local minimum", Sec. 4).
    """
    return PotentialFunctionGains(g=1.0, s=1.0, mu=20.0, eta=120.0, theta_m=theta_m,
                                  theta_0=1.2 * theta_m if theta_0 is None else theta_0)


def guo2011_adaptive_gains(theta_m: float = math.radians(10.0),
                           theta_0: float | None = None) -> PotentialFunctionGains:
    r"""Adaptive gains of Guo et al. (2011) Fig. 3 (and Figs. 4-5), Sec. 4 / Table 1.

    :math:`u_{\mu m} = 0.2`, :math:`u_{sm} = 0.2`, :math:`u_{gm} = 0.1` N m, :math:`\mu_{min} = 20`,
    :math:`s_{max} = g_{max} = 1`, :math:`\omega_{max} = 1.91` deg/s (wheel momentum 20 N m s over the smallest
    inertia, 600 kg m^2), :math:`\theta_{lm} = 1` deg, :math:`|u_i| \le u_{max} = 0.5` N m, :math:`\eta = 120`;
    ``theta_0`` defaults to :math:`1.2\,\theta_m` (the Fig. 4 sweep). The fixed g, s, mu are unused in adaptive
    mode and set to the bounds.
    """
    return PotentialFunctionGains(
        g=1.0, s=1.0, mu=20.0, eta=120.0, theta_m=theta_m, theta_0=1.2 * theta_m if theta_0 is None else theta_0,
        u_mu=0.2, u_s=0.2, u_g=0.1, mu_min=20.0, s_max=1.0, g_max=1.0, w_max=math.radians(1.91),
        theta_lm=math.radians(1.0), u_max=0.5)
