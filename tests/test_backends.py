"""Backend registry and the conic-program interface (design.md: backends by name)."""

import numpy as np
import pytest
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram, available_backends, make_backend
from convexguid.errors import BackendError


def small_qp(shift: float = 0.0) -> ConicProgram:
    """min (x0-1)^2 + (x1-2)^2  s.t.  x0 + x1 = 1 + shift, x0 >= 0.2.

    KKT by hand: unconstrained in the bound x0 = (shift)/2, so x = (0.2, 0.8) for shift 0 and
    (0.25, 1.25) for shift 0.5 (bound inactive).
    """
    P = sp.csc_matrix(np.diag([2.0, 2.0]))
    q = np.array([-2.0, -4.0])
    A = sp.csc_matrix(np.array([[1.0, 1.0], [-1.0, 0.0]]))
    b = np.array([1.0 + shift, -0.2])
    return ConicProgram(P, q, A, b, Cones(zero=1, nonneg=1))


@pytest.mark.parametrize("name", ["clarabel", "osqp", "qpsolvers:clarabel"])
def test_backends_agree_on_a_qp_with_known_solution(name):
    backend = make_backend(name, small_qp(), tolerance=1e-9)
    res = backend.solve()
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [0.2, 0.8], atol=1e-6)
    backend.update(small_qp(shift=0.5))
    np.testing.assert_allclose(backend.solve().x, [0.25, 1.25], atol=1e-6)


def test_objective_uses_upper_triangle():
    prog = small_qp()
    prog.P = sp.csc_matrix(np.array([[2.0, 1.0], [0.0, 2.0]]))
    x = np.array([1.0, -1.0])
    full = np.array([[2.0, 1.0], [1.0, 2.0]])
    assert prog.objective(x) == pytest.approx(0.5 * x @ full @ x + prog.q @ x)


def test_unknown_backend_lists_installed():
    with pytest.raises(BackendError) as info:
        make_backend("no-such-solver", small_qp())
    message = str(info.value)
    assert "no-such-solver" in message and "clarabel" in message and "osqp" in message
    assert "clarabel" in available_backends()


def test_infeasible_program_reported():
    prog = small_qp()
    prog.A = sp.csc_matrix(np.array([[1.0, 1.0], [-1.0, -1.0]]))
    prog.b = np.array([1.0, -2.0])  # x0 + x1 = 1 and x0 + x1 >= 2
    assert make_backend("clarabel", prog).solve().status == "infeasible"


def test_update_rejects_a_new_sparsity_pattern():
    backend = make_backend("clarabel", small_qp())
    other = small_qp()
    other.A = sp.csc_matrix(np.array([[1.0, 0.0], [-1.0, 0.0]]))
    with pytest.raises(ValueError):
        backend.update(other)


def test_osqp_refuses_second_order_cones():
    prog = ConicProgram(sp.csc_matrix((3, 3)), np.array([1.0, 0, 0]), sp.csc_matrix(-np.eye(3)), np.zeros(3),
                        Cones(soc=(3,)))
    with pytest.raises(BackendError):
        make_backend("osqp", prog)
    res = make_backend("clarabel", prog).solve()
    assert res.status == "optimal" and res.x[0] == pytest.approx(0.0, abs=1e-6)
