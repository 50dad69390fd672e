"""The burn/coast arcs' design vector (Wang & Tang 2003, eq. 4) and what ``scp_arcs`` reads from it and starts with.

The maneuver is split into arcs burn - coast - burn - ... (``burns`` burn arcs); each burn into ``S`` equal
sub-intervals. The design vector holds the state and the thrust direction at every burn node and the arc
durations:

.. math::

    D = [X_1^T, U_1^T, \\dots, X_n^T, U_n^T, T_1, \\dots, T_{2b-1}]^T,
    \\qquad n = b (S + 1).

:class:`ArcLayout` says where each part lives; :class:`ArcsPlan` is what the arcs' program
(:mod:`convexguid.families.rendezvous.arc_phases`) reads and writes in it: the starts (the paper's guess, the
``lcvx`` optimum followed, a finer mesh) as design vectors, and the burns, node times and thrust command read from
one.

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003, eqs. (4)-(11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from convexguid.families.rendezvous.case import BurnArc, Rendezvous, ThrustPlan


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

    def arcs(self) -> list[tuple[str, int]]:
        """``("burn", b)`` or ``("coast", c)`` for every arc in time order (the order of the durations)."""
        burns = [[("burn", b)] + [("coast", b + self.lead_coast)] * (b < self.burns - 1) for b in range(self.burns)]
        return ([("coast", 0)] * self.lead_coast + [arc for pair in burns for arc in pair]
                + [("coast", self.num_coasts - 1)] * self.trail_coast)

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
"""A burn of the plan followed (:meth:`ArcsPlan.following`) that starts or ends more than this fraction of the
maneuver away from its end gets a coast arc there."""


class ArcsPlan:
    """The starts and the readings of the arcs' program, on design vectors.

    A statement is made as ``cls(case, burns, subintervals, guess, lead_coast, trail_coast)`` (``guess``: a design
    vector, default :meth:`paper_guess`) and sets :attr:`case` and :attr:`layout`; :meth:`design_vector` gives the
    design vector of its own vector (the same vector unless it says otherwise).
    """

    case: Rendezvous
    layout: ArcLayout

    def design_vector(self, x: np.ndarray) -> np.ndarray:
        """The design vector (eq. 4) of the program's vector ``x``."""
        return x

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Burn node states ``(n, nx)``, directions ``(n, nu)`` and arc durations of the program's vector ``x``."""
        return self.layout.split(self.design_vector(x))

    def paper_guess(self) -> np.ndarray:
        """The paper's kind of guess, from the boundary conditions only (a design vector).

        Equal arc durations; states interpolated linearly in time between the boundary
        states; every direction along the velocity change :math:`v_f - v_0`.
        """
        case, lay = self.case, self.layout
        durations = np.full(lay.num_arcs, case.duration / lay.num_arcs)
        times = self.node_times(durations)
        s = ((times - case.t0) / case.duration)[:, None]
        states = (1 - s) * case.x0 + s * case.xf
        dv = case.xf[case.nu:] - case.x0[case.nu:]
        direction = dv / np.linalg.norm(dv) if np.linalg.norm(dv) > 0 else np.eye(case.nu)[0]
        return lay.join(states, np.tile(direction, (lay.num_nodes, 1)), durations)

    @classmethod
    def following(cls, case: Rendezvous, subintervals: int, burns: tuple[BurnArc, ...], thrust: ThrustPlan,
                  states_at):
        """A program of as many burns as another plan (the ``lcvx`` optimum), started from its burn structure.

        The burn arcs take the plan's burn durations and the coasts the gaps between them; a first burn that
        starts later, or a last one that ends earlier, than :data:`END_COAST_FRACTION` of the maneuver from its
        end gets a lead or trail coast. The nodes take the plan's states at their times (``states_at(times)``,
        the flown plan) and the direction of its thrust, or of the nearest burn's middle where it is off.
        """
        slack = END_COAST_FRACTION * case.duration
        lead, trail = burns[0].start_s - case.t0 > slack, case.tf - burns[-1].end_s > slack
        lay = ArcLayout(case.nx, case.nu, len(burns), subintervals, lead, trail)
        durations = np.empty(lay.num_arcs)
        durations[[lay.burn_arc(b) for b in range(lay.burns)]] = [b.duration_s for b in burns]
        gaps = [max(b.start_s - a.end_s, 0.0) for a, b in zip(burns[:-1], burns[1:], strict=True)]
        gaps = [burns[0].start_s - case.t0] * lead + gaps + [case.tf - burns[-1].end_s] * trail
        coasts = [lay.coast_arc(c) for c in range(lay.num_coasts)]
        durations[coasts] = gaps
        spare = case.duration - durations.sum()  # the ends left without a coast, shared by the coasts
        if coasts:
            durations[coasts] += spare / lay.num_coasts
        else:
            durations[0] += spare
        times = node_times(case, lay, durations)
        middles = np.array([0.5 * (b.start_s + b.end_s) for b in burns])
        directions = np.empty((times.size, lay.nu))
        for k, t in enumerate(times):
            u = thrust(t)
            if np.linalg.norm(u) < 1e-6:
                u = thrust(middles[np.argmin(np.abs(middles - t))])
            norm = np.linalg.norm(u)
            directions[k] = u / norm if norm > 0 else np.eye(lay.nu)[0]
        return cls(case, lay.burns, subintervals, lay.join(states_at(times), directions, durations), lead, trail)

    def refined(self, x: np.ndarray, subintervals: int):
        """The same arcs with ``subintervals`` per burn, and ``x`` carried over as its start (its own vector).

        Arc durations are kept; states and directions are interpolated linearly in time inside
        each burn (directions renormalised).
        """
        lay = self.layout
        new = ArcLayout(lay.nx, lay.nu, lay.burns, subintervals, lay.lead_coast, lay.trail_coast)
        states, dirs, durations = self.split(x)
        old_s, new_s = np.linspace(0.0, 1.0, lay.nodes_per_burn), np.linspace(0.0, 1.0, new.nodes_per_burn)
        new_states, new_dirs = [], []
        for b in range(lay.burns):
            nodes = lay.burn_nodes(b)
            new_states.append(np.column_stack([np.interp(new_s, old_s, col) for col in states[nodes].T]))
            d = np.column_stack([np.interp(new_s, old_s, col) for col in dirs[nodes].T])
            new_dirs.append(d / np.linalg.norm(d, axis=1, keepdims=True))
        start = new.join(np.vstack(new_states), np.vstack(new_dirs), durations)
        finer = type(self)(self.case, lay.burns, subintervals, start, lay.lead_coast, lay.trail_coast)
        return finer, finer.initial_guess()

    def node_times(self, durations: np.ndarray) -> np.ndarray:
        """Time of every burn node: equally spaced over its arc."""
        return node_times(self.case, self.layout, durations)

    def burn_arcs(self, x: np.ndarray) -> tuple[BurnArc, ...]:
        lay = self.layout
        _, _, durations = self.split(x)
        starts = arc_starts(self.case, durations)
        return tuple(BurnArc(float(starts[lay.burn_arc(b)]), float(starts[lay.burn_arc(b)]
                                                                    + durations[lay.burn_arc(b)]))
                     for b in range(lay.burns))

    def thrust_plan(self, x: np.ndarray) -> ThrustPlan:
        """The engine's command: full thrust along the interpolated, normalized node direction on burns.

        The transcription interpolates the direction linearly (eq. 6), whose norm dips
        slightly below 1 between nodes; a constant-thrust engine flies its unit vector,
        which is what the verification propagates.
        """
        _, dirs, durations = self.split(x)
        return ThrustPlan.from_nodes(self.node_times(durations), dirs, self.burn_arcs(x), normalize=True)


def arc_starts(case: Rendezvous, durations: np.ndarray) -> np.ndarray:
    """Each arc's start time."""
    return case.t0 + np.concatenate([[0.0], np.cumsum(durations)[:-1]])


def node_times(case: Rendezvous, layout: ArcLayout, durations: np.ndarray) -> np.ndarray:
    """Time of every burn node: equally spaced over its arc."""
    starts = arc_starts(case, durations)
    return np.concatenate([starts[layout.burn_arc(b)] + np.linspace(0.0, durations[layout.burn_arc(b)],
                                                                      layout.nodes_per_burn)
                           for b in range(layout.burns)])
