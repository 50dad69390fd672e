"""Exact tests of convexguid.rotations against closed forms (test level 1: exact)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from convexguid import rotations as rot

TOL = 1e-12
H = 1e-30  # complex-step size: derivative exact to machine precision


def _R1(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, s], [0, -s, c]])


def _R2(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])


def _R3(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def _rodrigues(axis: np.ndarray, angle: float) -> np.ndarray:
    """C_BI of a rotation of B by `angle` about unit `axis`: cos a I + (1 - cos a) e e^T - sin a [e x]."""
    e = axis / np.linalg.norm(axis)
    ex = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return np.cos(angle) * np.eye(3) + (1 - np.cos(angle)) * np.outer(e, e) - np.sin(angle) * ex


def _rpy(rng: np.random.Generator, n: int, margin: float = 0.05) -> np.ndarray:
    """Random (roll, pitch, yaw) with roll, yaw in (-pi, pi) and |pitch| <= pi/2 - margin."""
    lim = np.array([np.pi, np.pi / 2 - margin, np.pi])
    return rng.uniform(-lim, lim, size=(n, 3))


def _quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _same_quat(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance between quaternions up to the sign ambiguity q ~ -q."""
    return np.minimum(np.abs(a - b).max(-1), np.abs(a + b).max(-1))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240601)


# ---------------------------------------------------------------- DCMs and Euler angles


def test_euler321_to_dcm_closed_form(rng):
    rpy = _rpy(rng, 200, margin=0.0)
    C = rot.euler321_to_dcm(rpy)
    assert C.shape == (200, 3, 3)
    for a, Ci in zip(rpy, C, strict=True):
        phi, theta, psi = a
        np.testing.assert_allclose(Ci, _R1(phi) @ _R2(theta) @ _R3(psi), atol=TOL, rtol=0)
        np.testing.assert_allclose(rot.euler321_to_dcm(a), Ci, atol=0, rtol=0)


@pytest.mark.parametrize(
    ("rpy_deg", "v_I", "v_B"),
    [
        ((0, 0, 90), (1, 0, 0), (0, -1, 0)),  # yaw 90: inertial x is body -y
        ((0, 0, 90), (0, 1, 0), (1, 0, 0)),
        ((0, 90, 0), (1, 0, 0), (0, 0, 1)),  # pitch 90: inertial x is body +z
        ((0, 90, 0), (0, 0, 1), (-1, 0, 0)),
        ((90, 0, 0), (0, 1, 0), (0, 0, -1)),  # roll 90: inertial y is body -z
        ((90, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((90, 0, 90), (1, 0, 0), (0, 0, 1)),  # yaw then roll: x -> -y -> +z
    ],
)
def test_elementary_rotations(rpy_deg, v_I, v_B):
    rpy = np.radians(rpy_deg)
    np.testing.assert_allclose(rot.euler321_to_dcm(rpy) @ v_I, v_B, atol=TOL)
    np.testing.assert_allclose(rot.quat_rotate(rot.euler321_to_quat(rpy), v_I), v_B, atol=TOL)


def test_dcm_orthonormal(rng):
    for C in (rot.euler321_to_dcm(_rpy(rng, 100, 0.0)), rot.quat_to_dcm(_quats(rng, 100))):
        np.testing.assert_allclose(C @ np.swapaxes(C, -1, -2), np.broadcast_to(np.eye(3), C.shape), atol=TOL)
        np.testing.assert_allclose(np.linalg.det(C), 1.0, atol=TOL, rtol=0)


def test_euler_dcm_round_trip(rng):
    rpy = _rpy(rng, 500)
    np.testing.assert_allclose(rot.dcm_to_euler321(rot.euler321_to_dcm(rpy)), rpy, atol=TOL, rtol=0)
    np.testing.assert_allclose(rot.quat_to_euler321(rot.euler321_to_quat(rpy)), rpy, atol=TOL, rtol=0)
    np.testing.assert_allclose(rot.dcm_to_euler321(rot.euler321_to_dcm(rpy[0])), rpy[0], atol=TOL, rtol=0)


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-10, -np.pi / 2 + 1e-9])
def test_dcm_to_euler_near_gimbal_lock_reproduces_dcm(rng, pitch):
    for roll, yaw in rng.uniform(-np.pi, np.pi, size=(20, 2)):
        C = rot.euler321_to_dcm([roll, pitch, yaw])
        rpy = rot.dcm_to_euler321(C)
        np.testing.assert_allclose(rot.euler321_to_dcm(rpy), C, atol=1e-12)
        assert abs(rpy[1] - pitch) < 1e-7


