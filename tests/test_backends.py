"""Backend registry and the conic-program interface (backends by name)."""

import numpy as np
import pytest
import scipy.sparse as sp

from convexguid.backends import (
    BackendResult,
    Cones,
    ConicProgram,
    FallbackBackend,
    auto_backend,
    available_backends,
    make_backend,
)
from convexguid.backends.dense import DaqpBackend
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


@pytest.mark.parametrize("name", ["clarabel", "osqp", "piqp", "qpsolvers:clarabel", "daqp", "auto"])
def test_backends_agree_on_a_qp_with_known_solution(name):
    backend = make_backend(name, small_qp(), tolerance=1e-9)
    res = backend.solve()
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [0.2, 0.8], atol=1e-6)
    backend.update(small_qp(shift=0.5))
    np.testing.assert_allclose(backend.solve().x, [0.25, 1.25], atol=1e-6)


def test_clarabel_without_iterative_refinement_gives_the_same_answer():
    """The setting reaches Clarabel (and the fallback of a dense backend), and the solution is unchanged."""
    plain = make_backend("clarabel", small_qp(), tolerance=1e-9, iterative_refinement=False)
    assert plain._solver.get_settings().iterative_refinement_enable is False
    assert make_backend("clarabel", small_qp())._solver.get_settings().iterative_refinement_enable is True
    res = plain.solve()
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [0.2, 0.8], atol=1e-6)
    fallback = make_backend("daqp", small_qp(), fallback="clarabel", iterative_refinement=False)
    assert isinstance(fallback, FallbackBackend) and fallback.iterative_refinement is False


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


@pytest.mark.parametrize("name", ["osqp", "piqp"])
def test_qp_backends_refuse_second_order_cones(name):
    prog = ConicProgram(sp.csc_matrix((3, 3)), np.array([1.0, 0, 0]), sp.csc_matrix(-np.eye(3)), np.zeros(3),
                        Cones(soc=(3,)))
    with pytest.raises(BackendError):
        make_backend(name, prog)
    res = make_backend("clarabel", prog).solve()
    assert res.status == "optimal" and res.x[0] == pytest.approx(0.0, abs=1e-6)


# --- the dense backend and the auto choice -------------------------------------------------------

def penalized_qp(seed: int, penalty: float = 1.0) -> ConicProgram:
    """A random program shaped like an SCP subproblem: a strictly convex QP in 6 core variables with
    equalities, hard inequalities, a box, and penalty slacks, 4 on one row each and 2 on opposite rows.

    Variables ``[x (6), s_hinge (4), t_abs (2)]``. Rows: zero cone ``E x = f`` (2); nonnegative cone
    ``G x <= h`` (2), ``a_i'x - s_i <= b_i`` (4), ``c_j'x - t_j <= -e_j`` and ``-c_j'x - t_j <= e_j`` (2 + 2),
    ``-s, -t <= 0`` (6), ``|x| <= 1.5`` (12). With ``penalty`` 1 some penalties are paid at the optimum.
    """
    rng = np.random.default_rng(seed)
    n, n_h, n_a = 6, 4, 2
    L = rng.normal(size=(n, n))
    H = L @ L.T + 0.1 * np.eye(n)
    E, G = rng.normal(size=(2, n)), rng.normal(size=(2, n))
    Ah, Ac = rng.normal(size=(n_h, n)), rng.normal(size=(n_a, n))
    bh, e = rng.normal(size=n_h), rng.normal(size=n_a)
    N = n + n_h + n_a
    hinge = np.hstack([Ah, -np.eye(n_h), np.zeros((n_h, n_a))])
    plus = np.hstack([Ac, np.zeros((n_a, n_h)), -np.eye(n_a)])
    minus = np.hstack([-Ac, np.zeros((n_a, n_h)), -np.eye(n_a)])
    slack_bounds = np.hstack([np.zeros((n_h + n_a, n)), -np.eye(n_h + n_a)])
    box = np.hstack([np.vstack([np.eye(n), -np.eye(n)]), np.zeros((2 * n, n_h + n_a))])
    A = np.vstack([np.hstack([E, np.zeros((2, n_h + n_a))]), np.hstack([G, np.zeros((2, n_h + n_a))]),
                   hinge, plus, minus, slack_bounds, box])
    b = np.concatenate([np.zeros(2), np.abs(rng.normal(size=2)), bh, -e, e, np.zeros(n_h + n_a), np.full(2 * n, 1.5)])
    P = np.zeros((N, N))
    P[:n, :n] = H
    q = np.concatenate([rng.normal(size=n) * 5, np.full(n_h + n_a, penalty)])
    return ConicProgram(sp.csc_matrix(np.triu(P)), q, sp.csc_matrix(A), b,
                        Cones(zero=2, nonneg=A.shape[0] - 2))


