"""LPMPC building blocks against closed forms and integration (Feng, Chen, Yang 2018, Sec. 2).

Exact level: LGR points and weights against their closed forms, the Radau differentiation matrix on
polynomials, the MRP error matrices against complex-step derivatives. Verified level: the terminal
map against integrating the linearized and the nonlinear dynamics, and the correction cancelling the
linear miss.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from convexguid.dynamics.mrp_attitude import mrp_error_matrices, mrp_state_derivative
from convexguid.families.lpmpc.controller import box_constrained_correction, energy_optimal_correction, terminal_map
from convexguid.transcription.lgr import RadauGrid, lgr_differentiation, lgr_points, lgr_weights, radau_support

INERTIA = np.diag([5.0, 70.0, 70.0])
INERTIA_INV = np.linalg.inv(INERTIA)


def test_lgr_points_and_weights_match_closed_forms():
    # N = 2: roots of P1 + P2 are -1 and 1/3, weights 1/2 and 3/2
    np.testing.assert_allclose(lgr_points(2), [-1.0, 1.0 / 3.0], atol=1e-15)
    np.testing.assert_allclose(lgr_weights(2), [0.5, 1.5], atol=1e-15)
    # N = 3: -1, (1 -+ sqrt 6)/5; weights 2/9, (16 + sqrt 6)/18, (16 - sqrt 6)/18
    r6 = np.sqrt(6.0)
    np.testing.assert_allclose(lgr_points(3), [-1.0, (1 - r6) / 5, (1 + r6) / 5], atol=1e-15)
    np.testing.assert_allclose(lgr_weights(3), [2 / 9, (16 + r6) / 18, (16 - r6) / 18], atol=1e-15)


@pytest.mark.parametrize("n", [3, 8, 12])
def test_lgr_quadrature_is_exact_to_degree_2n_minus_2(n):
    tau, w = lgr_points(n), lgr_weights(n)
    for k in range(2 * n - 1):
        exact = 2.0 / (k + 1) if k % 2 == 0 else 0.0
        assert w @ tau**k == pytest.approx(exact, abs=1e-13), k
    assert abs(w @ tau ** (2 * n - 1)) > 1e-9  # and not beyond: a Radau rule has degree 2n - 2


@pytest.mark.parametrize("n", [3, 8, 12])
def test_differentiation_matrix_is_exact_on_polynomials_up_to_degree_n(n):
    D, s, tau = lgr_differentiation(n), radau_support(n), lgr_points(n)
    assert D.shape == (n, n + 1)
    for k in range(n + 1):
        np.testing.assert_allclose(D @ s**k, k * tau ** max(k - 1, 0) * (k > 0), atol=1e-11)
    assert np.abs(D @ s ** (n + 1) - (n + 1) * tau**n).max() > 1e-6


def _complex_step(f, x, h=1e-30):
    return np.array([np.imag(f(x + 1j * h * e)) / h for e in np.eye(x.size)]).T


def test_error_matrices_match_complex_step_derivatives_of_the_nonlinear_model():
    rng = np.random.default_rng(7)
    for _ in range(5):
        x, u = rng.normal(size=6) * 0.4, rng.normal(size=3)
        A, B = mrp_error_matrices(x, INERTIA, INERTIA_INV)
        def f_x(z, u=u):
            return mrp_state_derivative(z, u, INERTIA, INERTIA_INV)

        def f_u(v, x=x):
            return mrp_state_derivative(x.astype(complex), v, INERTIA, INERTIA_INV)

        np.testing.assert_allclose(A, _complex_step(f_x, x), atol=1e-15)
        np.testing.assert_allclose(B, _complex_step(f_u, u), atol=1e-15)


def _nominal(t):
    """A smooth slew-like nominal in MRPs (not a solution of the dynamics: A(t) only needs the states)."""
    return np.array([0.5 - 0.06 * t, 0.1 * np.sin(0.4 * t), -0.2 + 0.02 * t, -0.25, 0.04 * np.cos(0.3 * t), 0.03])


def _smooth_du(t):
    return np.array([0.1 * np.sin(0.3 * t), 0.2 * np.cos(0.2 * t) - 0.2, 0.05 * t / 8])


def _linear_flow(t_span, dx0, du_fn):
    def rhs(t, y):
        A, B = mrp_error_matrices(_nominal(t), INERTIA, INERTIA_INV)
        return A @ y + B @ du_fn(t)

    return solve_ivp(rhs, t_span, dx0, rtol=1e-12, atol=1e-14).y[:, -1]


@pytest.fixture(scope="module")
def tmap():
    grid = RadauGrid(8, 0.0, 8.0)
    A, B = mrp_error_matrices(np.array([_nominal(t) for t in grid.times]), INERTIA, INERTIA_INV)
    return terminal_map(grid, A, B)


def test_predicted_terminal_error_matches_the_integrated_linear_model(tmap):
    dx0 = np.array([2e-3, -1e-3, 5e-4, 1e-3, -2e-3, 5e-4])
    du_nodes = np.array([_smooth_du(t) for t in tmap.grid.times[1:]])
    integrated = _linear_flow((0.0, 8.0), dx0, _smooth_du)
    np.testing.assert_allclose(tmap.predict(dx0, du_nodes), integrated, atol=1e-4 * np.abs(integrated).max())


def test_sensitivity_to_each_node_control_is_the_adjoint_one(tmap):
    """K_u / (p w_k) = Phi(t_f, t_k) B_k: what makes the energy-optimal correction keep an optimal nominal."""
    grid = tmap.grid

    def adjoint(t, y):
        A, _ = mrp_error_matrices(_nominal(t), INERTIA, INERTIA_INV)
        return (-y.reshape(6, 6) @ A).ravel()

    B = np.zeros((6, 3))
    B[3:] = INERTIA_INV
    for k, t_k in enumerate(grid.times[1:], start=1):
        phi = solve_ivp(adjoint, (8.0, t_k), np.eye(6).ravel(), rtol=1e-11, atol=1e-13).y[:, -1].reshape(6, 6)
        node = tmap.Ku[:, 3 * (k - 1):3 * k] / (grid.p * grid.weights[k])
        np.testing.assert_allclose(node, phi @ B, atol=1e-4 * np.abs(phi @ B).max())


def test_prediction_matches_the_nonlinear_model_for_small_errors():
    """A nominal flown with its own torque, then a small initial error: nonlinear and linear agree to 2nd order."""
    u_nom = lambda t: np.array([0.2 * np.cos(t / 3), -1.0 + 0.3 * t, 0.5])  # noqa: E731
    x_nom0 = np.array([0.3, -0.1, 0.2, 0.02, 0.05, -0.03])
    flow = lambda x0: solve_ivp(lambda t, x: mrp_state_derivative(x, u_nom(t), INERTIA, INERTIA_INV), (0, 6), x0,  # noqa: E731
                                rtol=1e-12, atol=1e-14, dense_output=True)
    nominal = flow(x_nom0)
    grid = RadauGrid(10, 0.0, 6.0)
    A, B = mrp_error_matrices(nominal.sol(grid.times).T, INERTIA, INERTIA_INV)
    tm = terminal_map(grid, A, B)
    for scale in (1e-3, 1e-4):
        dx0 = scale * np.array([1.0, -0.5, 0.3, 0.2, 0.4, -0.1])
        actual = flow(x_nom0 + dx0).y[:, -1] - nominal.y[:, -1]
        error = np.abs(tm.predict(dx0) - actual).max()
        assert error < 20 * scale**2 + 1e-9, (scale, error)  # second order in the initial error


def test_one_correction_cancels_the_linear_miss_exactly(tmap):
    miss = np.array([0.01, -0.02, 0.005, 1e-3, -2e-3, 4e-3])
    u_nodes = np.array([_smooth_du(t) for t in tmap.grid.times[1:]]) * 10
    du = energy_optimal_correction(tmap, u_nodes, miss)
    np.testing.assert_allclose(tmap.predict(np.zeros(6), du), -miss, atol=1e-12)
    # among all corrections that cancel the miss, this one has the least corrected-control energy
    null = np.linalg.svd(tmap.Ku)[2][6:].T
    omega = np.repeat(tmap.energy_weights, 3)
    best = omega @ (u_nodes.ravel() + du.ravel()) ** 2
    rng = np.random.default_rng(3)
    for _ in range(20):
        other = du.ravel() + null @ rng.normal(size=null.shape[1]) * 0.1
        assert omega @ (u_nodes.ravel() + other) ** 2 > best


def test_box_constrained_correction_keeps_the_box_and_still_cancels_the_miss(tmap):
    miss = np.array([0.02, -0.02, 0.01, 2e-3, -4e-3, 4e-3])
    u_nodes = np.array([_smooth_du(t) for t in tmap.grid.times[1:]]) * 10
    free = energy_optimal_correction(tmap, u_nodes, miss)
    loose = box_constrained_correction(tmap, u_nodes, miss, np.full(3, 1e3))
    np.testing.assert_allclose(loose, free, atol=1e-6)
    limit = 0.9 * np.abs(u_nodes + free).max(axis=0)
    boxed = box_constrained_correction(tmap, u_nodes, miss, limit)
    assert boxed is not None
    assert np.all(np.abs(u_nodes + boxed) <= limit * (1 + 1e-6))
    np.testing.assert_allclose(tmap.predict(np.zeros(6), boxed), -miss, atol=1e-7)
    assert box_constrained_correction(tmap, u_nodes, miss, np.full(3, 1e-6)) is None  # no room: honest None
