"""The convex curvature model every ocp subproblem carries (convexguid.ocp.curvature): exact where the constraints'
curvature is convex, without the bilinear and the shared parts it leaves out by design, and positive semidefinite;
and the first guess the engine starts from."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp

from convexguid.ocp import Problem
from convexguid.ocp.curvature import ElementCurvature
from convexguid.ocp.element_hessian import ElementHessian
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.ocp.solve import transcribe
from convexguid.scp.lagrangian import CurvatureWeights


def _weights(program, rng) -> CurvatureWeights:
    ev = program.evaluate(program.initial_guess(), jacobians=False)
    equalities = sum(b.values.size for b in ev.equalities)
    inequalities = sum(b.values.size for b in ev.inequalities)
    return CurvatureWeights(np.zeros(0), rng.uniform(0.5, 2.0, inequalities), rng.uniform(-1.0, 1.0, equalities))


def _matrix(model, values, n) -> np.ndarray:
    upper = sp.coo_matrix((values, (model.rows, model.cols)), shape=(n, n)).toarray()
    return upper + np.triu(upper, 1).T


def _disc(free_time: bool, bilinear: bool) -> Problem:
    p = Problem("disc")
    x = p.state("x", initial=0.0, final=1.0)
    v = p.state("v", initial=0.0, final=0.0)
    u = p.control("u", bounds=(-2.0, 2.0))
    p.dynamics({x: v, v: u * v if bilinear else u})
    p.path_constraint("disc", x**2 + v**2 - 4.0)  # convex: its curvature is kept whole
    if free_time:
        p.final_time(bounds=(0.5, 5.0), guess=2.0)
        p.minimize_time()
    else:
        p.final_time(2.0)
        p.minimize_energy()
    p.transcription(6)
    return p


def test_convex_constraints_give_the_exact_lagrangian_hessian():
    program = transcribe(_disc(free_time=False, bilinear=False))
    rng = np.random.default_rng(1)
    z, weights = program.initial_guess() + rng.normal(0, 0.1, program.num_variables), _weights(program, rng)
    model = program.curvature_model()
    exact = program.lagrangian_hessian(z, weights).toarray()
    assert np.allclose(_matrix(model, model.values(z, weights), program.num_variables), exact, atol=1e-12)


def test_each_element_keeps_its_net_positive_curvature():
    """Three elements of one row each: a bilinear term (eigenvalues +1, -1) adds nothing, a convex one is kept
    whole, a mixed one (3 and -1) keeps its positive part at its net share (3 - 1) / 3."""
    z = ca.SX.sym("z", 6)
    rows = ca.vertcat(z[0] * z[1], z[2] ** 2 + 0.5 * z[3] ** 2, 1.5 * z[4] ** 2 - 0.5 * z[5] ** 2)
    elements = ElementCurvature(ElementHessian(z, rows, np.arange(3)))
    model = _matrix(elements, elements.values(np.zeros(6), np.ones(3)), 6)
    assert np.allclose(model, np.diag([0.0, 0.0, 2.0, 1.0, 2.0, 0.0]), atol=1e-14)
    assert np.allclose(_matrix(elements, elements.values(np.zeros(6), [1.0, -1.0, 0.0]), 6), 0.0, atol=1e-14)


@pytest.mark.parametrize("grid", [None, [0.0, 0.1, 0.3, 0.35, 0.6, 0.8, 1.0]])
def test_the_hessian_by_element_classes_is_casadis_hessian_of_the_whole_lagrangian(grid):
    """Built class by class in each interval's own variables (convexguid.ocp.element_hessian), the Lagrangian's
    Hessian is CasADi's of the whole program, with time in the dynamics, a free final time and, on an uneven grid,
    intervals that are each their own class."""
    p = Problem("driven")
    x = p.state("x", initial=0.0, final=1.0)
    v = p.state("v", initial=0.0, final=0.0)
    u = p.control("u", bounds=(-3.0, 3.0))
    p.dynamics({x: v * ca.cos(0.3 * p.time) + x * v, v: u - 0.1 * v**2 * ca.sin(p.time)})
    p.path_constraint("disc", x**2 + v**2 * u - 4.0)
    p.final_time(bounds=(0.5, 5.0), guess=2.0)
    p.minimize_time()
    p.transcription(6)
    program = transcribe(p) if grid is None else HermiteSimpsonProgram(p, grid=grid)
    rng = np.random.default_rng(5)
    z, weights = program.initial_guess() + rng.normal(0, 0.2, program.num_variables), _weights(program, rng)
    symbols, equalities, path, epigraph = program._symbols
    multipliers = [ca.SX.sym("w", e.shape[0]) for e in (equalities, path, epigraph)]
    whole = ca.Function("whole", [symbols, *multipliers], [ca.hessian(sum(
        (ca.dot(w, e) for w, e in zip(multipliers, (equalities, path, epigraph), strict=True) if e.shape[0]), ca.SX(0)),
        symbols)[0]])
    expected = np.asarray(ca.densify(whole(z, weights.equality, weights.inequality[: path.shape[0]],
                                           weights.inequality[path.shape[0]: path.shape[0] + epigraph.shape[0]])))
    assert len(program._hessian.classes) > (5 if grid else 1)
    assert np.allclose(program.lagrangian_hessian(z, weights).toarray(), expected, rtol=1e-12, atol=1e-12)


def test_bilinear_dynamics_give_a_convex_model():
    program = transcribe(_disc(free_time=False, bilinear=True))
    rng = np.random.default_rng(2)
    z, weights = program.initial_guess() + rng.normal(0, 0.3, program.num_variables), _weights(program, rng)
    model = program.curvature_model()
    assert np.linalg.eigvalsh(_matrix(model, model.values(z, weights), program.num_variables)).min() >= -1e-12


def test_the_free_final_time_carries_no_curvature():
    program = transcribe(_disc(free_time=True, bilinear=False))
    rng = np.random.default_rng(3)
    z, weights = program.initial_guess(), _weights(program, rng)
    model = program.curvature_model()
    last = program.num_variables - 1  # the final time
    assert last not in model.rows and last not in model.cols
    exact = program.lagrangian_hessian(z, weights).toarray()
    assert np.abs(exact[last, :last]).max() > 0  # it does couple to the intervals
    kept = _matrix(model, model.values(z, weights), program.num_variables)
    assert np.allclose(kept[:last, :last], exact[:last, :last], atol=1e-12)


def test_an_affine_program_has_no_curvature_model():
    p = Problem("double-integrator")
    x = p.state("x", initial=0.0, final=1.0)
    v = p.state("v", initial=0.0, final=0.0)
    u = p.control("u")
    p.dynamics({x: v, v: u})
    p.final_time(1.0)
    p.minimize_energy()
    p.transcription(5)
    assert transcribe(p).curvature_model() is None


@pytest.mark.parametrize("shift", [0.0, 1e-12])
def test_the_model_moves_continuously_with_its_point(shift):
    program = transcribe(_disc(free_time=True, bilinear=True))
    rng = np.random.default_rng(4)
    z, weights = program.initial_guess() + rng.normal(0, 0.2, program.num_variables), _weights(program, rng)
    model = program.curvature_model()
    base = model.values(z, weights)
    moved = model.values(z + shift, weights)
    assert np.allclose(moved, base, rtol=1e-9, atol=1e-9 * np.abs(base).max())


def test_a_free_position_is_flown_by_its_speed_and_a_driven_state_is_not():
    """The first guess (convexguid.ocp.guess, forward Euler at the nodes): a range with no final value follows its
    speed instead of resting at its start; a state a control drives keeps its straight line."""
    p = Problem("glide")
    x = p.state("x", initial=0.0)  # free range
    v = p.state("v", initial=2.0, final=4.0)
    w = p.state("w", initial=1.0)  # free, but driven by the control
    u = p.control("u", bounds=(-1.0, 1.0))
    p.dynamics({x: v, v: u, w: u})
    p.final_time(2.0)
    p.minimize_energy()
    p.transcription(4)
    program = transcribe(p)
    states = program.states(program.initial_guess())
    speed = np.linspace(2.0, 4.0, 5)
    assert np.allclose(states[:, 0], np.concatenate([[0.0], np.cumsum(0.5 * speed[:-1])]))
    assert np.allclose(states[:, 1], speed) and np.allclose(states[:, 2], 1.0)