@pytest.mark.parametrize("seed", range(6))
def test_daqp_solves_penalty_slacks_as_pieces_exactly(seed):
    """DAQP sees the 6 core variables only; its answer, slacks and row multipliers, is Clarabel's."""
    program = penalized_qp(seed)
    backend = make_backend("daqp", program, tolerance=1e-9)
    layout = backend._layout
    assert (layout.core.size, layout.hinge.size, layout.absolute.size) == (6, 4, 2)
    res = backend.solve()
    ref = make_backend("clarabel", program, tolerance=1e-10).solve()
    assert res.status == ref.status == "optimal"
    assert res.objective == pytest.approx(ref.objective, rel=1e-8, abs=1e-8)
    np.testing.assert_allclose(res.x, ref.x, atol=1e-6)
    assert res.primal_residual <= 1e-9 and res.dual_residual <= 1e-8
    nz = program.cones.zero
    assert np.all(res.z[nz:] >= 0)
    # the equality rows' multipliers (the SCP's curvature needs them) and the hinge rows' are unique
    np.testing.assert_allclose(res.z[:8], ref.z[:8], atol=1e-6)
    # the opposite rows of an |.| penalty: only their difference is determined
    np.testing.assert_allclose(res.z[8:10] - res.z[10:12], ref.z[8:10] - ref.z[10:12], atol=1e-6)


def with_second_bound(program: ConicProgram, var: int, limit: float) -> ConicProgram:
    """``program`` with one more row, ``x_var <= limit``, after its others: a second upper bound on that variable."""
    row = sp.csc_matrix(([1.0], ([0], [var])), shape=(1, program.A.shape[1]))
    cones = Cones(zero=program.cones.zero, nonneg=program.cones.nonneg + 1)
    return ConicProgram(program.P, program.q, sp.vstack([program.A, row]).tocsc(), np.append(program.b, limit), cones)


@pytest.mark.parametrize("seed", range(6))
def test_piqp_takes_single_variable_rows_as_bounds_and_returns_every_rows_multiplier(seed):
    """The slacks' and the box's rows become PIQP's bounds; the answer is Clarabel's, and the multipliers handed back
    in the program's own rows meet the KKT conditions (a bound's on the tighter of its two rows)."""
    program = with_second_bound(penalized_qp(seed), var=seed % 6, limit=0.3)
    backend = make_backend("piqp", program, tolerance=1e-10)
    assert backend._layout.bound_rows.size == 6 + 12 + 1 and backend._layout.ineq_rows.size == 2 + 4 + 4
    res = backend.solve()
    ref = make_backend("clarabel", program, tolerance=1e-10).solve()
    assert res.status == ref.status == "optimal"
    assert res.objective == pytest.approx(ref.objective, rel=1e-8, abs=1e-8)
    np.testing.assert_allclose(res.x, ref.x, atol=1e-7)
    nz, z, x = program.cones.zero, res.z, res.x
    assert np.all(z[nz:] >= 0)
    stationarity = program.hessian_times(x) + program.q + program.A.T @ z
    assert np.max(np.abs(stationarity)) <= 1e-6
    assert np.max(np.abs(z[nz:] * (program.b - program.A @ x)[nz:])) <= 1e-6
    np.testing.assert_allclose(z[:nz], ref.z[:nz], atol=1e-6)
    assert z[-1] > 0 and z[12 + 6 + seed % 6] == 0.0  # x_var <= 0.3 binds; its looser box row, 1.5, carries nothing


def test_piqp_leaves_out_a_row_without_an_upper_limit(capfd):
    """A row ``a'x <= inf`` bounds nothing: PIQP does not see it (nor warns about it), and its multiplier is zero."""
    program = penalized_qp(4)
    program.b = program.b.copy()
    program.b[2] = np.inf  # the first hard inequality
    res = make_backend("piqp", program, tolerance=1e-10).solve()
    program.b[2] = 1e6  # Clarabel's answer with the row far from binding
    ref = make_backend("clarabel", program, tolerance=1e-10).solve()
    assert res.status == "optimal" and res.z[2] == 0.0
    np.testing.assert_allclose(res.x, ref.x, atol=1e-6)
    printed = capfd.readouterr()
    assert "PIQP" not in printed.out + printed.err


@pytest.mark.parametrize("name", ["piqp", "clarabel"])
def test_a_limit_that_is_not_a_number_fails_the_solve(capfd, name):
    """A row whose limit is NaN (a constraint evaluated outside its domain) is no program to solve: the backend
    says ``failed``. PIQP alone would read the NaN as no limit, drop the row without a word that reaches the caller,
    and call the rest optimal."""
    program = penalized_qp(5)
    program.b = program.b.copy()
    program.b[2] = np.nan
    res = make_backend(name, program, tolerance=1e-10).solve()
    assert res.status == "failed" and not res.usable
    printed = capfd.readouterr()
    assert "PIQP" not in printed.out + printed.err


