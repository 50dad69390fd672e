"""Method ``scp_arcs``: Wang & Tang's burn/coast transcription, written by hand, solved by SCP.

The maneuver is split into arcs burn - coast - burn - ... (``burns`` burn arcs); each
burn into ``S`` equal sub-intervals. The design vector (eq. 4,
:class:`~convexguid.families.rendezvous.arc_layout.ArcLayout`) holds the state and
the thrust direction at every node and the arc durations:

.. math::

    D = [X_1^T, U_1^T, \\dots, X_n^T, U_n^T, T_1, \\dots, T_{2b-1}]^T,
    \\qquad n = b (S + 1).

Constraints: Hermite-Simpson defects on every burn sub-interval of length
:math:`h = T_{burn}/S` (eqs. 5-8, :mod:`convexguid.transcription.hermite_simpson`),
the coast map :math:`\\Phi(T_{coast}) X_{end} - X_{start} = 0` (eq. 9, closed-form STM),
:math:`|U_k|^2 = 1` at every node, the boundary states, :math:`\\sum T_i = t_f - t_0` and
:math:`T_i \\ge 0`. Objective: the total burn time :math:`\\sum T_{burn}` (eq. 10), linear.
Started from the ``lcvx`` optimum (:meth:`ArcsProgram.following`), the arcs may also open with a coast from
the initial state or close with one to the final state, where that optimum does (the paper's arcs start and
end on a burn, which a fixed-time rendezvous whose best burns sit inside the window cannot fly).

The nonconvex parts (the unit thrust direction, the durations multiplying the
dynamics, the STM of an unknown coast duration) are linearized about the previous
iterate by the SCP engine; the subproblem is a linear program in a trust region.
The paper instead solves the NLP with an exterior penalty (eq. 12).

The same NLP stated as a maneuver in phases on :mod:`convexguid.ocp` is
:class:`~convexguid.families.rendezvous.arc_phases.PhasedArcsProgram` (beside this one, not yet the method's:
its plans agree with this program's to round-off, not bit for bit).

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003, eqs. (4)-(11).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from convexguid.dynamics.clohessy_wiltshire import cw_stm, cw_stm_derivative
from convexguid.families.rendezvous.arc_layout import ArcLayout, ArcsPlan
from convexguid.families.rendezvous.case import Rendezvous
from convexguid.scp.problem import (
    ConstraintBlock,
    CurvatureModel,
    Evaluation,
    LinearConstraints,
    OutputConstraints,
    ProgramSize,
)
from convexguid.transcription.hermite_simpson import hermite_simpson_defects


class ArcsProgram(ArcsPlan):
    """:class:`convexguid.scp.problem.NonconvexProgram` of the burn/coast transcription, written by hand (its
    starts and readings: :class:`~convexguid.families.rendezvous.arc_layout.ArcsPlan`)."""

    def __init__(self, case: Rendezvous, burns: int, subintervals: int, guess: np.ndarray | None = None,
                 lead_coast: bool = False, trail_coast: bool = False) -> None:
        self.case = case
        self.layout = ArcLayout(case.nx, case.nu, burns, subintervals, lead_coast, trail_coast)
        self.num_variables = self.layout.num_variables
        self._A, self._B = case.matrices()
        self._guess = guess

    # --- dynamics f(x, u) = A x + B u on stacked rows -------------------------------------------
    def _f(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return x @ self._A.T + u @ self._B.T

    def _jac(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        k = x.shape[0]
        return np.broadcast_to(self._A, (k, *self._A.shape)), np.broadcast_to(self._B, (k, *self._B.shape))

    # --- NonconvexProgram -----------------------------------------------------------------------
    def size(self) -> ProgramSize:
        """The paper's counts: defects, coast maps, unit directions, boundary states, total time; T >= 0."""
        lay = self.layout
        nonlinear = lay.burns * lay.subintervals * lay.nx + (lay.burns - 1) * lay.nx + lay.num_nodes
        lin = self.linear_constraints()
        return ProgramSize(self.num_variables, nonlinear + lin.A.shape[0], lin.G.shape[0])

    def initial_guess(self) -> np.ndarray:
        """The guess the program was made with (:meth:`following`), else :meth:`paper_guess`."""
        return self._guess.copy() if self._guess is not None else self.paper_guess()

    def variable_scale(self) -> np.ndarray:
        """Position, velocity, direction and duration scales (the trust region is a box in these units)."""
        case, lay = self.case, self.layout
        d = case.nu
        pos = max(np.abs(case.x0[:d]).max(), np.abs(case.xf[:d]).max(), 1.0)
        vel = max(np.abs(case.x0[d:]).max(), np.abs(case.xf[d:]).max(), case.accel * case.duration / 10)
        node = np.concatenate([np.full(d, pos), np.full(d, vel), np.ones(lay.nu)])
        return np.concatenate([np.tile(node, lay.num_nodes), np.full(lay.num_arcs, case.duration)])

    def residual_weights(self) -> np.ndarray:
        return np.zeros(0)

    def linear_cost(self) -> np.ndarray:
        """Total burn time, eq. (10)."""
        c = np.zeros(self.num_variables)
        lay = self.layout
        c[[lay.duration_offset + lay.burn_arc(b) for b in range(lay.burns)]] = 1.0
        return c

    @cached_property
    def _linear(self) -> LinearConstraints:
        """Boundary states (where no lead or trail coast reaches them), :math:`\\sum T_i = t_f - t_0`, and
        :math:`-T_i \\le 0`."""
        lay, n = self.layout, self.num_variables
        ends = [(0, self.case.x0)] * (not lay.lead_coast) + [(lay.num_nodes - 1, self.case.xf)] * (not lay.trail_coast)
        A = np.zeros((len(ends) * lay.nx + 1, n))
        for i, (node, _) in enumerate(ends):
            A[i * lay.nx + np.arange(lay.nx), lay.state_index(node)] = 1.0
        A[-1, lay.duration_offset:] = 1.0
        b = np.concatenate([*(state for _, state in ends), [self.case.duration]])
        G = np.zeros((lay.num_arcs, n))
        G[np.arange(lay.num_arcs), lay.duration_offset + np.arange(lay.num_arcs)] = -1.0
        return LinearConstraints(A, b, G, np.zeros(lay.num_arcs))

    def linear_constraints(self) -> LinearConstraints:
        return self._linear

    def output_constraints(self) -> OutputConstraints:
        return OutputConstraints.none(0)

    def evaluate(self, x: np.ndarray, jacobians: bool = True) -> Evaluation:
        blocks = (self._burn_defects(x, jacobians), self._coast_defects(x, jacobians),
                  self._unit_directions(x, jacobians))
        return Evaluation(np.zeros(0), np.zeros((0, self.num_variables)) if jacobians else None, (), blocks)

    @cached_property
    def _patterns(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Structural nonzeros ``(rows, cols)`` of each block's Jacobian (fixed, so the subproblem's is too)."""
        lay = self.layout
        nx, S = lay.nx, lay.subintervals

        def node_cols(node: int) -> np.ndarray:
            return node * lay.node_size + np.arange(lay.node_size)

        def dense_block(rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            r, c = np.meshgrid(rows, cols, indexing="ij")
            return r.ravel(), c.ravel()

        burn, coast, unit = [], [], []
        for b in range(lay.burns):
            nodes = lay.burn_nodes(b)
            for k in range(S):
                cols = np.concatenate([node_cols(nodes[k]), node_cols(nodes[k + 1]),
                                       [lay.duration_offset + lay.burn_arc(b)]])
                burn.append(dense_block((b * S + k) * nx + np.arange(nx), cols))
        for c in range(lay.num_coasts):
            leaves, reaches = lay.coast_ends(c)
            cols = [lay.state_index(node) for node in (leaves, reaches) if node is not None]
            cols = np.concatenate([*cols, [lay.duration_offset + lay.coast_arc(c)]])
            coast.append(dense_block(c * nx + np.arange(nx), cols))
        for k in range(lay.num_nodes):
            unit.append(dense_block(np.array([k]), lay.direction_index(k)))

        def join(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
            if not parts:
                return np.zeros(0, int), np.zeros(0, int)
            return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])

        return {"burn_defects": join(burn), "coast_defects": join(coast), "unit_thrust_direction": join(unit)}

    def _block(self, name: str, values: np.ndarray, jacobian_data: np.ndarray | None) -> ConstraintBlock:
        """A constraint block in nondimensional units (defects divided by the position/velocity scales).

        ``jacobian_data`` lists the Jacobian's entries in the order of :attr:`_patterns` (row-major
        over each block of rows and its columns); the result's Jacobian is sparse with that pattern.
        """
        scale = self._state_scale if name != "unit_thrust_direction" else np.ones(1)
        per_row = np.resize(1.0 / scale, values.size)
        jac = None
        if jacobian_data is not None:
            rows, cols = self._patterns[name]
            jac = sp.coo_matrix((jacobian_data * per_row[rows], (rows, cols)), shape=(values.size, self.num_variables))
        return ConstraintBlock(name, values * per_row, jac, "" if name == "unit_thrust_direction" else "scaled")

    @cached_property
    def _state_scale(self) -> np.ndarray:
        """Position and velocity scales of :meth:`variable_scale`, one per state component."""
        return self.variable_scale()[: self.layout.nx]

    def curvature_model(self) -> CurvatureModel:
        """Diagonal curvature :math:`2\\lambda_k` of :math:`\\lambda_k(|U_k|^2 - 1)` on the direction entries
        (raised to zero where negative).

        This is the term that keeps the subproblem from gaining thrust by turning
        :math:`U_k` along the tangent of the unit sphere (a linear model sees no cost in
        it); the other constraints' curvature is left to the trust region.
        """
        columns = self._direction_columns
        nodes, nu = columns.shape

        def values(x: np.ndarray, weights) -> np.ndarray:
            # the unit-direction rows are the last equality block
            return np.repeat(np.maximum(2.0 * weights.equality[-nodes:], 0.0), nu)

        return CurvatureModel(columns.ravel(), columns.ravel(), values)

    @cached_property
    def _direction_columns(self) -> np.ndarray:
        """Design-vector index of every direction component, shape ``(num_nodes, nu)``."""
        return np.array([self.layout.direction_index(k) for k in range(self.layout.num_nodes)])

    # --- constraint blocks -----------------------------------------------------------------------
    def _burn_defects(self, x: np.ndarray, jacobians: bool) -> ConstraintBlock:
        """Hermite-Simpson defects of every burn sub-interval, eqs. (5)-(8)."""
        lay = self.layout
        states, dirs, durations = lay.split(x)
        S = lay.subintervals
        values, data = [], []
        for burn in range(lay.burns):
            nodes = lay.burn_nodes(burn)
            h = np.full(S, durations[lay.burn_arc(burn)] / S)
            hs = hermite_simpson_defects(self._f, self._jac, states[nodes[:-1]], dirs[nodes[:-1]],
                                         states[nodes[1:]], dirs[nodes[1:]], h)
            values.append(hs.values.ravel())
            # columns per sub-interval: node k (state, direction), node k+1, the burn's duration (h = T/S)
            data.append(np.concatenate([hs.d_x0, hs.d_u0, hs.d_x1, hs.d_u1, hs.d_h[:, :, None] / S], axis=2).ravel())
        return self._block("burn_defects", np.concatenate(values), np.concatenate(data) if jacobians else None)

    def _coast_defects(self, x: np.ndarray, jacobians: bool) -> ConstraintBlock:
        """Coast arcs, eq. (9): :math:`\\Phi(T_c) X_{end} - X_{start}` with :math:`d\\Phi/dT = A\\Phi` (a lead
        coast leaves the initial state, a trail coast reaches the final one: fixed, so without columns)."""
        lay, n, dim, case = self.layout, self.case.mean_motion, self.case.dim, self.case
        states, _, durations = lay.split(x)
        values, data = [np.zeros(0)], [np.zeros(0)]
        for coast in range(lay.num_coasts):
            leaves, reaches = lay.coast_ends(coast)
            x_leave = case.x0 if leaves is None else states[leaves]
            x_reach = case.xf if reaches is None else states[reaches]
            tc = durations[lay.coast_arc(coast)]
            phi = cw_stm(n, tc, dim)
            values.append(phi @ x_leave - x_reach)
            # columns: the state the coast leaves, the state it reaches (each if free), the coast duration
            d_tc = cw_stm_derivative(n, tc, dim) @ x_leave
            parts = [phi] * (leaves is not None) + [-np.eye(lay.nx)] * (reaches is not None) + [d_tc[:, None]]
            data.append(np.hstack(parts).ravel())
        return self._block("coast_defects", np.concatenate(values), np.concatenate(data) if jacobians else None)

    def _unit_directions(self, x: np.ndarray, jacobians: bool) -> ConstraintBlock:
        """:math:`|U_k|^2 - 1 = 0` at every node."""
        _, dirs, _ = self.layout.split(x)
        return self._block("unit_thrust_direction", np.sum(dirs**2, axis=1) - 1.0,
                           (2 * dirs).ravel() if jacobians else None)