# ---------------------------------------------------------------- quaternions


def test_quat_to_dcm_matches_euler_and_rodrigues(rng):
    rpy = _rpy(rng, 300, margin=0.0)
    np.testing.assert_allclose(rot.quat_to_dcm(rot.euler321_to_quat(rpy)), rot.euler321_to_dcm(rpy), atol=TOL)
    for _ in range(50):
        axis, angle = rng.normal(size=3), rng.uniform(-2 * np.pi, 2 * np.pi)
        q = rot.axis_angle_to_quat(axis, angle)
        np.testing.assert_allclose(rot.quat_to_dcm(q), _rodrigues(axis, angle), atol=TOL)
        np.testing.assert_allclose(rot.quat_to_dcm(3.7 * q), _rodrigues(axis, angle), atol=TOL)


def test_euler321_to_quat_is_zyx_product(rng):
    ez, ey, ex = np.eye(3)[::-1]
    for phi, theta, psi in _rpy(rng, 50, margin=0.0):
        expected = rot.quat_multiply(
            rot.quat_multiply(rot.axis_angle_to_quat(ez, psi), rot.axis_angle_to_quat(ey, theta)),
            rot.axis_angle_to_quat(ex, phi),
        )
        np.testing.assert_allclose(rot.euler321_to_quat([phi, theta, psi]), expected, atol=TOL)


def test_hamilton_units():
    i, j, k, one = np.eye(4)
    np.testing.assert_array_equal(rot.quat_multiply(i, j), k)
    np.testing.assert_array_equal(rot.quat_multiply(j, k), i)
    np.testing.assert_array_equal(rot.quat_multiply(k, i), j)
    np.testing.assert_array_equal(rot.quat_multiply(j, i), -k)
    for u in (i, j, k):
        np.testing.assert_array_equal(rot.quat_multiply(u, u), -one)


def test_composition_rule(rng):
    """q_CI = q_BI (x) q_CB  <=>  C(p (x) q) = C(q) C(p)."""
    p, q, r = _quats(rng, 100), _quats(rng, 100), _quats(rng, 100)
    pq = rot.quat_multiply(p, q)
    np.testing.assert_allclose(rot.quat_to_dcm(pq), rot.quat_to_dcm(q) @ rot.quat_to_dcm(p), atol=TOL)
    p_qr = rot.quat_multiply(p, rot.quat_multiply(q, r))
    np.testing.assert_allclose(rot.quat_multiply(pq, r), p_qr, atol=TOL)
    ident = rot.quat_multiply(p, rot.quat_conjugate(p))
    np.testing.assert_allclose(ident, np.tile([0, 0, 0, 1.0], (100, 1)), atol=TOL)


def test_quat_rotate_is_conjugation(rng):
    q, v = _quats(rng, 100), rng.normal(size=(100, 3))
    v4 = np.concatenate([v, np.zeros((100, 1))], 1)
    sandwich = rot.quat_multiply(rot.quat_multiply(rot.quat_conjugate(q), v4), q)
    np.testing.assert_allclose(rot.quat_rotate(q, v), sandwich[:, :3], atol=TOL)
    Cv = np.einsum("nij,nj->ni", rot.quat_to_dcm(q), v)
    np.testing.assert_allclose(rot.quat_rotate(q, v), Cv, atol=TOL)


def test_dcm_quat_round_trip_all_shepperd_branches(rng):
    q = _quats(rng, 400)
    special = [rot.axis_angle_to_quat(a, ang) for a in np.eye(3) for ang in (np.pi, np.pi - 1e-3, 0.1)]
    q = np.vstack([q, special, [[0, 0, 0, 1.0]]])
    q_back = rot.dcm_to_quat(rot.quat_to_dcm(q))
    assert np.all(q_back[:, 3] >= 0)
    assert _same_quat(q_back, q).max() < TOL
    C = rot.euler321_to_dcm(_rpy(rng, 200, margin=0.0))
    np.testing.assert_allclose(rot.quat_to_dcm(rot.dcm_to_quat(C)), C, atol=TOL)
    np.testing.assert_allclose(rot.dcm_to_quat(C[0]), rot.dcm_to_quat(C)[0], atol=0)


