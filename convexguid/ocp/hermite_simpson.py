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
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from convexguid.ocp.transcription import Symbols, Transcription


def quadratic_weights(s: float) -> tuple[float, float, float]:
    """Weights of the node, midpoint and next-node values in the quadratic through them, at the share ``s`` of
    the interval (Lagrange on 0, 1/2, 1): how a control is held between nodes."""
    return 2 * (s - 0.5) * (s - 1), -4 * s * (s - 1), 2 * s * (s - 0.5)


class HermiteSimpsonProgram(Transcription):
    method = "hermite-simpson"
    QUADRATIC_SAMPLES = (0.125, 0.25, 0.375, 0.625, 0.75, 0.875)

    def __init__(self, problem, margins=None, intervals=None) -> None:
        self.linear_control = problem.control_interpolation == "linear"
        # a linear control stays within the box of its node values; a quadratic one may overshoot between them
        self.INTERPOLATION_SAMPLES = () if self.linear_control else self.QUADRATIC_SAMPLES
        super().__init__(problem, margins, intervals)

    def control_values_per_axis(self) -> int:
        return self.N + 1 if self.linear_control else 2 * self.N + 1

    def per_step_weights(self) -> np.ndarray:
        if self.linear_control:  # the trapezoidal rule (for the fuel; the energy has its own rows)
            weights = np.ones(self.N + 1)
            weights[[0, -1]] = 0.5
            return weights
        node = np.full(self.N + 1, 2 / 6)
        node[[0, -1]] = 1 / 6
        return np.concatenate([node, np.full(self.N, 4 / 6)])

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
        node = np.full(N + 1, 2 * h / 6)
        node[[0, -1]] = h / 6
        return select, np.concatenate([np.repeat(node, nu), np.full(N * nu, 4 * h / 6)])

    def intervals(self, s: Symbols, imposed) -> list:
        N, f = self.N, self.rate
        U = s.V[:, : N + 1]
        M = 0.5 * (U[:, :-1] + U[:, 1:]) if self.linear_control else s.V[:, N + 1:]
        defects = []
        for k in range(N):
            tk = k * s.h
            fk, fk1 = f(s.X[:, k], U[:, k], tk), f(s.X[:, k + 1], U[:, k + 1], tk + s.h)
            xm = 0.5 * (s.X[:, k] + s.X[:, k + 1]) + s.h / 8 * (fk - fk1)
            fm = f(xm, M[:, k], tk + s.h / 2)
            defects.append((s.X[:, k + 1] - s.X[:, k] - s.h / 6 * (fk + 4 * fm + fk1)) / self.state_scale)
            imposed("node", k, k / N, s.X[:, k], U[:, k], tk)
            imposed("mid", k, (k + 0.5) / N, xm, M[:, k], tk + s.h / 2)
        imposed("node", N, 1.0, s.X[:, N], U[:, N], s.tf)
        return defects

    def control_value_shares(self) -> np.ndarray:
        nodes = np.linspace(0.0, 1.0, self.N + 1)
        return nodes if self.linear_control else np.concatenate([nodes, (np.arange(self.N) + 0.5) / self.N])

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

    def control_function(self, z: np.ndarray):
        nodes, mids = self.node_controls(z), self.midpoint_controls(z)
        h = self.final_time(z) / self.N

        def u(t: float) -> np.ndarray:
            k = min(int(t // h), self.N - 1)
            if self.linear_control:
                share = (t - k * h) / h
                return (1.0 - share) * nodes[k] + share * nodes[k + 1]
            a, m, b = quadratic_weights((t - k * h) / h)
            return a * nodes[k] + m * mids[k] + b * nodes[k + 1]

        return u

    def refined(self, z: np.ndarray) -> tuple[HermiteSimpsonProgram, np.ndarray]:
        """The old nodes, the Hermite-Simpson midpoint states as the new nodes between them, the controls'
        quadratics at the new midpoints."""
        N = self.N
        fine = HermiteSimpsonProgram(self.problem, intervals=2 * N)
        X, U, M = self.states(z), self.node_controls(z), self.midpoint_controls(z)
        tf = self.final_time(z)
        h = tf / N
        f = np.array([np.asarray(self.rate(X[k], U[k], k * h)).ravel() for k in range(N + 1)])
        states = np.empty((2 * N + 1, self.nx))
        states[0::2], states[1::2] = X, 0.5 * (X[:-1] + X[1:]) + h / 8 * (f[:-1] - f[1:])
        controls = np.empty((2 * N + 1, self.nu))
        controls[0::2], controls[1::2] = U, M
        if self.linear_control:
            return fine, fine.assemble(states, controls, tf)

        def quadratic(s: float) -> np.ndarray:
            a, m, b = quadratic_weights(s)
            return a * U[:-1] + m * M + b * U[1:]

        mids = np.empty((2 * N, self.nu))
        mids[0::2], mids[1::2] = quadratic(0.25), quadratic(0.75)
        return fine, fine.assemble(states, np.vstack([controls, mids]), tf)
