r"""Attitude representations: DCMs, Euler 3-2-1 angles, quaternions and MRPs.

Conventions (used by every function of this module):

* Quaternions are scalar-last ``q = [x, y, z, w]`` with the Hamilton product, and describe the body
  frame B relative to the inertial frame I.
* The direction cosine matrix ``C = C_BI`` maps inertial components to body components,
  :math:`v_B = C_{BI} v_I`. In terms of q,

  .. math:: C_{BI}(q) = (w^2 - q_v^T q_v) I + 2 q_v q_v^T - 2 w [q_v\times],

  i.e. :math:`v_B = q^* \otimes v_I \otimes q` and, for the composition of B relative to I (``p``) with
  C relative to B (``q``), :math:`C_{CI} = C(q) C(p) = C(p \otimes q)`.
* Euler angles are the 3-2-1 (Z-Y-X) sequence: yaw :math:`\psi` about z, then pitch :math:`\theta` about the
  new y, then roll :math:`\phi` about the new x. Arrays are ordered ``(roll, pitch, yaw)`` in radians;
  :math:`C_{BI} = R_1(\phi) R_2(\theta) R_3(\psi)`, :math:`R_3(\psi) = [[c, s, 0], [-s, c, 0], [0, 0, 1]]`.
* Modified Rodrigues parameters are :math:`p = \mathbf{q}_v / (1 + w)`.
* Body rates ``omega_B`` are the angular velocity of B relative to I in body components, so that
  :math:`\dot C_{BI} = -[\omega_B\times] C_{BI}` and :math:`\dot q = \tfrac12 q \otimes [\omega_B, 0]`.

Functions accept one item (``(3,)``, ``(4,)``, ``(3, 3)``) or a stack with leading batch dimensions.

References
----------
M. D. Shuster, "A survey of attitude representations", J. Astronaut. Sci. 41(4), 1993.
S. W. Shepperd, "Quaternion from rotation matrix", J. Guid. Control 1(3), 1978.
H. Schaub and J. L. Junkins, *Analytical Mechanics of Space Systems*, 4th ed., AIAA, 2018, ch. 3
(MRP kinematics, eq. 3.165).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "skew", "euler321_to_dcm", "dcm_to_euler321", "quat_to_dcm", "dcm_to_quat", "euler321_to_quat",
    "quat_to_euler321", "quat_multiply", "quat_conjugate", "quat_normalize", "quat_rotate",
    "quat_angle_between", "axis_angle_to_quat", "quat_to_mrp", "mrp_to_quat", "mrp_shadow",
    "quat_rate_matrix", "quat_derivative", "mrp_derivative", "euler321_rates_matrix",
    "euler321_body_rates", "euler321_rates_from_body",
]

GIMBAL_LOCK_TOL = 1e-9
"""Smallest :math:`|\\cos\\theta|` for which Euler 3-2-1 rates are computed from body rates."""


def _arr(x: ArrayLike, last: int) -> NDArray:
    """Float (or complex) array whose trailing dimension has length ``last``."""
    a = np.asarray(x)
    a = a.astype(np.result_type(a.dtype, np.float64), copy=False)
    if a.ndim == 0 or a.shape[-1] != last:
        raise ValueError(f"expected an array of shape (..., {last}), got shape {a.shape}")
    return a


def _norm(a: NDArray) -> NDArray:
    """Euclidean norm over the last axis without ``abs`` (so complex-step differentiation works)."""
    return np.sqrt(np.sum(a * a, axis=-1))


def _matrix3(rows: list[list[NDArray | float]], like: NDArray) -> NDArray:
    """A ``(..., 3, 3)`` array from nine entries (arrays shaped like ``like`` or scalars), filled in place."""
    out = np.empty(like.shape + (3, 3), dtype=like.dtype)
    for i, row in enumerate(rows):
        for j, entry in enumerate(row):
            out[..., i, j] = entry
    return out


def cross3(a: NDArray, b: NDArray) -> NDArray:
    """Cross product of two 3-vectors (several times faster than ``np.cross`` for single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def cross_rows(a: NDArray, b: NDArray) -> NDArray:
    """Cross products of stacked 3-vectors ``(..., 3)`` (broadcast; complex-safe): the products and differences of
    ``np.cross``, in its order, so the same numbers, without its argument handling (which costs more than the
    arithmetic on a few dozen rows)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape), dtype=np.result_type(a, b))
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    np.subtract(a1 * b2, a2 * b1, out=out[..., 0])
    np.subtract(a2 * b0, a0 * b2, out=out[..., 1])
    np.subtract(a0 * b1, a1 * b0, out=out[..., 2])
    return out


def skew(v: ArrayLike) -> NDArray:
    r"""Cross-product matrix :math:`[v\times]`, :math:`[v\times] u = v \times u`; shape ``(..., 3, 3)``."""
    v = _arr(v, 3)
    x, y, z = np.moveaxis(v, -1, 0)
    return _matrix3([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]], x)


def euler321_to_dcm(rpy: ArrayLike) -> NDArray:
    r"""DCM :math:`C_{BI}` of Euler 3-2-1 angles ``(roll, pitch, yaw)``; complex input is supported.

    .. math::
        C_{BI} = R_1(\phi)R_2(\theta)R_3(\psi) = \begin{bmatrix}
        c_\theta c_\psi & c_\theta s_\psi & -s_\theta \\
        s_\phi s_\theta c_\psi - c_\phi s_\psi & s_\phi s_\theta s_\psi + c_\phi c_\psi & s_\phi c_\theta \\
        c_\phi s_\theta c_\psi + s_\phi s_\psi & c_\phi s_\theta s_\psi - s_\phi c_\psi & c_\phi c_\theta
        \end{bmatrix}
    """
    a = _arr(rpy, 3)
    (cp, ct, cy), (sp, st, sy) = np.moveaxis(np.cos(a), -1, 0), np.moveaxis(np.sin(a), -1, 0)
    rows = [[ct * cy, ct * sy, -st],
            [sp * st * cy - cp * sy, sp * st * sy + cp * cy, sp * ct],
            [cp * st * cy + sp * sy, cp * st * sy - sp * cy, cp * ct]]
    return _matrix3(rows, cp)


def dcm_to_euler321(C: ArrayLike) -> NDArray:
    r"""Euler 3-2-1 angles ``(roll, pitch, yaw)`` of a DCM :math:`C_{BI}`.

    Pitch lies in :math:`[-\pi/2, \pi/2]`, roll and yaw in :math:`(-\pi, \pi]`:

    .. math::
        \theta = \operatorname{atan2}(-C_{13}, \sqrt{C_{11}^2 + C_{12}^2}), \quad
        \psi = \operatorname{atan2}(C_{12}, C_{11}), \quad
        \phi = \operatorname{atan2}(C_{31} s_\psi - C_{32} c_\psi,\; C_{22} c_\psi - C_{21} s_\psi).

    Roll is taken from :math:`C R_3(\psi)^T = R_1(\phi) R_2(\theta)`, which stays well conditioned at
    gimbal lock (:math:`|\theta| = \pi/2`): there yaw is only fixed by round-off (0 for an exact DCM) and
    roll absorbs the rest, so the angles always reproduce C. No error is raised.
    """
    C = np.asarray(C, dtype=float)
    theta = np.arctan2(-C[..., 0, 2], np.hypot(C[..., 0, 0], C[..., 0, 1]))
    psi = np.arctan2(C[..., 0, 1], C[..., 0, 0])
    cy, sy = np.cos(psi), np.sin(psi)
    phi = np.arctan2(C[..., 2, 0] * sy - C[..., 2, 1] * cy, C[..., 1, 1] * cy - C[..., 1, 0] * sy)
    return np.stack([phi, theta, psi], -1)


def quat_normalize(q: ArrayLike) -> NDArray:
    """Unit quaternion ``q / |q|`` (scalar-last); raises ValueError for a zero quaternion."""
    q = _arr(q, 4)
    n = _norm(q)
    if np.any(np.abs(n) == 0) or not np.all(np.isfinite(n)):
        raise ValueError(f"cannot normalise a zero or non-finite quaternion (norms {np.abs(n)})")
    return q / n[..., None]


def quat_conjugate(q: ArrayLike) -> NDArray:
    """Conjugate ``[-x, -y, -z, w]`` of a scalar-last quaternion (the inverse of a unit quaternion)."""
    q = _arr(q, 4)
    return np.concatenate([-q[..., :3], q[..., 3:]], -1)


def quat_multiply(p: ArrayLike, q: ArrayLike) -> NDArray:
    r"""Hamilton product :math:`p \otimes q` of scalar-last quaternions.

    .. math:: p \otimes q = [\, p_w \mathbf{q}_v + q_w \mathbf{p}_v + \mathbf{p}_v \times \mathbf{q}_v,\;
              p_w q_w - \mathbf{p}_v \cdot \mathbf{q}_v \,]

    With body-relative-to-inertial quaternions, if ``p`` takes I to B and ``q`` takes B to C, then
    ``p (x) q`` takes I to C: ``quat_to_dcm(quat_multiply(p, q)) == quat_to_dcm(q) @ quat_to_dcm(p)``.
    """
    p, q = _arr(p, 4), _arr(q, 4)
    pv, pw, qv, qw = p[..., :3], p[..., 3:], q[..., :3], q[..., 3:]
    vec = pw * qv + qw * pv + np.cross(pv, qv)
    return np.concatenate([vec, pw * qw - np.sum(pv * qv, -1, keepdims=True)], -1)


def quat_sign_continuous(q: ArrayLike) -> NDArray:
    """Rows of ``q`` with signs flipped so that consecutive quaternions have a nonnegative dot product.

    :math:`q` and :math:`-q` are the same attitude; a sampled path may jump between them, which a
    transcription would read as a 180 deg change of its states.
    """
    q = np.array(q, dtype=float)
    for k in range(1, len(q)):
        if q[k] @ q[k - 1] < 0:
            q[k] = -q[k]
    return q


def quat_to_dcm(q: ArrayLike) -> NDArray:
    r"""DCM :math:`C_{BI}` of a body-relative-to-inertial quaternion (scalar-last, normalised first).

    .. math:: C_{BI} = (w^2 - q_v^T q_v) I + 2 q_v q_v^T - 2 w [q_v\times]
    """
    q = quat_normalize(q)
    v, w = q[..., :3], q[..., 3, None, None]
    eye = np.eye(3) * (w**2 - np.sum(v * v, -1)[..., None, None])
    return eye + 2 * v[..., :, None] * v[..., None, :] - 2 * w * skew(v)


def dcm_to_quat(C: ArrayLike) -> NDArray:
    r"""Quaternion (scalar-last, :math:`w \ge 0`) of a DCM :math:`C_{BI}` by Shepperd's method.

    Each of :math:`w, x, y, z` gives the whole quaternion from the trace and the (anti)symmetric parts
    of C, e.g.

    .. math:: 4w\,[x, y, z, w] = [C_{23}-C_{32},\; C_{31}-C_{13},\; C_{12}-C_{21},\; 1 + \operatorname{tr} C];

    the component of largest magnitude (largest of tr C, C11, C22, C33) is used, then normalised.
    """
    C = np.asarray(C, dtype=float)

    def c(i: int, j: int) -> NDArray:
        return C[..., i, j]

    tr = c(0, 0) + c(1, 1) + c(2, 2)
    a, b, d = c(1, 2) - c(2, 1), c(2, 0) - c(0, 2), c(0, 1) - c(1, 0)  # 4w(x, y, z)
    e, f, g = c(0, 1) + c(1, 0), c(2, 0) + c(0, 2), c(1, 2) + c(2, 1)  # 4(xy, xz, yz)
    cand = np.stack([
        np.stack([1 + 2 * c(0, 0) - tr, e, f, a], -1),
        np.stack([e, 1 + 2 * c(1, 1) - tr, g, b], -1),
        np.stack([f, g, 1 + 2 * c(2, 2) - tr, d], -1),
        np.stack([a, b, d, 1 + tr], -1),
    ], -2)
    k = np.argmax(np.stack([c(0, 0), c(1, 1), c(2, 2), tr], -1), -1)
    u = np.take_along_axis(cand, k[..., None, None], -2)[..., 0, :]
    q = u / np.linalg.norm(u, axis=-1, keepdims=True)
    return np.where(q[..., 3:] < 0, -q, q)


def euler321_to_quat(rpy: ArrayLike) -> NDArray:
    r"""Quaternion of Euler 3-2-1 angles: :math:`q = q_z(\psi) \otimes q_y(\theta) \otimes q_x(\phi)`."""
    a = _arr(rpy, 3) / 2
    (cp, ct, cy), (sp, st, sy) = np.moveaxis(np.cos(a), -1, 0), np.moveaxis(np.sin(a), -1, 0)
    return np.stack([sp * ct * cy - cp * st * sy, cp * st * cy + sp * ct * sy,
                     cp * ct * sy - sp * st * cy, cp * ct * cy + sp * st * sy], -1)


def quat_to_euler321(q: ArrayLike) -> NDArray:
    """Euler 3-2-1 angles ``(roll, pitch, yaw)`` of a body-relative-to-inertial quaternion (scalar-last)."""
    return dcm_to_euler321(quat_to_dcm(q))


def quat_rotate(q: ArrayLike, v_I: ArrayLike) -> NDArray:
    r"""Body components :math:`v_B = C_{BI}(q) v_I = q^* \otimes v_I \otimes q` (q scalar-last, B rel. I)."""
    return np.einsum("...ij,...j->...i", quat_to_dcm(q), _arr(v_I, 3))


def quat_angle_between(q1: ArrayLike, q2: ArrayLike) -> NDArray:
    r"""Principal Euler-axis angle in :math:`[0, \pi]` between two attitudes (scalar-last quaternions).

    .. math:: \delta = 2 \operatorname{atan2}(|(q_1^* \otimes q_2)_v|,\; |q_1 \cdot q_2|)
    """
    dq = quat_multiply(quat_conjugate(quat_normalize(q1)), quat_normalize(q2))
    return 2 * np.arctan2(np.linalg.norm(dq[..., :3], axis=-1), np.abs(dq[..., 3]))


def axis_angle_to_quat(axis: ArrayLike, angle: ArrayLike) -> NDArray:
    r"""Quaternion :math:`[\sin(\alpha/2) e, \cos(\alpha/2)]` of a rotation of B by ``angle`` about ``axis``.

    The axis is normalised (ValueError if zero). ``axis_angle_to_quat([0, 0, 1], psi)`` is the yaw rotation
    :math:`C_{BI} = R_3(\psi)`.
    """
    e = _arr(axis, 3)
    n = _norm(e)
    if np.any(np.abs(n) == 0):
        raise ValueError(f"rotation axis must be nonzero, got {np.asarray(axis).tolist()}")
    h = np.asarray(angle)[..., None] / 2
    v = np.sin(h) * e / n[..., None]
    return np.concatenate([v, np.broadcast_to(np.cos(h), v.shape[:-1] + (1,))], -1)


def quat_to_mrp(q: ArrayLike) -> NDArray:
    r"""MRPs :math:`p = \mathbf{q}_v / (1 + w)` of a scalar-last quaternion (normalised first).

    Singular at :math:`w = -1` (a 360 deg rotation); pass ``-q`` there to get the shadow set.
    """
    q = quat_normalize(q)
    if np.any(np.abs(1 + q[..., 3]) < 1e-15):
        raise ValueError("MRPs are singular at w = -1; use -q (the same attitude) instead")
    return q[..., :3] / (1 + q[..., 3:])


def mrp_to_quat(p: ArrayLike) -> NDArray:
    r"""Quaternion :math:`[2p, 1 - p^Tp] / (1 + p^Tp)` (scalar-last) of MRPs p."""
    p = _arr(p, 3)
    s = np.sum(p * p, -1, keepdims=True)
    return np.concatenate([2 * p, 1 - s], -1) / (1 + s)


def mrp_shadow(p: ArrayLike) -> NDArray:
    r"""Shadow MRPs :math:`-p / p^Tp` (same attitude); ValueError for p = 0."""
    p = _arr(p, 3)
    s = np.sum(p * p, -1, keepdims=True)
    if np.any(s == 0):
        raise ValueError("the shadow set of p = 0 is at infinity")
    return -p / s


def quat_rate_matrix(omega_B: ArrayLike) -> NDArray:
    r"""Matrix :math:`\Omega(\omega)` with :math:`\dot q = \tfrac12 \Omega(\omega_B) q` (scalar-last q).

    .. math:: \Omega(\omega) = \begin{bmatrix} -[\omega\times] & \omega \\ -\omega^T & 0 \end{bmatrix}
    """
    w = _arr(omega_B, 3)
    top = np.concatenate([-skew(w), w[..., :, None]], -1)
    bottom = np.concatenate([-w, np.zeros_like(w[..., :1])], -1)[..., None, :]
    return np.concatenate([top, bottom], -2)


def quat_derivative(q: ArrayLike, omega_B: ArrayLike) -> NDArray:
    r"""Quaternion rate :math:`\dot q = \tfrac12 q \otimes [\omega_B, 0]` (scalar-last, B rel. I)."""
    w = _arr(omega_B, 3)
    return 0.5 * quat_multiply(q, np.concatenate([w, np.zeros_like(w[..., :1])], -1))


def mrp_derivative(p: ArrayLike, omega_B: ArrayLike) -> NDArray:
    r"""MRP rate for body rates :math:`\omega_B` (Schaub & Junkins eq. 3.165).

    .. math:: \dot p = \tfrac14 \left[(1 - p^Tp) I + 2 [p\times] + 2 p p^T\right] \omega_B
    """
    p, w = _arr(p, 3), _arr(omega_B, 3)
    s, pw = np.sum(p * p, -1, keepdims=True), np.sum(p * w, -1, keepdims=True)
    return 0.25 * ((1 - s) * w + 2 * np.cross(p, w) + 2 * p * pw)


def euler321_rates_matrix(rpy: ArrayLike) -> NDArray:
    r"""Matrix E with :math:`\omega_B = E(\phi, \theta, \psi)\,[\dot\phi, \dot\theta, \dot\psi]^T`.

    .. math:: E = \begin{bmatrix} 1 & 0 & -s_\theta \\ 0 & c_\phi & s_\phi c_\theta \\
              0 & -s_\phi & c_\phi c_\theta \end{bmatrix}
    """
    a = _arr(rpy, 3)
    cp, sp, ct, st = np.cos(a[..., 0]), np.sin(a[..., 0]), np.cos(a[..., 1]), np.sin(a[..., 1])
    return _matrix3([[1.0, 0.0, -st], [0.0, cp, sp * ct], [0.0, -sp, cp * ct]], cp)


def euler321_body_rates(rpy: ArrayLike, rates: ArrayLike) -> NDArray:
    r"""Body rates :math:`\omega_B = E\,[\dot\phi, \dot\theta, \dot\psi]^T` (:func:`euler321_rates_matrix`),
    written out so no matrix is formed; complex input is supported.

    .. math::
        \omega_1 = \dot\phi - s_\theta\dot\psi, \quad
        \omega_2 = c_\phi\dot\theta + s_\phi c_\theta\dot\psi, \quad
        \omega_3 = -s_\phi\dot\theta + c_\phi c_\theta\dot\psi
    """
    a, r = _arr(rpy, 3), _arr(rates, 3)
    cp, sp, ct, st = np.cos(a[..., 0]), np.sin(a[..., 0]), np.cos(a[..., 1]), np.sin(a[..., 1])
    pd, td, yd = r[..., 0], r[..., 1], r[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, r.shape), dtype=np.result_type(a, r))
    out[..., 0] = pd - st * yd
    out[..., 1] = cp * td + sp * ct * yd
    out[..., 2] = -sp * td + cp * ct * yd
    return out


def euler321_rates_from_body(rpy: ArrayLike, omega_B: ArrayLike) -> NDArray:
    r"""Euler 3-2-1 rates :math:`E^{-1}\omega_B`; ValueError at gimbal lock (:math:`|\cos\theta| < 10^{-9}`).

    .. math::
        \dot\phi = \omega_1 + (\omega_2 s_\phi + \omega_3 c_\phi) \tan\theta, \quad
        \dot\theta = \omega_2 c_\phi - \omega_3 s_\phi, \quad
        \dot\psi = (\omega_2 s_\phi + \omega_3 c_\phi) / \cos\theta
    """
    a, w = _arr(rpy, 3), _arr(omega_B, 3)
    cp, sp, ct, st = np.cos(a[..., 0]), np.sin(a[..., 0]), np.cos(a[..., 1]), np.sin(a[..., 1])
    if np.any(np.abs(ct) < GIMBAL_LOCK_TOL):
        raise ValueError(f"Euler 3-2-1 rates are undefined at gimbal lock (pitch +-90 deg): {a.tolist()}")
    r = w[..., 1] * sp + w[..., 2] * cp
    return np.stack([w[..., 0] + r * st / ct, w[..., 1] * cp - w[..., 2] * sp, r / ct], -1)