def test_quat_angle_between(rng):
    q1 = _quats(rng, 200)
    axes, angles = rng.normal(size=(200, 3)), rng.uniform(0, np.pi, size=200)
    q2 = rot.quat_multiply(q1, rot.axis_angle_to_quat(axes, angles))
    np.testing.assert_allclose(rot.quat_angle_between(q1, q2), angles, atol=TOL, rtol=0)
    np.testing.assert_allclose(rot.quat_angle_between(q1, -q2), angles, atol=TOL, rtol=0)
    big = rot.quat_multiply(q1, rot.axis_angle_to_quat(axes, 2 * np.pi - angles))  # same as -angles
    np.testing.assert_allclose(rot.quat_angle_between(q1, big), angles, atol=TOL, rtol=0)
    tiny = rot.quat_angle_between([0, 0, 0, 1.0], rot.axis_angle_to_quat([1, 2, 3], 1e-9))
    assert abs(tiny - 1e-9) < 1e-24


# ---------------------------------------------------------------- MRPs


def test_mrp_closed_form_and_round_trip(rng):
    axes = rng.normal(size=(200, 3))
    e = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    angles = rng.uniform(-1.9 * np.pi, 1.9 * np.pi, size=200)
    q = rot.axis_angle_to_quat(axes, angles)
    p = rot.quat_to_mrp(q)
    np.testing.assert_allclose(p, e * np.tan(angles / 4)[:, None], atol=1e-11, rtol=1e-12)
    np.testing.assert_allclose(rot.mrp_to_quat(p), q, atol=TOL)
    np.testing.assert_allclose(rot.quat_to_dcm(rot.mrp_to_quat(p)), _rodrigues_batch(axes, angles), atol=TOL)


def _rodrigues_batch(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    return np.array([_rodrigues(a, t) for a, t in zip(axes, angles, strict=True)])


def test_mrp_shadow(rng):
    p = rng.normal(size=(100, 3))
    s = rot.mrp_shadow(p)
    np.testing.assert_allclose(np.sum(p * s, 1), -1.0, atol=TOL)  # s = -p/|p|^2
    np.testing.assert_allclose(rot.mrp_to_quat(s), -rot.mrp_to_quat(p), atol=TOL)
    np.testing.assert_allclose(rot.mrp_shadow(s), p, atol=TOL, rtol=TOL)


# ---------------------------------------------------------------- kinematics


def _omega_from_dcm_rate(C: np.ndarray, Cdot: np.ndarray) -> np.ndarray:
    """omega_B from Cdot = -[omega x] C, i.e. [omega x] = -Cdot C^T."""
    W = -Cdot @ C.T
    np.testing.assert_allclose(W, -W.T, atol=TOL)
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


def test_skew(rng):
    a, b = rng.normal(size=(2, 50, 3))
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rot.skew(a), b), np.cross(a, b), atol=TOL)


def test_euler_rates_matrix_complex_step(rng):
    for rpy, rpy_dot in zip(_rpy(rng, 100, 0.0), rng.normal(size=(100, 3)), strict=True):
        Cdot = rot.euler321_to_dcm(rpy + 1j * H * rpy_dot).imag / H
        omega = _omega_from_dcm_rate(rot.euler321_to_dcm(rpy), Cdot)
        np.testing.assert_allclose(rot.euler321_rates_matrix(rpy) @ rpy_dot, omega, atol=TOL)
        explicit = [rpy_dot[0] - rpy_dot[2] * np.sin(rpy[1]),
                    rpy_dot[1] * np.cos(rpy[0]) + rpy_dot[2] * np.sin(rpy[0]) * np.cos(rpy[1]),
                    -rpy_dot[1] * np.sin(rpy[0]) + rpy_dot[2] * np.cos(rpy[0]) * np.cos(rpy[1])]
        np.testing.assert_allclose(omega, explicit, atol=TOL)


def test_euler321_body_rates_match_the_dcm_rate_and_invert(rng):
    """omega from the DCM's complex-step rate (independent of E), and euler321_rates_from_body undoes it."""
    rpy, rpy_dot = _rpy(rng, 100, 0.01), rng.normal(size=(100, 3))
    omega = rot.euler321_body_rates(rpy, rpy_dot)
    for k in range(0, 100, 7):
        Cdot = rot.euler321_to_dcm(rpy[k] + 1j * H * rpy_dot[k]).imag / H
        np.testing.assert_allclose(omega[k], _omega_from_dcm_rate(rot.euler321_to_dcm(rpy[k]), Cdot), atol=TOL)
    np.testing.assert_allclose(rot.euler321_rates_from_body(rpy, omega), rpy_dot, atol=1e-10)


