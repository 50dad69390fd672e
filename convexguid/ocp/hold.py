"""Zero- and first-order-hold transcriptions: the dynamics integrated across each interval (multiple shooting).

The control is held between nodes: constant on each interval (zero-order hold, one value per interval) or linear
between node values (first-order hold, one value per node), the way a flight computer commands it. Each interval's
defect is the node state less the flow from the previous node under the held control,

.. math::

    x_{k+1} - \\Phi_h(x_k, u_k, u_{k+1}, t_k) = 0,

divided by the states' scales, with :math:`\\Phi_h` ``substeps`` classical Runge-Kutta steps across the interval
(fourth order: on Clohessy-Wiltshire with four steps across a 9 s interval the map is within 3e-9 (relative) of
the state from the exact discretization, the matrix exponential, and the error falls 256-fold for four times the
steps, tests/test_ocp_holds.py; the dense check judges the flown plan, and a grid that is too coarse is doubled).
CasADi differentiates through the steps: the Jacobian is the exact sensitivity of the discrete map to the node
state, the control values and the final time (what SCPToolbox's and OpenSCvx's PTR get by integrating the
variational equations, here by automatic differentiation). Path constraints hold at the nodes; the dense check
judges them between. The objectives' quadrature: the rectangle rule for a zero-order hold (exact), the
trapezoidal rule on the node values for a first-order hold. A closed-form flow (``"flow"``) replaces the
Runge-Kutta steps of a zero-order hold by the map the user states (:class:`ClosedFormFlowProgram`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from convexguid.ocp.parts import runge_kutta
from convexguid.ocp.transcription import Symbols, Transcription


class HoldProgram(Transcription):
    """A hold of ``order`` 0 or 1 (subclasses below), the flow integrated by ``problem.substeps`` RK4 steps, on equal
    intervals (a hold takes no grid of its own: its steps, instants and refinement are the equal ones)."""

    order = 0

    def control_values_per_axis(self) -> int:
        return self.N + self.order

    def per_step_weights(self) -> np.ndarray:
        weights = np.ones(self.control_values_per_axis())
        if self.order == 1:
            weights[[0, -1]] = 0.5
        return weights

    def _flow(self) -> ca.Function:
        """``(x0, u_start, u_end, t0, h) -> x(t0 + h)`` under the held control."""
        p = self.problem
        x0, ua, ub = (ca.SX.sym(name, size) for name, size in (("x0", self.nx), ("ua", self.nu), ("ub", self.nu)))
        t0, h = ca.SX.sym("t0"), ca.SX.sym("h")
        steps = p.substeps
        dt = h / steps

        def rate(x, tau):
            control = ua + (tau / h) * (ub - ua) if self.order == 1 else ua
            return self.rate(x, control, t0 + tau)

        return ca.Function("flow", [x0, ua, ub, t0, h], [runge_kutta(rate, x0, dt, steps)])

    def _interval_controls(self, V, k: int):
        """The held control's start and end values on interval ``k`` (columns of ``V``)."""
        return (V[:, k], V[:, k + 1]) if self.order == 1 else (V[:, k], V[:, k])

    def _node_control(self, V, k: int):
        return V[:, k] if self.order == 1 else V[:, min(k, self.N - 1)]

    def intervals(self, s: Symbols, imposed) -> list:
        self.flow = flow = self._flow()
        defects = []
        for k in range(self.N):
            start, end = self._interval_controls(s.V, k)
            defects.append((s.X[:, k + 1] - flow(s.X[:, k], start, end, k * s.h, s.h)) / self.state_scale)
        for k in range(self.N + 1):
            imposed("node", k, k / self.N, s.X[:, k], self._node_control(s.V, k), k * s.h)
        return defects

    def control_value_shares(self) -> np.ndarray:
        # a zero-order hold's value stands for its interval (its middle), a first-order hold's for its node
        nodes = self.node_shares()
        return nodes if self.order == 1 else 0.5 * (nodes[:-1] + nodes[1:])

    def node_controls(self, z: np.ndarray) -> np.ndarray:
        values = self.control_values(z)
        return values if self.order == 1 else np.vstack([values, values[-1:]])

    def values_from_nodes(self, controls: np.ndarray) -> np.ndarray:
        return controls if self.order == 1 else controls[:-1]

    def interval_control_columns(self, k: int, j: int) -> tuple[int, ...]:
        first, nu = self.control_start, self.nu
        return (first + k * nu + j, first + (k + 1) * nu + j) if self.order == 1 else (first + k * nu + j,)

    def interval_weights(self, share: float) -> tuple[float, ...]:
        return (1.0 - share, share) if self.order == 1 else (1.0,)

    def control_function(self, z: np.ndarray):
        values = self.control_values(z)
        h = self.final_time(z) / self.N

        def u(t: float) -> np.ndarray:
            k = min(int(t // h), self.N - 1)
            if self.order == 0:
                return values[k]
            share = (t - k * h) / h
            return (1.0 - share) * values[k] + share * values[k + 1]

        return u

    def refined(self, z: np.ndarray) -> tuple[HoldProgram, np.ndarray]:
        """The old nodes, the flow to each interval's middle as the new nodes between them, the same held
        control (a zero-order hold's value twice; a first-order hold's line sampled at the new node)."""
        N = self.N
        fine = type(self)(self.problem, intervals=2 * N)
        X, values = self.states(z), self.control_values(z)
        tf = self.final_time(z)
        h = tf / N
        states = np.empty((2 * N + 1, self.nx))
        states[0::2] = X
        for k in range(N):
            start = values[k]
            end = values[k + 1] if self.order == 1 else start
            middle = 0.5 * (start + end) if self.order == 1 else start
            states[2 * k + 1] = np.asarray(self.flow(X[k], start, middle, k * h, h / 2)).ravel()
        if self.order == 1:
            fine_values = np.empty((2 * N + 1, self.nu))
            fine_values[0::2], fine_values[1::2] = values, 0.5 * (values[:-1] + values[1:])
        else:
            fine_values = np.repeat(values, 2, axis=0)
        return fine, fine.assemble(states, fine_values, tf)


class ZeroOrderHoldProgram(HoldProgram):
    method = "zoh"
    order = 0


class FirstOrderHoldProgram(HoldProgram):
    method = "foh"
    order = 1


class ClosedFormFlowProgram(ZeroOrderHoldProgram):
    """A zero-order hold whose node-to-node map is the problem's closed-form flow
    (:meth:`~convexguid.ocp.problem.Problem.flow`) instead of Runge-Kutta steps: exact for any interval length."""

    method = "flow"

    def _flow(self) -> ca.Function:
        p = self.problem
        x0, ua, ub = (ca.SX.sym(name, size) for name, size in (("x0", self.nx), ("ua", self.nu), ("ub", self.nu)))
        t0, h = ca.SX.sym("t0"), ca.SX.sym("h")
        after = ca.vertcat(*(p.transitions.get(v.name, v.symbol) for v in p.states))
        after = ca.substitute(after, ca.vertcat(p.state_vector(), p.control_vector(), p.time), ca.vertcat(x0, ua, h))
        return ca.Function("flow", [x0, ua, ub, t0, h], [after])
