"""The hand-assembled SCP subproblem against its definition stated in cvxpy.

:class:`~convexguid.scp.assembly.SubproblemAssembler` writes the trust-region subproblem straight into
sparse conic form (scaled columns, fixed CSC pattern). Here cvxpy states it as the docstring of
:mod:`convexguid.scp.assembly` reads,

    min  y'Wy + c'd + rho (1's_o + 1's_g + 1't)
    s.t. A d = b - A x,  J d - y = -r,  G d <= h - G x,  M y - s_o <= m,
         g + grad g d <= s_g,  |e + grad e d| <= t,  s_o, s_g, t >= 0,  |d_i| <= Delta sigma_i,

and both must have the same optimal value and step ``d``: on the flat-attitude program of
Cai et al. 2018 (8 nodes) and on a tiny hand-written program with every kind of constraint.
"""

from __future__ import annotations

from pathlib import Path

import cvxpy as cp
import numpy as np
import pytest
import scipy.sparse as sp

from convexguid.backends import make_backend
from convexguid.families.flat_attitude.program import FlatAttitudeProgram, build_problem
from convexguid.scp.assembly import SubproblemAssembler
from convexguid.scp.problem import ConstraintBlock, Evaluation, LinearConstraints, OutputConstraints
from convexguid.spec import load_problem

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


def assembled_subproblem(x, ev, lin, out, scale, cost, weights, radius, rho):
    """The same subproblem from :class:`SubproblemAssembler` solved by the clarabel backend."""
    assembler = SubproblemAssembler(x.size, ev, lin, out, scale, cost, weights)
    program = assembler.build(x, ev, radius, rho)
    result = make_backend("clarabel", program, tolerance=1e-10).solve()
    assert result.status == "optimal", result.status
    return program.objective(result.x), assembler.step(result.x)


def flat_attitude_case():
    """Cai et al. 2018 with 8 nodes, about the initial guess: residuals = torques, keep-out cone, torque box."""
    program = FlatAttitudeProgram(build_problem(load_problem(FLAT, ["discretization.nodes=8"])))
    x = program.initial_guess()
    return (x, program.evaluate(x), program.linear_constraints(), program.output_constraints(),
            program.variable_scale(), program.linear_cost(), program.residual_weights(), 0.05, 10.0)


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
    value, d = assembled_subproblem(*args)
    x, scale, radius = args[0], args[4], args[7]
    print(f"value: assembled {value:.12g}, cvxpy {value_ref:.12g}, difference {abs(value - value_ref):.2e}; "
          f"max |d - d_cvxpy| {np.max(np.abs(d - d_ref)):.2e}")
    assert value == pytest.approx(value_ref, rel=TOL, abs=TOL)
    assert np.allclose(d, d_ref, rtol=0, atol=TOL * max(1.0, np.max(np.abs(d_ref))))
    # the comparison means something only if the step is not trivial and the trust region bites somewhere
    assert np.max(np.abs(d) / scale) > 0.1 * radius
    assert np.isclose(np.max(np.abs(d) / scale), radius, rtol=1e-6)
    assert x.size == d.size
