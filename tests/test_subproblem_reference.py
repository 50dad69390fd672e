"""The hand-assembled SCP subproblem against its definition stated in cvxpy.

:class:`~convexguid.scp.assembly.SubproblemAssembler` writes the trust-region subproblem straight into
sparse conic form (scaled columns, fixed CSC pattern). Here cvxpy states it as the docstring of
:mod:`convexguid.scp.assembly` reads,

    min  y'Wy + c'd + rho (1's_o + 1's_g + 1't)
    s.t. A d = b - A x,  J d - y = -r,  G d <= h - G x,  M y - s_o <= m,
         g + grad g d <= s_g,  |e + grad e d| <= t,  s_o, s_g, t >= 0,  |d_i| <= Delta sigma_i,

and both must have the same optimal value and step ``d``: on the flat-attitude program of
Cai et al. 2018 (8 nodes) and on a tiny hand-written program with every kind of constraint.

The condensed subproblem (:class:`~convexguid.scp.condensed.CondensedAssembler`, the lifted
residuals substituted) is the same problem in fewer variables: solved by Clarabel and by DAQP
it must give the lifted one's step, model value and equality multipliers, on the flat-attitude
program at 8 and 32 nodes and on the tiny program.
"""

from __future__ import annotations

from pathlib import Path

import cvxpy as cp
import numpy as np
import pytest
import scipy.sparse as sp

from convexguid.backends import make_backend
from convexguid.families.flat_attitude.program import FlatAttitudeProgram, build_problem
from convexguid.problem_files import load_problem
from convexguid.scp.assembly import SubproblemAssembler
from convexguid.scp.condensed import CondensedAssembler
from convexguid.scp.problem import ConstraintBlock, Evaluation, LinearConstraints, OutputConstraints

FLAT = Path(__file__).resolve().parents[1] / "problems" / "cai2018_flat_attitude.yaml"
TOL = 1e-6


