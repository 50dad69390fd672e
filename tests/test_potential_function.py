"""Potential-function attitude controller of Guo, Li, Ma (2011) and its reaction-wheel simulation."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from convexguid.dynamics.disturbance import guo2011_disturbance, no_disturbance
from convexguid.errors import SpecError
from convexguid.families.potential_function.controller import (
    PotentialFunctionController,
    PotentialFunctionGains,
    angle_to_plane,
    attractive_potential,
    barrier_offset,
    error_quaternion,
    guo2011_adaptive_gains,
    guo2011_fixed_gains,
    repulsive_potential,
)
from convexguid.families.potential_function.plant import (
    GUO2011_INERTIA,
    GUO2011_Q0,
    GUO2011_Q_COMMAND,
    GUO2011_Q_FORBIDDEN,
    maneuver_metrics,
    quaternion_rate,
    settling_time,
    simulate,
)
from convexguid.rotations import (
    axis_angle_to_quat,
    quat_angle_between,
    quat_derivative,
    quat_multiply,
    quat_normalize,
    quat_to_dcm,
)

DEG = math.pi / 180
RNG = np.random.default_rng(20110301)


def _controller(gains: PotentialFunctionGains, forbidden: bool = True,
                cls: type = PotentialFunctionController) -> PotentialFunctionController:
    return cls(GUO2011_INERTIA, GUO2011_Q_COMMAND, gains, GUO2011_Q_FORBIDDEN if forbidden else None)


def _run(gains: PotentialFunctionGains, dt: float, t_final: float, forbidden: bool = True,
         cls: type = PotentialFunctionController):
    result = simulate(_controller(gains, forbidden, cls), GUO2011_INERTIA, GUO2011_Q0, np.zeros(3),
                      GUO2011_Q_COMMAND, t_final, dt)
    return result, maneuver_metrics(result)


def _random_quat() -> np.ndarray:
    return quat_normalize(RNG.normal(size=4))


# ---------------------------------------------------------------------------------------------- unit level


def test_error_quaternion_is_eq5_matrix_and_hamilton_convention():
    q, qc = _random_quat(), _random_quat()
    x, y, z, w = qc  # eq. 5, rows written out from the paper
    m = np.array([[w, z, -y, -x], [-z, w, x, -y], [y, -x, w, -z], [x, y, z, w]])
    e = error_quaternion(q, qc)
    np.testing.assert_allclose(e, m @ q, atol=1e-14)
    np.testing.assert_allclose(quat_multiply(qc, e), q, atol=1e-14)  # q = q_c (x) e
    np.testing.assert_allclose(error_quaternion(qc, qc), [0, 0, 0, 1], atol=1e-15)
    assert 2 * math.acos(min(1.0, abs(e[3]))) == pytest.approx(float(quat_angle_between(q, qc)), abs=1e-7)


def test_quaternion_rate_matches_rotations_kinematics():
    q, w = _random_quat(), RNG.normal(size=3)
    np.testing.assert_allclose(quaternion_rate(q, w), quat_derivative(q, w), atol=1e-15)


def test_attractive_potential_zero_only_at_command():
    assert attractive_potential([0, 0, 0, 1]) == 0
    for _ in range(20):
        e = _random_quat()
        assert attractive_potential(e) > 0
        assert attractive_potential(e) == pytest.approx(2 - 2 * e[3])


def test_repulsive_potential_positive_outside_and_blows_up_on_boundary():
    eta, theta_m = 120.0, 10 * DEG
    b_edge = axis_angle_to_quat([1.0, 2.0, 3.0], theta_m)
    assert b_edge @ b_edge - 2 * b_edge[3] + 1 == pytest.approx(barrier_offset(theta_m))
    values = [repulsive_potential(axis_angle_to_quat([1.0, 2.0, 3.0], a), eta, theta_m)
              for a in np.array([10.001, 10.1, 12, 20, 45, 90, 180]) * DEG]
    assert all(v > 0 for v in values)
    assert np.all(np.diff(values) < 0)  # grows as the forbidden attitude is approached
    assert values[0] > 1e3
    assert repulsive_potential(axis_angle_to_quat([0, 0, 1.0], 9 * DEG), eta, theta_m) < 0  # inside Q_bm


def test_angle_to_plane_matches_spherical_trigonometry():
    for _ in range(30):
        a_e = quat_normalize(np.r_[RNG.normal(size=3), 0.0])[:3]
        b = _random_quat()
        b = -b if b[3] < 0 else b
        a_b = b[:3] / np.linalg.norm(b[:3])
        theta_b = 2 * math.atan2(np.linalg.norm(b[:3]), b[3])
        phi = math.acos(np.clip(a_e @ a_b, -1, 1))
        expected = math.asin(abs(math.sin(theta_b)) * math.sin(phi))
        assert angle_to_plane(a_e, b) == pytest.approx(expected, abs=1e-9)
    assert angle_to_plane(np.array([0, 0, -1.0]), error_quaternion(GUO2011_Q0, GUO2011_Q_FORBIDDEN)) == 0


def _state_with_active_potential():
    """A state off the slew axis, moving toward q_b, where all three existence conditions hold."""
    q = quat_multiply(axis_angle_to_quat([0, 0, 1.0], 12 * DEG), axis_angle_to_quat([1.0, 0.3, 0], 3 * DEG))
    return q, np.array([0.001, -0.002, 0.02])


def test_virtual_rate_is_minus_s_times_complex_step_gradient_of_potential():
    gains = guo2011_fixed_gains()
    q, omega = _state_with_active_potential()
    u, info = _controller(gains).torque(0.0, q, omega)
    assert info.potential_active and info.v_r > 0

    def potential(v: np.ndarray) -> complex:  # V_a + V_r at q (x) [v/2, 1], v a small body rotation
        qp = quat_multiply(q, np.r_[v / 2, 1.0])
        return (attractive_potential(error_quaternion(qp, GUO2011_Q_COMMAND))
                + repulsive_potential(error_quaternion(qp, GUO2011_Q_FORBIDDEN), gains.eta, gains.theta_m))

    h = 1e-20
    grad = np.array([potential(1j * h * np.eye(3)[k]).imag / h for k in range(3)])
    np.testing.assert_allclose(-info.omega_c / gains.s, grad, rtol=1e-10, atol=1e-14)
    # ... and a central finite difference agrees too
    fd = np.array([(potential(1e-6 * np.eye(3)[k]) - potential(-1e-6 * np.eye(3)[k])) / 2e-6 for k in range(3)])
    np.testing.assert_allclose(fd, grad, rtol=1e-6)


def test_backstepping_law_gives_eq20_lyapunov_derivative():
    """dV_t/dt along the closed loop equals -s|R_eb|^2 - g mu |R_web|^2 + mu R_web^T I^-1 u_d (eq. 20)."""
    gains = guo2011_fixed_gains()
    ctrl = _controller(gains)
    q, omega = _state_with_active_potential()
    h_w = np.array([1.0, -2.0, 3.0])
    u, info = ctrl.torque(0.0, q, omega, h_w)
    assert info.potential_active and not info.escape_active
    u_d = guo2011_disturbance(100.0)
    inertia = GUO2011_INERTIA
    q_dot = quat_derivative(q, omega)
    w_dot = np.linalg.solve(inertia, u + u_d - np.cross(omega, inertia @ omega + h_w))

    def lyapunov(qq: np.ndarray, w: np.ndarray) -> complex:  # eq. 17, potential held active
        e, b = error_quaternion(qq, GUO2011_Q_COMMAND), error_quaternion(qq, GUO2011_Q_FORBIDDEN)
        v_r = repulsive_potential(b, gains.eta, gains.theta_m)
        r_web = w + gains.s * (e[:3] - gains.eta * v_r**2 * b[:3])
        return attractive_potential(e) + v_r + 0.5 * gains.mu * r_web @ r_web

    h = 1e-20
    v_dot = lyapunov(q + 1j * h * q_dot, omega + 1j * h * w_dot).imag / h
    r_eb = -info.omega_c / gains.s
    r_web = omega + gains.s * r_eb
    expected = (-gains.s * r_eb @ r_eb - gains.g * gains.mu * r_web @ r_web
                + gains.mu * r_web @ np.linalg.solve(inertia, u_d))
    assert v_dot == pytest.approx(expected, rel=1e-9)


def test_existence_conditions_switch_as_described():
    ctrl = _controller(guo2011_fixed_gains())
    e0 = error_quaternion(GUO2011_Q0, GUO2011_Q_COMMAND)
    b0 = error_quaternion(GUO2011_Q0, GUO2011_Q_FORBIDDEN)
    # at rest at q0: forbidden nearer than command (1), not approaching (2), on the slew's great circle (3)
    assert ctrl.existence_conditions(e0, b0, np.zeros(3)) == ((True, False, True), 0.0)
    assert ctrl.existence_conditions(e0, b0, np.array([0, 0, 0.01]))[0] == (True, True, True)  # toward q_b
    assert ctrl.existence_conditions(e0, b0, np.array([0, 0, -0.01]))[0][1] is False  # away from q_b
    _, info = ctrl.torque(0.0, GUO2011_Q0, np.array([0, 0, 0.01]))
    assert info.potential_active and info.v_r > 0
    _, info = ctrl.torque(0.0, GUO2011_Q0, np.zeros(3))
    assert not info.potential_active and info.v_r == 0
    # condition 1 fails near the command: theta_b - theta_m = 30 deg > theta_e = 5 deg
    q85 = axis_angle_to_quat([0, 0, 1.0], 85 * DEG)
    e, b = error_quaternion(q85, GUO2011_Q_COMMAND), error_quaternion(q85, GUO2011_Q_FORBIDDEN)
    assert ctrl.existence_conditions(e, b, np.array([0, 0, -0.01]))[0] == (False, True, True)
    # condition 3: off the slew axis theta_be grows; it holds only while theta_be < theta_0
    q = quat_multiply(axis_angle_to_quat([0, 0, 1.0], 20 * DEG), axis_angle_to_quat([1.0, 0, 0], 25 * DEG))
    e, b = error_quaternion(q, GUO2011_Q_COMMAND), error_quaternion(q, GUO2011_Q_FORBIDDEN)
    (_, _, c3), theta_be = ctrl.existence_conditions(e, b, np.zeros(3))
    assert theta_be > 12 * DEG and not c3
    wide = PotentialFunctionController(GUO2011_INERTIA, GUO2011_Q_COMMAND,
                                       guo2011_fixed_gains(10 * DEG, 1.2 * theta_be), GUO2011_Q_FORBIDDEN)
    assert wide.existence_conditions(e, b, np.zeros(3))[0][2]
    # no forbidden attitude: no repulsion at all (eq. 22)
    _, info = _controller(guo2011_fixed_gains(), forbidden=False).torque(0.0, GUO2011_Q0, np.array([0, 0, 0.01]))
    assert info.conditions == (False, False, False) and math.isnan(info.theta_b)


def test_fixed_gain_torque_at_start_is_linear_backstepping():
    u, info = _controller(guo2011_fixed_gains()).torque(0.0, GUO2011_Q0, np.zeros(3))
    # eq. 22 at rest: u = -(g s + 1/mu) I e with e_z = -sin 45 deg
    np.testing.assert_allclose(u, [0, 0, (1 + 1 / 20) * 600 * math.sin(math.pi / 4)], atol=1e-12)
    assert info.theta_b == pytest.approx(45 * DEG) and info.theta_e == pytest.approx(90 * DEG)


def test_adaptive_gains_follow_eqs_26_to_30():
    gains = guo2011_adaptive_gains()
    _, info = _controller(gains).torque(0.0, GUO2011_Q0, np.zeros(3))
    e_z = math.sin(math.pi / 4)
    assert info.mu == pytest.approx(600 * e_z / 0.2)  # eq. 26: ||I e||_inf / u_mu
    assert info.s == pytest.approx(1.91 * DEG / e_z)  # eq. 30: rate limit binds (R_s = 0 at rest)
    assert info.g == pytest.approx(0.1 / (600 * info.s * e_z))  # eq. 28 with the adapted s
    assert np.abs(info.omega_c).max() == pytest.approx(1.91 * DEG)
    # at rest on the command the bounds mu_min, s_max, g_max are used
    _, info = _controller(gains).torque(0.0, GUO2011_Q_COMMAND, np.zeros(3))
    assert (info.mu, info.s, info.g) == (20.0, 1.0, 1.0)


def test_escape_torque_is_orthogonal_full_magnitude_and_follows_rotation():
    ctrl = _controller(guo2011_adaptive_gains())
    for omega in ([0, 0, 1e-4], [0, 3e-3, 1e-4], [0, -3e-3, 1e-4]):
        u, info = ctrl.torque(0.0, GUO2011_Q0, np.array(omega))
        assert info.potential_active and info.escape_active
        assert u[2] == 0 and np.abs(u).max() == pytest.approx(0.5)  # orthogonal to a_e = -z, |u|_inf = u_max
        assert u @ omega >= 0  # sgn(w^T a_e x a_r): pushes along the existing rotation (sgn(0) = +1)


@pytest.mark.parametrize("kwargs", [
    {"theta_0": 10 * DEG}, {"theta_0": 9 * DEG}, {"g": 0.0}, {"s": -1.0}, {"mu": math.nan}, {"eta": 0.0},
    {"theta_m": 0.0}, {"theta_m": 4.0, "theta_0": 5.0}, {"u_max": -0.5}, {"theta_lm": 1 * DEG},
    {"w_max": 0.03}, {"u_mu": 0.2}, {"u_mu": 0.2, "u_s": 0.2, "u_g": 0.1, "mu_min": 20, "s_max": 1, "g_max": 0},
])
def test_bad_gains_raise_spec_error(kwargs):
    base = {"g": 1.0, "s": 1.0, "mu": 20.0, "eta": 120.0, "theta_m": 10 * DEG, "theta_0": 12 * DEG}
    with pytest.raises(SpecError, match="PotentialFunctionGains"):
        PotentialFunctionGains(**{**base, **kwargs})


def test_bad_controller_and_simulation_inputs_raise_spec_error():
    gains = guo2011_fixed_gains()
    with pytest.raises(SpecError, match="inertia"):
        PotentialFunctionController(np.diag([1.0, -1.0, 1.0]), GUO2011_Q_COMMAND, gains)
    with pytest.raises(SpecError, match="q_forbidden"):
        PotentialFunctionController(GUO2011_INERTIA, GUO2011_Q_COMMAND, gains, np.zeros(4))
    ctrl = _controller(gains)
    with pytest.raises(SpecError, match="dt"):
        simulate(ctrl, GUO2011_INERTIA, GUO2011_Q0, np.zeros(3), GUO2011_Q_COMMAND, 10.0, 0.0)
    with pytest.raises(SpecError, match="differs"):
        simulate(ctrl, GUO2011_INERTIA, GUO2011_Q0, np.zeros(3), GUO2011_Q_FORBIDDEN, 10.0, 0.1)


def test_settling_time_and_disturbance():
    t = np.arange(6.0)
    assert settling_time(t, np.array([5, 3, 0.5, 2, 0.5, 0.1]), 1.0) == 4.0
    assert settling_time(t, np.array([5, 3, 0.5, 2, 0.5, 1.5]), 1.0) is None
    assert settling_time(t, np.zeros(6), 1.0) == 0.0
    np.testing.assert_allclose(guo2011_disturbance(100.0), 1e-3 * np.array([math.sin(1) - 0.5, math.sin(1) + 0.5,
                                                                            math.cos(1)]))


def test_internal_torques_conserve_inertial_momentum_and_quaternion_norm():
    info = _controller(guo2011_fixed_gains()).torque(0.0, GUO2011_Q0, np.zeros(3))[1]

    class ConstantTorque:
        q_command = GUO2011_Q_COMMAND

        def torque(self, t, q, omega, h_w=None):
            return np.array([0.1, -0.2, 0.3]), info

    r = simulate(ConstantTorque(), GUO2011_INERTIA, GUO2011_Q0, [0.01, -0.02, 0.03], GUO2011_Q_COMMAND, 20.0, 0.1,
                 disturbance=no_disturbance)
    # wheel torques are internal: the inertial angular momentum C_BI^T (I w + h_w) is constant
    h_inertial = np.einsum("nji,nj->ni", quat_to_dcm(r.q), r.omega @ GUO2011_INERTIA + r.h_w)
    np.testing.assert_allclose(h_inertial, np.broadcast_to(h_inertial[0], h_inertial.shape), atol=1e-9)
    assert np.abs(h_inertial[0]).max() > 1.0
    np.testing.assert_allclose(np.linalg.norm(r.q, axis=1), 1.0, atol=1e-14)


# ---------------------------------------------------------------------------------------------- Sec. 4 scenarios


@pytest.fixture(scope="module")
def fig2():
    return [_run(guo2011_fixed_gains(), dt, 40.0) for dt in (0.01, 0.005)]


@pytest.fixture(scope="module")
def fig3():
    return [_run(guo2011_adaptive_gains(), dt, 260.0) for dt in (0.1, 0.05)]


def test_fig2_fixed_gains_avoid_forbidden_attitude_in_about_25_s(fig2):
    (r, m), _ = fig2
    assert 20.0 < m.t_1deg < 32.0  # paper: "about 25 s"; measured 26.9 s
    assert m.t_01deg is not None and m.final_error_deg < 0.01
    assert np.all(r.theta_b > 10 * DEG) and m.min_theta_b_deg > 15.0
    assert 100.0 < m.max_abs_u < 2000.0  # hundreds of N m (paper ~1000 N m; measured 445 N m)
    assert r.potential_active.any() and not r.escape_active.any() and not r.saturated.any()


def test_fig2_insensitive_to_halving_the_step(fig2):
    (_, m1), (_, m2) = fig2
    assert m2.t_1deg == pytest.approx(m1.t_1deg, abs=0.2)
    assert m2.t_01deg == pytest.approx(m1.t_01deg, abs=0.2)
    assert m2.min_theta_b_deg == pytest.approx(m1.min_theta_b_deg, abs=0.5)


def test_fig3_adaptive_gains_respect_torque_limit_and_avoid(fig3):
    (r, m), _ = fig3
    assert np.abs(r.u).max() <= 0.5
    assert np.abs(r.u_unclipped).max() <= 0.5 + 1e-3  # eq. 25 holds up to the neglected gyroscopic term
    assert np.all(r.theta_b > 10 * DEG)
    assert m.t_01deg is not None and m.t_01deg < 250.0 and m.final_error_deg < 0.01
    assert r.escape_active[: int(round(10.0 / r.dt))].any()  # escape acts at the start of the maneuver
    assert not r.escape_active[int(round(50.0 / r.dt)):].any()


def test_fig3_insensitive_to_halving_the_step(fig3):
    (_, m1), (_, m2) = fig3
    assert m2.t_1deg == pytest.approx(m1.t_1deg, abs=1.0)
    assert m2.t_01deg == pytest.approx(m1.t_01deg, abs=1.0)
    assert m2.min_theta_b_deg == pytest.approx(m1.min_theta_b_deg, abs=0.5)
    assert m2.energy == pytest.approx(m1.energy, rel=0.02)


def test_fig3_escape_law_shortens_the_maneuver(fig3):
    _, m = _run(dataclasses.replace(guo2011_adaptive_gains(), theta_lm=None), 0.1, 260.0)
    assert m.t_1deg > fig3[0][1].t_1deg + 20.0


@pytest.mark.parametrize("theta_m_deg", [5.0, 20.0, 40.0])
def test_fig4_avoidance_for_a_range_of_forbidden_angles(theta_m_deg):
    r, m = _run(guo2011_adaptive_gains(theta_m_deg * DEG), 0.1, 300.0)
    assert np.all(r.theta_b > theta_m_deg * DEG)
    assert np.abs(r.u).max() <= 0.5
    assert m.t_01deg is not None and m.final_error_deg < 0.01


def test_fig5_no_forbidden_attitude(fig3):
    r, m = _run(guo2011_adaptive_gains(), 0.1, 220.0, forbidden=False)
    assert not r.potential_active.any() and np.isnan(m.min_theta_b_deg)
    assert np.abs(r.u_unclipped).max() <= 0.5
    assert m.t_01deg is not None and m.t_1deg < fig3[0][1].t_1deg  # no detour: faster than Fig. 3
    assert np.degrees(np.abs(r.omega).max()) < 1.91


def test_printed_condition_3_would_pass_through_the_forbidden_attitude():
    class AsPrinted(PotentialFunctionController):
        def existence_conditions(self, e, b, omega):
            (c1, c2, c3), theta_be = super().existence_conditions(e, b, omega)
            return (c1, c2, not c3 and not math.isnan(theta_be)), theta_be

    r, m = _run(guo2011_fixed_gains(), 0.01, 4.0, cls=AsPrinted)
    assert not r.potential_active.any() and m.min_theta_b_deg < 1.0