def test_piqp_follows_updates_and_a_bound_whose_sign_turns():
    """Updates keep the layout while every bound row keeps its sign; a row whose coefficient changes sign is read
    again (it bounds the other side), and the answers stay Clarabel's."""
    first = penalized_qp(0)
    backend = make_backend("piqp", first, tolerance=1e-10)
    layout = backend._layout
    for seed in (1, 2):
        program = penalized_qp(seed)
        backend.update(program)
        assert backend._layout is layout
        np.testing.assert_allclose(backend.solve().x, make_backend("clarabel", program).solve().x, atol=1e-6)
    flipped = penalized_qp(3)
    flipped.A = flipped.A.copy()
    flipped.A[flipped.A.shape[0] - 1, 5] = 1.0  # the lower box row of x5 now reads x5 <= 1.5
    backend.update(flipped)
    res = backend.solve()
    assert backend._layout is not layout
    np.testing.assert_allclose(res.x, make_backend("clarabel", flipped).solve().x, atol=1e-6)


def test_daqp_warm_start_follows_updates():
    """One backend, a sequence of programs with the same pattern: every answer is Clarabel's."""
    backend = make_backend("daqp", penalized_qp(0), tolerance=1e-9)
    for seed in range(1, 5):
        program = penalized_qp(seed, penalty=10.0)
        backend.update(program)
        res = backend.solve()
        ref = make_backend("clarabel", program, tolerance=1e-10).solve()
        assert res.status == "optimal" and res.objective == pytest.approx(ref.objective, rel=1e-8, abs=1e-8)


def test_daqp_solves_again_at_the_looser_tolerance_what_it_calls_infeasible_at_the_tight_one(monkeypatch):
    """A DAQP "infeasible" at primal tolerance 1e-9 (numerical: the SCP's subproblems always admit d = 0) is solved
    again at 1e-8, and that answer, graded against the backend's tolerance, is Clarabel's."""
    import daqp

    from convexguid.backends.dense import PRIMAL_TOLERANCES

    real, tolerances = daqp.solve, []

    def tight_says_infeasible(*args, primal_tol, **kwargs):
        tolerances.append(primal_tol)
        answer = real(*args, primal_tol=primal_tol, **kwargs)
        return (answer[0], answer[1], -1, answer[3]) if primal_tol == PRIMAL_TOLERANCES[0] else answer

    monkeypatch.setattr(daqp, "solve", tight_says_infeasible)
    program = penalized_qp(0)
    res = make_backend("daqp", program, tolerance=1e-9).solve()
    ref = make_backend("clarabel", program, tolerance=1e-10).solve()
    assert res.status == "optimal" and res.objective == pytest.approx(ref.objective, rel=1e-8, abs=1e-8)
    assert tolerances[:2] == list(PRIMAL_TOLERANCES)


def test_daqp_reports_infeasible_and_refuses_cones():
    prog = small_qp()
    prog.A = sp.csc_matrix(np.array([[1.0, 1.0], [-1.0, -1.0]]))
    prog.b = np.array([1.0, -2.0])
    assert make_backend("daqp", prog).solve().status == "infeasible"
    soc = ConicProgram(sp.csc_matrix((3, 3)), np.array([1.0, 0, 0]), sp.csc_matrix(-np.eye(3)), np.zeros(3),
                       Cones(soc=(3,)))
    with pytest.raises(BackendError):
        make_backend("daqp", soc)


def test_daqp_solves_a_linear_program_by_proximal_iterations():
    """No curvature at all: DAQP's proximal iterations still reach the vertex, graded optimal."""
    prog = ConicProgram(sp.csc_matrix((2, 2)), np.array([-1.0, -2.0]),
                        sp.csc_matrix(np.array([[1.0, 1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])),
                        np.array([1.5, 1.0, 1.0, 0.0, 0.0]), Cones(nonneg=5))
    res = make_backend("daqp", prog, tolerance=1e-9).solve()
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [0.5, 1.0], atol=1e-7)


def test_auto_picks_by_cones_size_and_density():
    assert auto_backend(small_qp()) == "daqp"  # small and dense
    soc = ConicProgram(sp.csc_matrix((3, 3)), np.array([1.0, 0, 0]), sp.csc_matrix(-np.eye(3)), np.zeros(3),
                       Cones(soc=(3,)))
    assert auto_backend(soc) == "clarabel"
    res = make_backend("auto", soc).solve()
    assert res.status == "optimal" and res.x[0] == pytest.approx(0.0, abs=1e-6)
    n = 400  # large and sparse: a diagonal QP with a box
    big = ConicProgram(sp.identity(n, format="csc"), np.ones(n), sp.vstack([sp.identity(n), -sp.identity(n)]).tocsc(),
                       np.ones(2 * n), Cones(nonneg=2 * n))
    assert auto_backend(big) == "clarabel"
    backend = make_backend("auto", small_qp())
    assert isinstance(backend, FallbackBackend) and backend.name.startswith("auto -> daqp")


