"""Mapped Chebyshev transcription (Cai et al. 2018, eqs. 17-28) against closed forms."""

import numpy as np
import pytest

from convexguid.transcription.mapped_chebyshev import (
    MappedChebyshev,
    cgl_barycentric_weights,
    cgl_nodes,
    clenshaw_curtis_weights,
    kosloff_tal_ezer_alpha,
    kte_map,
    kte_map_derivative,
)


def test_map_parameter_matches_paper():
    # Paper Sec. 3: N = 32, eps = 1e-6 gives alpha = 0.9135.
    assert kosloff_tal_ezer_alpha(32, 1e-6) == pytest.approx(0.9135, abs=5e-5)


def test_cgl_nodes_and_weights_closed_form():
    n = 7
    k = np.arange(n + 1)
    np.testing.assert_allclose(cgl_nodes(n), np.cos(np.pi * k / n), atol=1e-15)
    w = cgl_barycentric_weights(n)
    assert w[0] == 0.5 and w[-1] == -0.5 and np.all(np.abs(w[1:-1]) == 1.0)
    assert not cgl_nodes(n).flags.writeable


def test_map_fixes_endpoints_and_derivative_is_exact():
    alpha = 0.9
    assert kte_map(np.array([-1.0, 1.0]), alpha) == pytest.approx([-1.0, 1.0], abs=1e-15)
    tau = np.linspace(-0.9, 0.9, 7)
    h = 1e-30  # complex step: exact derivative of the map
    np.testing.assert_allclose(kte_map_derivative(tau, alpha),
                               np.imag(np.arcsin(alpha * (tau + 1j * h)) / np.arcsin(alpha)) / h, rtol=1e-13)


@pytest.mark.parametrize("n", [4, 5, 16, 33])
def test_clenshaw_curtis_integrates_polynomials_exactly(n):
    w = clenshaw_curtis_weights(n)
    x = cgl_nodes(n)
    assert w.sum() == pytest.approx(2.0, abs=1e-14)
    for degree in range(n + 1):
        exact = 0.0 if degree % 2 else 2.0 / (degree + 1)
        assert w @ x**degree == pytest.approx(exact, abs=1e-13)


def test_paper_formula_for_odd_n_end_weight():
    assert clenshaw_curtis_weights(5)[0] == pytest.approx(1 / 25, abs=1e-15)
    assert clenshaw_curtis_weights(6)[0] == pytest.approx(1 / 35, abs=1e-15)


def test_differentiation_matrices_exact_on_low_degree_polynomials():
    grid = MappedChebyshev(12, 1e-6)
    x = grid.nodes
    # Rows of D sum to zero (constants), D x = 1; D2 x^2 = 2 exactly for the rational interpolant.
    np.testing.assert_allclose(grid.d1 @ np.ones_like(x), 0.0, atol=1e-11)
    np.testing.assert_allclose(grid.d1 @ x, 1.0, atol=1e-11)
    np.testing.assert_allclose(grid.d2 @ x, 0.0, atol=1e-9)
    np.testing.assert_allclose(grid.d2 @ x**2, 2.0, atol=1e-9)


def test_differentiation_converges_spectrally_on_smooth_functions():
    errors = []
    for n in (8, 16, 32):
        grid = MappedChebyshev(n, 1e-12)
        x = grid.nodes
        errors.append(np.abs(grid.d1 @ np.sin(2 * x) - 2 * np.cos(2 * x)).max())
    assert errors[1] < 1e-3 * errors[0] and errors[2] < 1e-8


def test_mapped_quadrature_of_known_integrals():
    grid = MappedChebyshev(32, 1e-6)
    w, x = grid.quadrature_weights, grid.nodes
    assert w.sum() == pytest.approx(2.0, abs=1e-8)
    assert w @ np.exp(x) == pytest.approx(np.e - 1 / np.e, rel=1e-8)
    assert w @ np.cos(3 * x) == pytest.approx(2 * np.sin(3) / 3, abs=1e-8)


def test_barycentric_interpolation_reproduces_nodes_and_smooth_functions():
    grid = MappedChebyshev(24, 1e-8)
    x = grid.nodes
    L = grid.interpolation_matrix(x)
    np.testing.assert_allclose(L, np.eye(x.size), atol=0)
    pts = np.linspace(-1, 1, 101)
    np.testing.assert_allclose(grid.interpolation_matrix(pts) @ np.exp(x), np.exp(pts), atol=1e-8)


def test_nodes_increase_and_times_map_interval():
    grid = MappedChebyshev(10, 1e-6)
    assert np.all(np.diff(grid.nodes) > 0)
    t = grid.times(5.0, 25.0)
    assert t[0] == pytest.approx(5.0) and t[-1] == pytest.approx(25.0)


@pytest.mark.parametrize("n, eps", [(1, 1e-6), (8, 0.0), (8, 1.0)])
def test_invalid_grid_rejected(n, eps):
    with pytest.raises(ValueError):
        MappedChebyshev(n, eps)
