"""Method ``scp_arcs``: Wang & Tang's burn/coast transcription, solved by sequential convex programming.

The maneuver is split into arcs burn - coast - burn - ... (``burns`` burn arcs); each
burn into ``S`` equal sub-intervals. The design vector (eq. 4) holds the state and
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

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003, eqs. (4)-(11).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from convexguid.dynamics.clohessy_wiltshire import cw_stm, cw_stm_derivative
from convexguid.families.rendezvous.case import BurnArc, Rendezvous, ThrustPlan
from convexguid.scp.problem import (
    ConstraintBlock,
    CurvatureModel,
    Evaluation,
    LinearConstraints,
    OutputConstraints,
    ProgramSize,
)
from convexguid.transcription.hermite_simpson import hermite_simpson_defects


@dataclass(frozen=True)
class ArcLayout:
    """Where each node and duration lives in the design vector (``burns`` burns, ``S`` sub-intervals each).

    The arcs run in time order: burn - coast - burn - ... - burn, as in the paper, optionally preceded by a
    ``lead_coast`` from the initial state and followed by a ``trail_coast`` to the final state (an optimum
    whose first burn starts late or whose last burn ends early, which the paper's arcs cannot fly).
    """

    nx: int
    nu: int
    burns: int
    subintervals: int
    lead_coast: bool = False
    trail_coast: bool = False

    @property
    def nodes_per_burn(self) -> int:
        return self.subintervals + 1

    @property
    def num_nodes(self) -> int:
        return self.burns * self.nodes_per_burn

    @property
    def num_arcs(self) -> int:
        return 2 * self.burns - 1 + self.lead_coast + self.trail_coast

    @property
    def num_coasts(self) -> int:
        return self.num_arcs - self.burns

    @property
    def node_size(self) -> int:
        return self.nx + self.nu

    @property
    def num_variables(self) -> int:
        return self.num_nodes * self.node_size + self.num_arcs

    @property
    def duration_offset(self) -> int:
        return self.num_nodes * self.node_size

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """States ``(n, nx)``, directions ``(n, nu)`` and arc durations from the design vector."""
        nodes = x[: self.duration_offset].reshape(self.num_nodes, self.node_size)
        return nodes[:, : self.nx], nodes[:, self.nx:], x[self.duration_offset:]

    def join(self, states: np.ndarray, directions: np.ndarray, durations: np.ndarray) -> np.ndarray:
        return np.concatenate([np.hstack([states, directions]).ravel(), durations])

    def state_index(self, node: int) -> np.ndarray:
        return node * self.node_size + np.arange(self.nx)

    def direction_index(self, node: int) -> np.ndarray:
        return node * self.node_size + self.nx + np.arange(self.nu)

    def burn_nodes(self, burn: int) -> np.ndarray:
        return burn * self.nodes_per_burn + np.arange(self.nodes_per_burn)

    def burn_arc(self, burn: int) -> int:
        """Index of burn ``burn``'s duration among the arc durations."""
        return self.lead_coast + 2 * burn

    def coast_arc(self, coast: int) -> int:
        """Index of coast ``coast``'s duration (coasts counted in time order, the lead coast first)."""
        return 2 * coast if self.lead_coast else 2 * coast + 1

    def coast_ends(self, coast: int) -> tuple[int | None, int | None]:
        """The nodes a coast leaves and reaches; None for the initial (lead coast) or final (trail coast) state."""
        before = coast - self.lead_coast  # the burn the coast follows
        leaves = None if before < 0 else int(self.burn_nodes(before)[-1])
        reaches = None if before + 1 >= self.burns else int(self.burn_nodes(before + 1)[0])
        return leaves, reaches


END_COAST_FRACTION = 1e-3
"""A burn of the plan followed (:meth:`ArcsProgram.following`) that starts or ends more than this fraction of the
maneuver away from its end gets a coast arc there."""


class ArcsProgram:
    """:class:`convexguid.scp.problem.NonconvexProgram` of the burn/coast transcription."""

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
        """The guess the program was made with (:meth:`following`), else the paper's kind of guess, from the
        boundary conditions only.

        Equal arc durations; states interpolated linearly in time between the boundary
        states; every direction along the velocity change :math:`v_f - v_0`.
        """
        if self._guess is not None:
            return self._guess.copy()
        case, lay = self.case, self.layout
        durations = np.full(lay.num_arcs, case.duration / lay.num_arcs)
        times = self.node_times(durations)
        s = ((times - case.t0) / case.duration)[:, None]
        states = (1 - s) * case.x0 + s * case.xf
        dv = case.xf[case.nu:] - case.x0[case.nu:]
        direction = dv / np.linalg.norm(dv) if np.linalg.norm(dv) > 0 else np.eye(case.nu)[0]
        return lay.join(states, np.tile(direction, (lay.num_nodes, 1)), durations)

    def following(self, burns: tuple[BurnArc, ...], thrust: ThrustPlan, states_at) -> ArcsProgram:
        """A program of as many burns as another plan (the ``lcvx`` optimum), started from its burn structure.

        The burn arcs take the plan's burn durations and the coasts the gaps between them; a first burn that
        starts later, or a last one that ends earlier, than :data:`END_COAST_FRACTION` of the maneuver from its
        end gets a lead or trail coast. The nodes take the plan's states at their times (``states_at(times)``,
        the flown plan) and the direction of its thrust, or of the nearest burn's middle where it is off.
        """
        case = self.case
        slack = END_COAST_FRACTION * case.duration
        lead, trail = burns[0].start_s - case.t0 > slack, case.tf - burns[-1].end_s > slack
        lay = ArcLayout(case.nx, case.nu, len(burns), self.layout.subintervals, lead, trail)
        durations = np.empty(lay.num_arcs)
        durations[[lay.burn_arc(b) for b in range(lay.burns)]] = [b.duration_s for b in burns]
        gaps = [max(b.start_s - a.end_s, 0.0) for a, b in zip(burns[:-1], burns[1:], strict=True)]
        gaps = [burns[0].start_s - case.t0] * lead + gaps + [case.tf - burns[-1].end_s] * trail
        durations[[lay.coast_arc(c) for c in range(lay.num_coasts)]] = gaps
        spare = case.duration - durations.sum()  # the ends left without a coast, shared by the coasts
        if lay.num_coasts:
            durations[[lay.coast_arc(c) for c in range(lay.num_coasts)]] += spare / lay.num_coasts
        else:
            durations[0] += spare
        program = ArcsProgram(case, lay.burns, lay.subintervals, None, lead, trail)
        times = program.node_times(durations)
        middles = np.array([0.5 * (b.start_s + b.end_s) for b in burns])
        directions = np.empty((times.size, lay.nu))
        for k, t in enumerate(times):
            u = thrust(t)
            if np.linalg.norm(u) < 1e-6:
                u = thrust(middles[np.argmin(np.abs(middles - t))])
            norm = np.linalg.norm(u)
            directions[k] = u / norm if norm > 0 else np.eye(lay.nu)[0]
        program._guess = lay.join(states_at(times), directions, durations)
        return program

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

    # --- reading a solution ----------------------------------------------------------------------
    def node_times(self, durations: np.ndarray) -> np.ndarray:
        """Time of every node: burn nodes equally spaced over their arc."""
        lay, starts = self.layout, self._arc_starts(durations)
        return np.concatenate([starts[lay.burn_arc(b)] + np.linspace(0.0, durations[lay.burn_arc(b)],
                                                                       lay.nodes_per_burn)
                               for b in range(lay.burns)])

    def _arc_starts(self, durations: np.ndarray) -> np.ndarray:
        return self.case.t0 + np.concatenate([[0.0], np.cumsum(durations)[:-1]])

    def burn_arcs(self, x: np.ndarray) -> tuple[BurnArc, ...]:
        lay = self.layout
        _, _, durations = lay.split(x)
        starts = self._arc_starts(durations)
        return tuple(BurnArc(float(starts[lay.burn_arc(b)]), float(starts[lay.burn_arc(b)]
                                                                    + durations[lay.burn_arc(b)]))
                     for b in range(lay.burns))

    def thrust_plan(self, x: np.ndarray) -> ThrustPlan:
        """The engine's command: full thrust along the interpolated, normalized node direction on burns.

        The transcription interpolates the direction linearly (eq. 6), whose norm dips
        slightly below 1 between nodes; a constant-thrust engine flies its unit vector,
        which is what the verification propagates.
        """
        _, dirs, durations = self.layout.split(x)
        return ThrustPlan.from_nodes(self.node_times(durations), dirs, self.burn_arcs(x), normalize=True)

    def refined(self, x: np.ndarray, subintervals: int) -> tuple[ArcsProgram, np.ndarray]:
        """The same transcription with ``subintervals`` per burn, and ``x`` carried over as its start.

        Arc durations are kept; states and directions are interpolated linearly in time inside
        each burn (directions renormalised).
        """
        finer = ArcsProgram(self.case, self.layout.burns, subintervals, None, self.layout.lead_coast,
                            self.layout.trail_coast)
        lay, new = self.layout, finer.layout
        states, dirs, durations = lay.split(x)
        old_s = np.linspace(0.0, 1.0, lay.nodes_per_burn)
        new_s = np.linspace(0.0, 1.0, new.nodes_per_burn)
        new_states, new_dirs = [], []
        for b in range(lay.burns):
            nodes = lay.burn_nodes(b)
            new_states.append(np.column_stack([np.interp(new_s, old_s, col) for col in states[nodes].T]))
            d = np.column_stack([np.interp(new_s, old_s, col) for col in dirs[nodes].T])
            new_dirs.append(d / np.linalg.norm(d, axis=1, keepdims=True))
        return finer, new.join(np.vstack(new_states), np.vstack(new_dirs), durations)