def test_fallback_answers_when_the_primary_is_not_optimal():
    class Failing(DaqpBackend):
        def solve(self):
            return BackendResult("optimal_inaccurate", np.zeros(2), 0.0, 3, 0.0, 1.0, 1.0)

    program = small_qp()
    backend = FallbackBackend(Failing(program), "clarabel", program, 1e-9)
    res = backend.solve()
    assert res.status == "optimal" and backend.fallbacks == 1
    np.testing.assert_allclose(res.x, [0.2, 0.8], atol=1e-6)
    backend.update(small_qp(shift=0.5))
    np.testing.assert_allclose(backend.solve().x, [0.25, 1.25], atol=1e-6)
    assert backend.fallbacks == 2


def _alp_rider_first_subproblem():
    """The first SCP subproblem of Betts' alp rider on 4 intervals (a quadrature cost of magnitude 4e4 weighted 30
    times: slack costs of 1e6), an LP bounded by its trust region."""
    import casadi as ca

    from convexguid.ocp import Problem
    from convexguid.ocp.solve import _settings, transcribe
    from convexguid.scp.engine import SCPAlgorithm

    p = Problem("alp-rider")
    ys = [p.state(f"y{i + 1}", initial=a, final=b) for i, (a, b) in enumerate([(2, 2), (1, 3), (2, 1), (1, -2)])]
    cost = p.state("J", initial=0.0)
    u1, u2 = p.control("u1"), p.control("u2")
    y1, y2, y3, y4 = ys
    square = y1**2 + y2**2 + y3**2 + y4**2
    p.dynamics({y1: -10 * y1 + u1 + u2, y2: -2 * y2 + u1 + 2 * u2, y3: -3 * y3 + 5 * y4 + u1 - u2,
                y4: 5 * y3 - 3 * y4 + u1 + 3 * u2, cost: 100 * square + 0.01 * (u1**2 + u2**2)})
    p.path_constraint("terrain", 3 * ca.exp(-12 * (p.time - 3) ** 2) + 0.01 - square)
    p.final_time(fixed=20.0)
    p.minimize_terminal(cost)
    p.transcription(4)
    program = transcribe(p)
    algorithm = SCPAlgorithm(program, _settings(["terminal"], 10))
    state = algorithm.initialize()
    return algorithm.assembler.build(state.x, state.raw, state.radius, state.penalty, None)


def test_clarabel_checks_an_unbounded_verdict_again_at_unit_objective_scale():
    """Clarabel 0.11 calls this bounded LP dual infeasible at its first iteration (its ray test is not invariant to
    the objective's scale); the backend solves it again with the objective divided by its largest coefficient and
    returns the optimum HiGHS finds, with multipliers on the program's own scale (strong duality holds)."""
    from scipy.optimize import linprog

    program = _alp_rider_first_subproblem()
    assert np.max(np.abs(program.q)) > 1e5 and not np.any(program.P.data)  # an LP
    result = make_backend("clarabel", program, tolerance=1e-8).solve()
    assert result.status == "optimal"
    nz, A = program.cones.zero, program.A.tocsr()
    highs = linprog(program.q, A_ub=A[nz:], b_ub=program.b[nz:], A_eq=A[:nz], b_eq=program.b[:nz],
                    bounds=(None, None), method="highs")
    assert highs.status == 0
    assert program.objective(result.x) == pytest.approx(highs.fun, rel=1e-6)
    assert -program.b @ result.z == pytest.approx(highs.fun, rel=1e-6)  # the dual objective, unscaled


def test_a_daqp_sibling_answers_as_a_backend_set_up_anew():
    """A sibling takes the layout over, not the warm start: on the next program it gives a fresh backend's answer,
    bitwise, its objective exactly the program's; a program of another structure gets none."""
    first = make_backend("daqp", penalized_qp(0), tolerance=1e-9, fallback="clarabel")
    first.solve()
    program = penalized_qp(3, penalty=10.0)
    sibling = first.sibling(program)
    assert sibling is not None and sibling.primary._layout is first.primary._layout
    ours, fresh = sibling.solve(), make_backend("daqp", program, tolerance=1e-9).solve()
    assert ours.status == fresh.status == "optimal" and ours.exact_objective
    np.testing.assert_array_equal(ours.x, fresh.x)
    np.testing.assert_array_equal(ours.z, fresh.z)
    shifted = ConicProgram(program.P, program.q, program.A, program.b, program.cones, constant=1.5)
    assert ours.objective + 1.5 == shifted.objective(ours.x)
    assert first.sibling(small_qp()) is None
