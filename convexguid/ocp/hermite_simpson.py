"""Hermite-Simpson collocation with midpoint controls (the default transcription).

Control values: the :math:`N + 1` node values, then the :math:`N` interval midpoints; on each interval the control
is the quadratic through node, midpoint and node. With ``control="linear"`` the node values only, the control linear
between them (its midpoint value the mean of the two nodes'). On an interval of length :math:`h = t_f / N` (Betts
2010, eqs. 4.103-4.104):

.. math::

    x_{k+1/2} = \\tfrac12 (x_k + x_{k+1}) + \\tfrac{h}{8} (f_k - f_{k+1}),\\qquad
    x_{k+1} - x_k - \\tfrac{h}{6} (f_k + 4 f_{k+1/2} + f_{k+1}) = 0,

each defect divided by its state's scale (the feasibility tolerance is then in the state's own magnitude). Path
constraints hold at every node and midpoint; Simpson's rule weighs the control values (``(1, 2, .., 2, 1)/6`` at
nodes, ``4/6`` at midpoints per unit step; a linear control's energy takes the midpoint means as residuals, its fuel
the trapezoidal rule on the node values). A bounded control's quadratic is held within its bounds at six points
of every interval: next to a switch of a bang-bang control the quadratic through three bounded values overshoots.

The intervals are equal unless a ``grid`` of node shares :math:`0 = \\tau_0 < \\dots < \\tau_N = 1` is given (what
error-driven refinement makes, :mod:`convexguid.ocp.mesh`): interval :math:`k` then has its own step
:math:`h_k = (\\tau_{k+1} - \\tau_k) t_f`, Simpson's weights scale with it, and the control's interpolant, the
path constraints' instants and the refinement follow the nodes. Equal shares take the equal-step build (the same
CasADi expressions, bit for bit).
"""

from __future__ import annotations

import copy
from functools import cached_property

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.ocp.declarations import PathConstraint
from convexguid.ocp.mesh import checked_shares, is_uniform, require_point_constraints_on_nodes, split_shares
from convexguid.ocp.transcription import Symbols, Transcription


def with_bounds_between_nodes(problem):
    """``problem`` with each finite bound of a state that has dynamics also held at the interval midpoints: a path
    row ``x - upper <= 0`` (or ``lower - x <= 0``) imposed between the nodes only (``holds_bound``; not judged by the
    dense check, which judges the bound itself). The midpoint state :math:`x_{k+1/2}` is a point of the collocated
    trajectory, but the nodes alone hold the bound hard, and an optimum may ride above it there: on the abort landing
    in windshear (Bulirsch, Montrone & Pesch, JOTA 70, 1991) the angle of attack sat on its bound with its rate
    chattering node to node, the cubic above the bound between them, and six repair rounds left the plan
    ``unverified``; with the midpoint rows it converged and verified (docs/ocp.md, 'Bounds between the nodes').
    The same problem when it holds them already."""
    held = {c.holds_bound for c in problem.constraints}
    added = []
    for i, v in enumerate(problem.states):
        rate = problem.rates.get(v.name)
        if rate is None or ca.SX(rate).is_zero():
            continue  # constant (a parameter, a coast's mass): its midpoint value is its node value
        for upper, bound in ((True, v.upper), (False, v.lower)):
            if bound is not None and (i, upper) not in held:
                added.append(PathConstraint(f"{v.name}_{'max' if upper else 'min'}_between_nodes",
                                            v.symbol - bound if upper else bound - v.symbol, v.unit, at_nodes=False,
                                            judged=False, holds_bound=(i, upper)))
    if not added:
        return problem
    stated = copy.copy(problem)
    stated.constraints = [*problem.constraints, *added]
    return stated


def quadratic_weights(s: float) -> tuple[float, float, float]:
    """Weights of the node, midpoint and next-node values in the quadratic through them, at the share ``s`` of
    the interval (Lagrange on 0, 1/2, 1): how a control is held between nodes."""
    return 2 * (s - 0.5) * (s - 1), -4 * s * (s - 1), 2 * s * (s - 0.5)