def test_euler_rates_from_body_inverts_matrix(rng):
    rpy, w = _rpy(rng, 200, margin=0.01), rng.normal(size=(200, 3))
    rates = rot.euler321_rates_from_body(rpy, w)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rot.euler321_rates_matrix(rpy), rates), w, atol=1e-11)
    np.testing.assert_allclose(rates, np.linalg.solve(rot.euler321_rates_matrix(rpy), w[..., None])[..., 0],
                               atol=1e-10, rtol=1e-12)


def test_quat_and_mrp_derivatives_complex_step(rng):
    for q, w in zip(_quats(rng, 50), rng.normal(size=(50, 3)), strict=True):
        qdot = rot.quat_derivative(q, w)
        np.testing.assert_allclose(0.5 * rot.quat_rate_matrix(w) @ q, qdot, atol=TOL)
        Cdot = rot.quat_to_dcm(q + 1j * H * qdot).imag / H
        np.testing.assert_allclose(_omega_from_dcm_rate(rot.quat_to_dcm(q), Cdot), w, atol=TOL)
        p = rot.quat_to_mrp(q if q[3] >= 0 else -q)
        Cdot = rot.quat_to_dcm(rot.mrp_to_quat(p + 1j * H * rot.mrp_derivative(p, w))).imag / H
        np.testing.assert_allclose(_omega_from_dcm_rate(rot.quat_to_dcm(q), Cdot), w, atol=1e-11)


def _integrate(f, y0: np.ndarray, t: float) -> np.ndarray:
    sol = solve_ivp(f, (0.0, t), y0, method="DOP853", rtol=1e-12, atol=1e-14)
    assert sol.success
    return sol.y[:, -1]


def test_integrated_kinematics_match_constant_rate_rotation(rng):
    """Under a constant body rate, q(t) = q0 (x) exp(omega t / 2) in closed form."""
    for _ in range(5):
        q0, w, t = _quats(rng, 1)[0], rng.normal(size=3), 2.0
        q0 = q0 if q0[3] > 0 else -q0
        q_exact = rot.quat_multiply(q0, rot.axis_angle_to_quat(w, np.linalg.norm(w) * t))
        q_num = _integrate(lambda _t, q, w=w: rot.quat_derivative(q, w), q0, t)
        np.testing.assert_allclose(q_num, q_exact, atol=1e-9)

        w_small = w * (0.5 / np.linalg.norm(w))  # 1 rad in 2 s: the MRPs stay far from their singularity
        q_exact = rot.quat_multiply(q0, rot.axis_angle_to_quat(w_small, 0.5 * t))
        p_num = _integrate(lambda _t, p, w=w_small: rot.mrp_derivative(p, w), rot.quat_to_mrp(q0), t)
        assert _same_quat(rot.mrp_to_quat(p_num), q_exact) < 1e-9

        rpy0 = _rpy(rng, 1, margin=0.6)[0]
        q0 = rot.euler321_to_quat(rpy0)
        q_exact = rot.quat_multiply(q0, rot.axis_angle_to_quat(w_small, 0.5 * t))
        rpy_num = _integrate(lambda _t, a, w=w_small: rot.euler321_rates_from_body(a, w), rpy0, t)
        np.testing.assert_allclose(rot.euler321_to_dcm(rpy_num), rot.quat_to_dcm(q_exact), atol=1e-9)


# ---------------------------------------------------------------- errors


def test_errors():
    with pytest.raises(ValueError, match="zero"):
        rot.quat_normalize([0, 0, 0, 0])
    with pytest.raises(ValueError, match="zero"):
        rot.quat_to_dcm([[0, 0, 0, 1], [0, 0, 0, 0]])
    with pytest.raises(ValueError, match="axis"):
        rot.axis_angle_to_quat([0, 0, 0], 1.0)
    with pytest.raises(ValueError, match="gimbal lock"):
        rot.euler321_rates_from_body([0.1, np.pi / 2, 0.3], [1, 2, 3])
    with pytest.raises(ValueError, match="gimbal lock"):
        rot.euler321_rates_from_body([[0, 0, 0], [0.1, -np.pi / 2, 0.3]], [1, 2, 3])
    with pytest.raises(ValueError, match="infinity"):
        rot.mrp_shadow([0, 0, 0])
    with pytest.raises(ValueError, match="singular"):
        rot.quat_to_mrp([0, 0, 0, -1])
    with pytest.raises(ValueError, match="shape"):
        rot.euler321_to_dcm([1.0, 2.0])