def _stack(blocks: tuple[ConstraintBlock, ...], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Values and dense Jacobian of a tuple of constraint blocks."""
    if not blocks:
        return np.zeros(0), np.zeros((0, n))
    jac = [b.jacobian.toarray() if sp.issparse(b.jacobian) else np.asarray(b.jacobian) for b in blocks]
    return np.concatenate([b.values for b in blocks]), np.vstack(jac)


def _dense(matrix) -> np.ndarray:
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix, dtype=float)


def cvxpy_subproblem(x, ev: Evaluation, lin: LinearConstraints, out: OutputConstraints, scale, cost, weights,
                     radius: float, rho: float) -> tuple[float, np.ndarray]:
    """The subproblem as its definition reads; returns the optimal value and ``d``."""
    n = x.size
    g, jac_g = _stack(ev.inequalities, n)
    e, jac_e = _stack(ev.equalities, n)
    A, G, M, J = _dense(lin.A), _dense(lin.G), _dense(out.M), _dense(ev.residual_jacobian)
    d, y = cp.Variable(n), cp.Variable(ev.residuals.size)
    objective = cp.sum(cp.multiply(weights, cp.square(y))) + cost @ d
    constraints = [J @ d - y == -ev.residuals, cp.abs(d) <= radius * scale]
    if A.shape[0]:
        constraints.append(A @ d == lin.b - A @ x)
    if G.shape[0]:
        constraints.append(G @ d <= lin.h - G @ x)
    for rows, build in ((M.shape[0], lambda s: M @ y - s <= out.m),
                        (g.size, lambda s: g + jac_g @ d <= s),
                        (e.size, lambda s: cp.abs(e + jac_e @ d) <= s)):
        if rows:
            slack = cp.Variable(rows, nonneg=True)
            objective = objective + rho * cp.sum(slack)
            constraints.append(build(slack))
    problem = cp.Problem(cp.Minimize(objective), constraints)
    problem.solve(solver=cp.CLARABEL, tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
    assert problem.status == cp.OPTIMAL, problem.status
    return float(problem.value), d.value


def assembled_subproblem(x, ev, lin, out, scale, cost, weights, radius, rho, assembler_type=SubproblemAssembler,
                         backend="clarabel"):
    """The same subproblem from ``assembler_type`` solved by ``backend``: model value, step, equality multipliers."""
    assembler = assembler_type(x.size, ev, lin, out, scale, cost, weights)
    program = assembler.build(x, ev, radius, rho)
    result = make_backend(backend, program, tolerance=1e-10).solve()
    assert result.status == "optimal", result.status
    return program.objective(result.x), assembler.step(result.x), assembler.multipliers(result.z).equality


def flat_attitude_case(nodes: int = 8):
    """Cai et al. 2018 with ``nodes`` nodes, about the initial guess: residuals = torques, keep-out cone, torque box."""
    program = FlatAttitudeProgram(build_problem(load_problem(FLAT, [f"discretization.nodes={nodes}"])))
    x = program.initial_guess()
    return (x, program.evaluate(x), program.linear_constraints(), program.output_constraints(),
            program.variable_scale(), program.linear_cost(), program.residual_weights(), 0.05, 10.0)


def flat_attitude_converging_case():
    """Cai et al. 2018 with 32 nodes (99 variables) one accepted step later, with the step wide open.

    About the initial guess the 0.05 trust region binds everywhere; here the radius 1 leaves the
    energy, the torque box and the keep-out cone to decide, as in the last SCP iterations.
    """
    program = FlatAttitudeProgram(build_problem(load_problem(FLAT, ["discretization.nodes=32"])))
    x0 = program.initial_guess()
    args = (x0, program.evaluate(x0), program.linear_constraints(), program.output_constraints(),
            program.variable_scale(), program.linear_cost(), program.residual_weights(), 0.5, 1e3)
    _, d, _ = assembled_subproblem(*args)
    x = x0 + d
    return (x, program.evaluate(x), *args[2:7], 1.0, 1e3)


def tiny_case():
    """3 variables with non-unit scales, every block: A, G, M, a nonlinear inequality and equality."""
    x = np.array([0.6, 0.9, 0.5])
    a, b, c = x
    ev = Evaluation(
        residuals=np.array([a - 1.0, b * c]),
        residual_jacobian=np.array([[1.0, 0.0, 0.0], [0.0, c, b]]),
        inequalities=(ConstraintBlock("disc", np.array([a**2 + b**2 - 1.0]), np.array([[2 * a, 2 * b, 0.0]])),),
        equalities=(ConstraintBlock("curve", np.array([a * b - c**2 - 0.1]), np.array([[b, a, -2 * c]])),),
    )
    lin = LinearConstraints(np.array([[1.0, 1.0, 1.0]]), np.array([2.0]), np.array([[0.0, 1.0, 0.0]]),
                            np.array([0.91]))
    out = OutputConstraints(sp.csr_matrix([[1.0, 0.0]]), np.array([-0.45]), ())
    return x, ev, lin, out, np.array([1.0, 2.0, 0.5]), np.array([0.0, 0.0, 0.3]), np.array([1.0, 2.0]), 0.03, 5.0


@pytest.mark.parametrize("case", [flat_attitude_case, tiny_case], ids=["flat_attitude_8_nodes", "tiny"])
def test_assembled_subproblem_is_the_stated_one(case):
    args = case()
    value_ref, d_ref = cvxpy_subproblem(*args)
    value, d, _ = assembled_subproblem(*args)
    x, scale, radius = args[0], args[4], args[7]
    print(f"value: assembled {value:.12g}, cvxpy {value_ref:.12g}, difference {abs(value - value_ref):.2e}; "
          f"max |d - d_cvxpy| {np.max(np.abs(d - d_ref)):.2e}")
    assert value == pytest.approx(value_ref, rel=TOL, abs=TOL)
    assert np.allclose(d, d_ref, rtol=0, atol=TOL * max(1.0, np.max(np.abs(d_ref))))
    # the comparison means something only if the step is not trivial and the trust region bites somewhere
    assert np.max(np.abs(d) / scale) > 0.1 * radius
    assert np.isclose(np.max(np.abs(d) / scale), radius, rtol=1e-6)
    assert x.size == d.size


CONDENSED_CASES = [pytest.param(flat_attitude_case, id="flat_attitude_8_nodes"),
                   pytest.param(lambda: flat_attitude_case(32), id="flat_attitude_32_nodes"),
                   pytest.param(flat_attitude_converging_case, id="flat_attitude_32_nodes_open"),
                   pytest.param(tiny_case, id="tiny")]


@pytest.fixture(scope="module")
def lifted_answers() -> dict:
    """The lifted subproblem's answer per case (Clarabel, 1e-10), computed once."""
    return {}


@pytest.mark.parametrize("backend", ["clarabel", "daqp"])
@pytest.mark.parametrize("case", CONDENSED_CASES)
def test_condensed_subproblem_has_the_lifted_optimum(case, backend, lifted_answers):
    args = case()
    if case not in lifted_answers:
        lifted_answers[case] = assembled_subproblem(*args)
    value_ref, d_ref, lam_ref = lifted_answers[case]
    value, d, lam = assembled_subproblem(*args, assembler_type=CondensedAssembler, backend=backend)
    scale, radius = args[4], args[7]
    print(f"{backend}: model value condensed {value:.12g}, lifted {value_ref:.12g}; "
          f"max |d - d_lifted| / scale {np.max(np.abs(d - d_ref) / scale):.2e}")
    # the model value the engine compares with the merit: the condensed program carries r'Wr as its constant
    assert value == pytest.approx(value_ref, rel=TOL, abs=TOL)
    assert np.allclose(d / scale, d_ref / scale, rtol=0, atol=TOL * max(1.0, np.max(np.abs(d_ref / scale))))
    np.testing.assert_allclose(lam, lam_ref, rtol=1e-5, atol=1e-6 * max(1.0, np.max(np.abs(lam_ref), initial=0.0)))
    assert np.max(np.abs(d) / scale) > 0.1 * radius  # not a trivial step
