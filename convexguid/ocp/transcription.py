"""Hermite-Simpson transcription of a :class:`~convexguid.ocp.problem.Problem` into the SCP engine's program.

Decision vector ``z = [x_0 .. x_N, u_0 .. u_N, u_{1/2} .. u_{N-1/2}, (s), (J), (t_f)]``: states and controls at
the :math:`N + 1` nodes, controls at the :math:`N` interval midpoints, for minimum fuel the slacks
:math:`s \\ge |u|` of every control value (and with a free final time the fuel's epigraph variable :math:`J`), and
the final time when it is free. On each
interval of length :math:`h = t_f / N` (Hermite-Simpson, Betts 2010, eqs. 4.103-4.104):

.. math::

    x_{k+1/2} = \\tfrac12 (x_k + x_{k+1}) + \\tfrac{h}{8} (f_k - f_{k+1}),\\qquad
    x_{k+1} - x_k - \\tfrac{h}{6} (f_k + 4 f_{k+1/2} + f_{k+1}) = 0,

each defect divided by its state's scale (the feasibility tolerance is then in the state's own magnitude). Path
constraints hold at every node and midpoint, and state bounds at every node, each less the margin a dense-check
repair may have added there (:class:`Margins`). Boundary values and bounds are the hard linear constraints
:math:`Az = b`, :math:`Gz \\le h`. Minimum time is the linear cost
:math:`t_f`; minimum energy is Simpson's rule on the squared controls, residuals
:math:`r = u` with weights :math:`h/6 \\cdot (1, 2, \\dots, 2, 1)` at nodes and :math:`4h/6` at midpoints; minimum
fuel :math:`\\int \\sum_i |u_i|\\,dt` is the same rule on the slacks, :math:`-s \\le u \\le s` linear: a linear cost
when the final time is fixed, else :math:`\\min J` subject to :math:`h \\sum_j w_j s_j - J \\le 0` (an epigraph the
engine linearizes like any constraint).
Jacobians and the Lagrangian Hessian are CasADi's exact sparse derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.scp.problem import ConstraintBlock, Evaluation, LinearConstraints, OutputConstraints

if TYPE_CHECKING:  # the problem module imports this one when it solves
    from convexguid.ocp.problem import Problem


def quadratic_weights(s: float) -> tuple[float, float, float]:
    """Weights of the node, midpoint and next-node values in the quadratic through them, at the share ``s`` of
    the interval (Lagrange on 0, 1/2, 1): how a control is held between nodes."""
    return 2 * (s - 0.5) * (s - 1), -4 * s * (s - 1), 2 * s * (s - 0.5)


class _Pattern:
    """A CasADi structural sparsity read once; each evaluation only fills its values (the engine fixes the
    subproblem's pattern from the first one)."""

    def __init__(self, pattern: ca.Sparsity) -> None:
        rows, cols = pattern.get_triplet()
        self.rows, self.cols = np.asarray(rows, dtype=int), np.asarray(cols, dtype=int)
        self.shape = pattern.shape

    def coo(self, values: ca.DM) -> sp.coo_matrix:
        return sp.coo_matrix((np.asarray(values.nonzeros(), dtype=float), (self.rows, self.cols)), shape=self.shape)


@dataclass(frozen=True)
class Margins:
    """How much tighter than stated a repair made each path-constraint row (nodes and midpoints, in the order of the
    path vector) and each node state bound (the states' part of ``z``)."""

    path: np.ndarray
    bounds: np.ndarray
    violation: float = float("inf")
    """The dense check's worst violation that led to these margins (the next repair must do better)."""

    @classmethod
    def none(cls, path_rows: int, state_values: int) -> Margins:
        return cls(np.zeros(path_rows), np.zeros(state_values))


class HermiteSimpsonProgram:
    """The transcribed problem as a :class:`~convexguid.scp.problem.NonconvexProgram`."""

    def __init__(self, problem: Problem, margins: Margins | None = None, intervals: int | None = None) -> None:
        problem.check()
        self.problem = problem
        self.N = intervals if intervals is not None else problem.intervals
        self.nx, self.nu = len(problem.states), len(problem.controls)
        self.free_time = problem.free_time
        self.fuel = problem.objective == "fuel"
        self.slack_start = (self.N + 1) * (self.nx + self.nu) + self.N * self.nu
        self.num_slacks = (2 * self.N + 1) * self.nu if self.fuel else 0
        self.epigraph = self.fuel and self.free_time
        self.num_variables = self.slack_start + self.num_slacks + int(self.epigraph) + int(self.free_time)
        self._build()
        self.margins = margins if margins is not None else Margins.none(self.num_path, (self.N + 1) * self.nx)

    # --- layout ---------------------------------------------------------------------------------------------
    def states(self, z: np.ndarray) -> np.ndarray:
        """Node states, shape ``(N + 1, nx)``."""
        return np.asarray(z[: (self.N + 1) * self.nx]).reshape(self.N + 1, self.nx)

    def node_controls(self, z: np.ndarray) -> np.ndarray:
        start = (self.N + 1) * self.nx
        return np.asarray(z[start: start + (self.N + 1) * self.nu]).reshape(self.N + 1, self.nu)

    def midpoint_controls(self, z: np.ndarray) -> np.ndarray:
        start = (self.N + 1) * (self.nx + self.nu)
        return np.asarray(z[start: start + self.N * self.nu]).reshape(self.N, self.nu)

    def final_time(self, z: np.ndarray) -> float:
        return float(z[-1]) if self.free_time else float(self.problem.tf)

    # --- symbolic maps --------------------------------------------------------------------------------------
    def _build(self) -> None:
        p, N, nx, nu = self.problem, self.N, self.nx, self.nu
        z = ca.SX.sym("z", self.num_variables)
        X = ca.reshape(z[: (N + 1) * nx], nx, N + 1)
        U = ca.reshape(z[(N + 1) * nx: (N + 1) * (nx + nu)], nu, N + 1)
        M = ca.reshape(z[(N + 1) * (nx + nu): (N + 1) * (nx + nu) + N * nu], nu, N)
        tf = z[-1] if self.free_time else p.tf
        h = tf / N
        x, u, t = p.state_vector(), p.control_vector(), p.time
        # the dynamics f(x, u, t) and every path constraint's value (None without any), built once: the
        # transcription, the grid refinement and the dense check all evaluate these
        self.rate = f = ca.Function("rate", [x, u, t], [p.rate_vector()])
        self.constraint_values = (ca.Function("g", [x, u, t], [ca.vertcat(*(c.expression for c in p.constraints))])
                                  if p.constraints else None)
        scale = ca.DM([v.scale for v in p.states])
        defects, constraints = [], []
        g = [ca.Function(f"g_{j}", [x, u, t], [c.expression]) for j, c in enumerate(p.constraints)]
        self.path_rows: list[tuple[str, int, int]] = []  # (node or mid, index, constraint) of each path row

        def imposed(kind: str, k: int, share: float, state, control, time) -> list:
            rows = []
            for j, c in enumerate(p.constraints):
                if c.applies(share, kind == "node"):
                    self.path_rows.append((kind, k, j))
                    rows.append(g[j](state, control, time))
            return rows

        for k in range(N):
            tk = k * h
            fk, fk1 = f(X[:, k], U[:, k], tk), f(X[:, k + 1], U[:, k + 1], tk + h)
            xm = 0.5 * (X[:, k] + X[:, k + 1]) + h / 8 * (fk - fk1)
            fm = f(xm, M[:, k], tk + h / 2)
            defects.append((X[:, k + 1] - X[:, k] - h / 6 * (fk + 4 * fm + fk1)) / scale)
            constraints += imposed("node", k, k / N, X[:, k], U[:, k], tk)
            constraints += imposed("mid", k, (k + 0.5) / N, xm, M[:, k], tk + h / 2)
        constraints += imposed("node", N, 1.0, X[:, N], U[:, N], tf)
        defect = ca.vertcat(*defects)
        path = ca.vertcat(*constraints) if constraints else ca.SX(0, 1)
        self._defects = ca.Function("defects", [z], [defect, ca.jacobian(defect, z)])
        self._path = ca.Function("path", [z], [path, ca.jacobian(path, z)])
        self._defect_pattern = _Pattern(ca.jacobian(defect, z).sparsity())
        self._path_pattern = _Pattern(ca.jacobian(path, z).sparsity())
        lam, mu = ca.SX.sym("lam", defect.shape[0]), ca.SX.sym("mu", path.shape[0])
        lagrangian = ca.dot(lam, defect) + (ca.dot(mu, path) if path.shape[0] else 0)
        self.num_path = path.shape[0]
        fuel = (h * ca.dot(ca.DM(self._simpson_per_step), z[self.slack_start: self.slack_start + self.num_slacks])
                - z[self.slack_start + self.num_slacks]) if self.epigraph else ca.SX(0, 1)
        self._fuel = ca.Function("fuel", [z], [fuel, ca.jacobian(fuel, z)])
        self._fuel_pattern = _Pattern(ca.jacobian(fuel, z).sparsity())
        nu_fuel = ca.SX.sym("nu", fuel.shape[0])
        if fuel.shape[0]:
            lagrangian = lagrangian + ca.dot(nu_fuel, fuel)
        hessian = ca.hessian(lagrangian, z)[0]
        self._hessian = ca.Function("hessian", [z, lam, mu, nu_fuel], [hessian])
        self._hessian_pattern = _Pattern(hessian.sparsity())

    @cached_property
    def _simpson_per_step(self) -> np.ndarray:
        """Simpson's weights per unit step of every control value, nodes then midpoints (``(1, 2, .., 2, 1)/6`` and
        ``4/6``), in the order of the controls in ``z``."""
        node = np.full(self.N + 1, 2 / 6)
        node[[0, -1]] = 1 / 6
        return np.concatenate([np.repeat(node, self.nu), np.full(self.N * self.nu, 4 / 6)])

    def refined(self, z: np.ndarray) -> tuple[HermiteSimpsonProgram, np.ndarray]:
        """The same problem on twice the intervals, and ``z`` carried onto it: the old nodes, the Hermite-Simpson
        midpoint states as the new nodes between them, the controls' quadratics at the new midpoints (margins
        start afresh: the finer grid has its own)."""
        p, N = self.problem, self.N
        fine = HermiteSimpsonProgram(p, intervals=2 * N)
        X, U, M = self.states(z), self.node_controls(z), self.midpoint_controls(z)
        tf, h = self.final_time(z), self.final_time(z) / N
        f = np.array([np.asarray(self.rate(X[k], U[k], k * h)).ravel() for k in range(N + 1)])
        mid_states = 0.5 * (X[:-1] + X[1:]) + h / 8 * (f[:-1] - f[1:])
        states = np.empty((2 * N + 1, self.nx))
        states[0::2], states[1::2] = X, mid_states
        controls = np.empty((2 * N + 1, self.nu))
        controls[0::2], controls[1::2] = U, M

        def quadratic(s: float) -> np.ndarray:
            a, m, b = quadratic_weights(s)
            return a * U[:-1] + m * M + b * U[1:]

        mids = np.empty((2 * N, self.nu))
        mids[0::2], mids[1::2] = quadratic(0.25), quadratic(0.75)
        parts = [states.ravel(), controls.ravel(), mids.ravel()]
        if fine.fuel:
            slacks = np.abs(np.concatenate([controls.ravel(), mids.ravel()]))
            parts.append(slacks)
            if fine.epigraph:
                parts.append([tf / (2 * N) * float(fine._simpson_per_step @ slacks)])
        if fine.free_time:
            parts.append([tf])
        return fine, np.concatenate(parts)

    # --- NonconvexProgram -----------------------------------------------------------------------------------
    def initial_guess(self) -> np.ndarray:
        """States straight from their initial to their final values (the other given one where only one is),
        controls at their guess (else the middle of finite bounds, else 0), the final time at its guess."""
        p, N = self.problem, self.N
        s = np.linspace(0.0, 1.0, N + 1)[:, None]
        start = np.array([v.initial if v.initial is not None else (v.final or 0.0) for v in p.states])
        end = np.array([v.final if v.final is not None else start[i] for i, v in enumerate(p.states)])
        states = start + s * (end - start)
        control = np.array([_control_guess(v) for v in p.controls])
        parts = [states.ravel(), np.tile(control, N + 1), np.tile(control, N)]
        if self.fuel:
            slacks = np.abs(np.tile(control, 2 * N + 1))
            parts.append(slacks)
            if self.epigraph:
                parts.append([p.tf_guess / N * float(self._simpson_per_step @ slacks)])
        if self.free_time:
            parts.append([p.tf_guess])
        return np.concatenate(parts)

    def variable_scale(self) -> np.ndarray:
        p, N = self.problem, self.N
        states = np.array([v.scale for v in p.states])
        controls = np.array([v.scale for v in p.controls])
        parts = [np.tile(states, N + 1), np.tile(controls, 2 * N + 1)]
        if self.fuel:
            parts.append(np.tile(controls, 2 * N + 1))
            if self.epigraph:
                parts.append([max(self.problem.tf_guess * float(controls.sum()), 1e-6)])
        if self.free_time:
            parts.append([max(self.problem.tf_guess, 1e-6)])
        return np.concatenate(parts)

    @cached_property
    def _energy_rows(self) -> tuple[sp.coo_matrix, np.ndarray]:
        """Residual selection (every node and midpoint control) and Simpson's weights for them."""
        N, nu = self.N, self.nu
        h = (self.problem.tf or 0.0) / N
        first = (N + 1) * self.nx
        columns = np.arange(first, first + (2 * N + 1) * nu)
        select = sp.csr_matrix((np.ones(columns.size), (np.arange(columns.size), columns)),
                               shape=(columns.size, self.num_variables))
        node_weight = np.full(N + 1, 2 * h / 6)
        node_weight[[0, -1]] = h / 6
        weights = np.concatenate([np.repeat(node_weight, nu), np.full(N * nu, 4 * h / 6)])
        return select.tocoo(), weights

    def residual_weights(self) -> np.ndarray:
        return self._energy_rows[1] if self.problem.objective == "energy" else np.zeros(0)

    def linear_cost(self) -> np.ndarray:
        cost = np.zeros(self.num_variables)
        if self.problem.objective == "time":
            cost[-1] = 1.0
        elif self.epigraph:
            cost[self.slack_start + self.num_slacks] = 1.0
        elif self.fuel:
            h = self.problem.tf / self.N
            cost[self.slack_start: self.slack_start + self.num_slacks] = h * self._simpson_per_step
        return cost

    def linear_constraints(self) -> LinearConstraints:
        p, N, nx, n = self.problem, self.N, self.nx, self.num_variables
        rows, values = [], []
        for i, v in enumerate(p.states):
            for node, value in ((0, v.initial), (N, v.final)):
                if value is not None:
                    rows.append(node * nx + i)
                    values.append(value)
        A = sp.coo_matrix((np.ones(len(rows)), (np.arange(len(rows)), rows)), shape=(len(rows), n))
        low, high = self._bounds()
        upper, lower = np.flatnonzero(np.isfinite(high)), np.flatnonzero(np.isfinite(low))
        blocks = [sp.coo_matrix((np.ones(upper.size), (np.arange(upper.size), upper)), shape=(upper.size, n)),
                  sp.coo_matrix((-np.ones(lower.size), (np.arange(lower.size), lower)), shape=(lower.size, n))]
        blocks += self._interpolated_control_bounds()
        if self.fuel:
            # -s <= u <= s for every control value: u - s <= 0 and -u - s <= 0
            controls = np.arange((N + 1) * nx, self.slack_start)
            slacks = np.arange(self.slack_start, self.slack_start + self.num_slacks)
            rows = np.arange(controls.size)
            for sign in (1.0, -1.0):
                blocks.append(sp.coo_matrix((np.concatenate([np.full(rows.size, sign), -np.ones(rows.size)]),
                                             (np.concatenate([rows, rows]), np.concatenate([controls, slacks]))),
                                            shape=(rows.size, n)))
        G = sp.vstack(blocks)
        # a repaired state bound holds with its margin at the nodes next to where the dense check saw it broken
        tightened = np.concatenate([self.margins.bounds, np.zeros(n - self.margins.bounds.size)])
        h = np.concatenate([high[upper] - tightened[upper], -low[lower] - tightened[lower],
                            self._interpolated_control_limits(), np.zeros(2 * self.num_slacks)])
        return LinearConstraints(A, np.array(values, dtype=float), G.tocoo(), h)

    INTERPOLATION_SAMPLES = (0.125, 0.25, 0.375, 0.625, 0.75, 0.875)
    """Shares of each interval where a bounded control's quadratic (node, midpoint, node) is held within its bounds:
    next to a switch of a bang-bang control the quadratic through three bounded values overshoots between them."""

    def _interpolated_control_bounds(self) -> list[sp.coo_matrix]:
        """Rows ``+-(a_0 u_k + a_m u_{k+1/2} + a_1 u_{k+1})``: the quadratic at :data:`INTERPOLATION_SAMPLES` for
        every bounded control on every interval (upper bounds, then lower; :meth:`_interpolated_control_limits`
        gives their right-hand sides)."""
        rows, cols, vals, count = [], [], [], 0
        for sign, upper in ((1.0, True), (-1.0, False)):
            for k in range(self.N):
                for j in self._bounded_controls(upper):
                    for s in self.INTERPOLATION_SAMPLES:
                        for column, weight in zip(self._control_columns(k, j), quadratic_weights(s), strict=True):
                            rows.append(count)
                            cols.append(column)
                            vals.append(sign * weight)
                        count += 1
        return [sp.coo_matrix((vals, (rows, cols)), shape=(count, self.num_variables))]

    def _interpolated_control_limits(self) -> np.ndarray:
        controls, samples = self.problem.controls, len(self.INTERPOLATION_SAMPLES)
        upper = [controls[j].upper for _ in range(self.N) for j in self._bounded_controls(True)]
        lower = [-controls[j].lower for _ in range(self.N) for j in self._bounded_controls(False)]
        return np.repeat(np.array(upper + lower, dtype=float), samples)

    def _bounded_controls(self, upper: bool) -> list[int]:
        return [j for j, v in enumerate(self.problem.controls) if (v.upper if upper else v.lower) is not None]

    def _control_columns(self, k: int, j: int) -> tuple[int, int, int]:
        """Columns of control ``j`` at node ``k``, midpoint ``k`` and node ``k + 1``."""
        first, nu = (self.N + 1) * self.nx, self.nu
        return first + k * nu + j, first + (self.N + 1) * nu + k * nu + j, first + (k + 1) * nu + j

    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        p, N = self.problem, self.N
        xl, xh = p.bounds_array(p.states)
        ul, uh = p.bounds_array(p.controls)
        low = [np.tile(xl, N + 1), np.tile(ul, 2 * N + 1)]
        high = [np.tile(xh, N + 1), np.tile(uh, 2 * N + 1)]
        if self.fuel:
            low += [np.zeros(self.num_slacks), np.full(int(self.epigraph), -np.inf)]
            high += [np.full(self.num_slacks, np.inf), np.full(int(self.epigraph), np.inf)]
        if self.free_time:
            low.append([p.tf_bounds[0]])
            high.append([p.tf_bounds[1]])
        return np.concatenate(low), np.concatenate(high)

    def output_constraints(self) -> OutputConstraints:
        return OutputConstraints.none(self.residual_weights().size)

    def evaluate(self, z: np.ndarray, jacobians: bool = True) -> Evaluation:
        defect, defect_jac = self._defects(z)
        path, path_jac = self._path(z)
        residuals = np.zeros(0)
        residual_jacobian = sp.coo_matrix((0, self.num_variables)) if jacobians else None
        if self.problem.objective == "energy":
            select = self._energy_rows[0]
            residuals = select @ z
            residual_jacobian = select if jacobians else None
        equalities = (ConstraintBlock("dynamics_defects", np.asarray(defect, dtype=float).ravel(),
                                      self._defect_pattern.coo(defect_jac) if jacobians else None, "scaled state"),)
        inequalities = ()
        if self.num_path:
            values = np.asarray(path, dtype=float).ravel() + self.margins.path
            inequalities = (ConstraintBlock("path_constraints", values,
                                            self._path_pattern.coo(path_jac) if jacobians else None),)
        if self.epigraph:
            fuel, fuel_jac = self._fuel(z)
            inequalities += (ConstraintBlock("fuel_epigraph", np.asarray(fuel, dtype=float).ravel(),
                                             self._fuel_pattern.coo(fuel_jac) if jacobians else None),)
        return Evaluation(residuals, residual_jacobian, inequalities, equalities)

    def lagrangian_hessian(self, z: np.ndarray, weights) -> sp.csr_matrix:
        """CasADi's exact :math:`\\sum \\lambda_k \\nabla^2 e_k + \\sum \\mu_j \\nabla^2 g_j` (the energy residuals are
        linear in ``z``: no curvature of their own)."""
        mu = weights.inequality[: self.num_path]
        nu = weights.inequality[self.num_path:]
        hessian = self._hessian(z, weights.equality, mu, nu)
        return self._hessian_pattern.coo(hessian).tocsr()


def _control_guess(v) -> float:
    if v.guess is not None:
        return v.guess
    if v.lower is not None and v.upper is not None:
        return 0.5 * (v.lower + v.upper)
    return 0.0