class HermiteSimpsonProgram(Transcription):
    method = "hermite-simpson"
    QUADRATIC_SAMPLES = (0.125, 0.25, 0.375, 0.625, 0.75, 0.875)

    def __init__(self, problem, margins=None, intervals=None, grid=None) -> None:
        self.linear_control = problem.control_interpolation == "linear"
        # a linear control stays within the box of its node values; a quadratic one may overshoot between them
        self.INTERPOLATION_SAMPLES = () if self.linear_control else self.QUADRATIC_SAMPLES
        self.uneven_shares = None
        """The node shares of the final time when the intervals are not equal (None: equal intervals)."""
        if grid is not None:
            shares = checked_shares(grid, f"{problem.name}: hermite-simpson")
            if intervals is not None and intervals != shares.size - 1:
                raise ValueError(f"intervals = {intervals} but the grid has {shares.size - 1}")
            intervals = shares.size - 1
            if not is_uniform(shares):
                require_point_constraints_on_nodes(problem, shares, f"{intervals}-interval grid")
                self.uneven_shares = shares
        problem = with_bounds_between_nodes(problem)
        self.split_from: tuple[np.ndarray, np.ndarray] | None = None
        """Each interval's parent's local error and the pieces the parent was split into, on a refined grid."""
        super().__init__(problem, margins, intervals)

    def node_shares(self) -> np.ndarray:
        return super().node_shares() if self.uneven_shares is None else self.uneven_shares

    def _steps(self) -> np.ndarray:
        """Each interval's length in mean steps :math:`t_f / N` (exactly 1 on equal intervals)."""
        return np.ones(self.N) if self.uneven_shares is None else np.diff(self.uneven_shares) * self.N

    def _node_sums(self, divisor: float) -> np.ndarray:
        """Each node's weight of a rule that gives it ``1 / divisor`` of each interval beside it, per mean step."""
        steps = self._steps()
        return (np.append(steps, 0.0) + np.insert(steps, 0, 0.0)) / divisor

    def _simpson_weights(self) -> tuple[np.ndarray, np.ndarray]:
        """Simpson's weights of the node and midpoint values per mean step :math:`t_f / N`."""
        return self._node_sums(6.0), 4 / 6 * self._steps()

    def initial_guess(self) -> np.ndarray:
        """The base's, but on an uneven grid the user's node values (given on equal intervals) are interpolated
        linearly in time onto its nodes."""
        guess = self.problem.guess_nodes
        if self.uneven_shares is None or guess is None:
            return super().initial_guess()
        return self._guess_on_grid(*guess)

    def initial_guess_straight(self) -> np.ndarray:
        """The base's straight line, on an uneven grid straight in time."""
        if self.uneven_shares is None:
            return super().initial_guess_straight()
        start, end, control = self.problem.straight_line()
        return self._guess_on_grid(np.vstack([start, end]), np.vstack([control, control]))

    def _guess_on_grid(self, states: np.ndarray, controls: np.ndarray) -> np.ndarray:
        """``z`` from node values given on equal intervals, interpolated linearly in time onto this grid's nodes."""
        given = np.linspace(0.0, 1.0, states.shape[0])
        onto = np.array([np.interp(self.uneven_shares, given, e) for e in np.eye(given.size)]).T
        p = self.problem
        return self.assemble(onto @ states, self.values_from_nodes(onto @ controls),
                             p.tf_guess if self.free_time else p.tf)

    def control_values_per_axis(self) -> int:
        return self.N + 1 if self.linear_control else 2 * self.N + 1

    def per_step_weights(self) -> np.ndarray:
        """Per mean step :math:`t_f / N` (on an uneven grid each interval weighs by its own length)."""
        if self.linear_control:  # the trapezoidal rule (for the fuel; the energy has its own rows)
            return self._node_sums(2.0)
        return np.concatenate(self._simpson_weights())

    @cached_property
    def _energy_rows(self) -> tuple[sp.coo_matrix, np.ndarray]:
        """Simpson's rule on the control: every node value, and for a linear control every midpoint mean."""
        if not self.linear_control:
            return Transcription._energy_rows.func(self)
        N, nu = self.N, self.nu
        h = (self.problem.tf or 0.0) / N
        first = self.control_start
        rows = list(range((N + 1) * nu))
        cols = list(range(first, first + (N + 1) * nu))
        vals = [1.0] * len(rows)
        for k in range(N):
            for j in range(nu):
                row = (N + 1) * nu + k * nu + j
                rows += [row, row]
                cols += [first + k * nu + j, first + (k + 1) * nu + j]
                vals += [0.5, 0.5]
        select = sp.coo_matrix((vals, (rows, cols)), shape=((2 * N + 1) * nu, self.num_variables))
        if self.uneven_shares is not None:
            node, mid = self._simpson_weights()
            return select, h * np.concatenate([np.repeat(node, nu), np.repeat(mid, nu)])
        node = np.full(N + 1, 2 * h / 6)
        node[[0, -1]] = h / 6
        return select, np.concatenate([np.repeat(node, nu), np.full(N * nu, 4 * h / 6)])

    def intervals(self, s: Symbols, imposed) -> list:
        N, f = self.N, self.rate
        U = s.V[:, : N + 1]
        M = 0.5 * (U[:, :-1] + U[:, 1:]) if self.linear_control else s.V[:, N + 1:]
        defects = []
        for k in range(N):
            tk, h, t_next, share, mid_share = self._interval_times(s, k)
            fk, fk1 = f(s.X[:, k], U[:, k], tk), f(s.X[:, k + 1], U[:, k + 1], t_next)
            xm = 0.5 * (s.X[:, k] + s.X[:, k + 1]) + h / 8 * (fk - fk1)
            fm = f(xm, M[:, k], tk + h / 2)
            defects.append((s.X[:, k + 1] - s.X[:, k] - h / 6 * (fk + 4 * fm + fk1)) / self.state_scale)
            imposed("node", k, share, s.X[:, k], U[:, k], tk)
            imposed("mid", k, mid_share, xm, M[:, k], tk + h / 2)
        imposed("node", N, 1.0, s.X[:, N], U[:, N], s.tf)
        return defects

    def _interval_times(self, s: Symbols, k: int) -> tuple:
        """Interval ``k``'s start time, step, end time, and its start's and midpoint's shares of the final time."""
        if self.uneven_shares is None:  # the equal-step expressions, unchanged
            return k * s.h, s.h, k * s.h + s.h, k / self.N, (k + 0.5) / self.N
        start, end = self.uneven_shares[k], self.uneven_shares[k + 1]
        return start * s.tf, (end - start) * s.tf, end * s.tf, float(start), 0.5 * float(start + end)

    def control_value_shares(self) -> np.ndarray:
        nodes = self.node_shares()
        mids = (np.arange(self.N) + 0.5) / self.N if self.uneven_shares is None else 0.5 * (nodes[:-1] + nodes[1:])
        return nodes if self.linear_control else np.concatenate([nodes, mids])

    def node_controls(self, z: np.ndarray) -> np.ndarray:
        return self.control_values(z)[: self.N + 1]

    def midpoint_controls(self, z: np.ndarray) -> np.ndarray:
        values = self.control_values(z)
        return 0.5 * (values[:-1] + values[1:]) if self.linear_control else values[self.N + 1:]

    def values_from_nodes(self, controls: np.ndarray) -> np.ndarray:
        return controls if self.linear_control else np.vstack([controls, 0.5 * (controls[:-1] + controls[1:])])

    def interval_control_columns(self, k: int, j: int) -> tuple[int, ...]:
        first, nu = self.control_start, self.nu
        if self.linear_control:
            return first + k * nu + j, first + (k + 1) * nu + j
        return first + k * nu + j, first + (self.N + 1) * nu + k * nu + j, first + (k + 1) * nu + j

    def interval_weights(self, share: float) -> tuple[float, ...]:
        return (1.0 - share, share) if self.linear_control else quadratic_weights(share)

    def _locate(self, t: float, tf: float) -> tuple[int, float]:
        """The interval holding the time ``t`` and the share of it ``t`` is at."""
        if self.uneven_shares is None:
            h = tf / self.N
            k = min(int(t // h), self.N - 1)
            return k, (t - k * h) / h
        times = tf * self.uneven_shares
        k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, self.N - 1))
        return k, (t - times[k]) / (times[k + 1] - times[k])

    def _interpolated(self, nodes: np.ndarray, mids: np.ndarray, k: int, share):
        """The control on interval ``k`` at ``share`` of it (a number, or a column of them: a row each)."""
        if self.linear_control:
            return (1.0 - share) * nodes[k] + share * nodes[k + 1]
        a, m, b = quadratic_weights(share)
        return a * nodes[k] + m * mids[k] + b * nodes[k + 1]

    def control_function(self, z: np.ndarray):
        nodes, mids = self.node_controls(z), self.midpoint_controls(z)
        tf = self.final_time(z)

        def u(t: float) -> np.ndarray:
            k, share = self._locate(t, tf)
            return self._interpolated(nodes, mids, k, share)

        return u

    def refined(self, z: np.ndarray, pieces=None, flown=None) -> tuple[HermiteSimpsonProgram, np.ndarray]:
        """The same problem with interval ``k`` split into ``pieces[k]`` equal parts (default: two everywhere, the
        intervals doubled) and ``z`` carried onto it (margins start afresh): the old nodes and their values kept,
        each new node's state ``flown(k, shares)`` (rows at those shares of interval ``k``; default: the interval's
        cubic Hermite interpolant of the node states and rates, the polynomial Hermite-Simpson collocates), the
        controls the plan's interpolant at the new nodes and midpoints, within the controls' bounds (Betts 2010,
        Sec. 4.7)."""
        N = self.N
        pieces = np.full(N, 2) if pieces is None else np.asarray(pieces, dtype=int)
        z = self.unwrapped(z)
        shares = self.node_shares()
        fine = HermiteSimpsonProgram(self.problem, grid=split_shares(shares, pieces))
        X, U, M = self.states(z), self.node_controls(z), self.midpoint_controls(z)
        tf = self.final_time(z)
        f = np.array([np.asarray(self.rate(X[k], U[k], tf * shares[k])).ravel() for k in range(N + 1)])
        low, high = self.problem.bounds_array(self.problem.controls)
        states, nodes, mids = [], [], []
        for k, m in enumerate(pieces):
            s = np.arange(m) / m  # the new nodes' shares of interval k (0: the old node)
            h = tf * (shares[k + 1] - shares[k])
            states.append(hermite_cubic(X[k], X[k + 1], h * f[k], h * f[k + 1], s) if flown is None or m == 1
                          else np.vstack([X[k], flown(k, s[1:])]))
            nodes.append(np.vstack([U[k], np.clip(self._interpolated(U, M, k, s[1:, None]), low, high)]))
            mids.append(M[k:k + 1] if m == 1 else np.clip(self._interpolated(U, M, k, (s + 0.5 / m)[:, None]), low,
                                                          high))
        states = np.vstack([*states, X[-1:]])
        controls = np.vstack([*nodes, U[-1:]])
        values = controls if self.linear_control else np.vstack([controls, *mids])
        return fine, fine.assemble(states, values, tf)

    def restated(self, problem) -> HermiteSimpsonProgram:
        """Another statement of the problem on this grid, uneven after a refinement, remembering what each interval
        was split from; margins afresh."""
        program = HermiteSimpsonProgram(problem, grid=self.uneven_shares, intervals=self.N)
        program.split_from = self.split_from
        return program

    def with_linear_control(self, z: np.ndarray, carry: bool = True) -> tuple[HermiteSimpsonProgram, np.ndarray]:
        """The same grid with each control linear between its node values (``control="linear"``: the midpoint
        values tied to the nodes' mean), margins afresh: the regularization of an optimum that chatters between node
        and midpoint values. Its start: ``z`` carried onto it (node states and controls, final time) when
        ``carry``, else its own first guess."""
        problem = copy.copy(self.problem)
        problem.control_interpolation = "linear"
        linear = self.restated(problem)
        if not carry:
            return linear, linear.initial_guess()
        z = self.unwrapped(z)
        return linear, linear.assemble(self.states(z), self.node_controls(z), self.final_time(z))


def hermite_cubic(x0: np.ndarray, x1: np.ndarray, dx0: np.ndarray, dx1: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The cubic through ``x0``, ``x1`` with slopes ``dx0``, ``dx1`` (per unit share) at the shares ``s`` of the
    interval, a row each (at ``s = 1/2``: Hermite-Simpson's midpoint state)."""
    s = np.asarray(s, dtype=float)[:, None]
    return ((2 * s**3 - 3 * s**2 + 1) * x0 + (s**3 - 2 * s**2 + s) * dx0 + (-2 * s**3 + 3 * s**2) * x1
            + (s**3 - s**2) * dx1)
