"""A maneuver in phases: burn, coast and burn arcs, stages, a hold point, each a
:class:`~convexguid.ocp.problem.Problem` of its own, linked at their ends.

Each phase states its own states, controls (none: a coast), duration (fixed, or free within bounds: its
:meth:`~convexguid.ocp.problem.Problem.final_time`), constraints, transcription and grid, and its time runs from
0 at its start. :class:`Phases` joins them in time order: :meth:`Phases.connect` makes states continuous from one
phase to another, :meth:`Phases.link` states any equality of their end values (:meth:`Problem.start`,
:meth:`Problem.end`, :attr:`Problem.duration`), linear or not, and :meth:`Phases.link_constraint` an inequality.
The objective is the sum of the phases' objectives (a phase may have none). The plan goes through the same engine,
the same dense check per phase (and of every link on the flown ends) and the same repairs as a single problem's
(:mod:`convexguid.ocp.phased`).

Minimal use::

    boost, coast = Problem("boost"), Problem("coast")
    ...                                # states, dynamics, final_time(bounds=...) of each
    coast.minimize_terminal(-coast_h)  # the highest altitude at the end of the coast
    flight = Phases("ascent", [boost, coast])
    flight.connect(boost, coast)       # every state they share by name is continuous
    solution = flight.solve()
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import casadi as ca
import numpy as np

from convexguid.errors import SpecError
from convexguid.ocp.declarations import column
from convexguid.ocp.problem import Problem
from convexguid.ocp.size import check_phases_size


class Phases:
    """Phases in time order and the links between their ends (see the module docstring)."""

    def __init__(self, name: str, phases: Sequence[Problem]) -> None:
        if not isinstance(name, str) or not name.strip():
            raise SpecError(f"Phases: name: expected a non-empty string (got {name!r})")
        self.name = name
        phases = list(phases)
        if len(phases) < 1 or not all(isinstance(p, Problem) for p in phases):
            raise SpecError(f"{name}: phases: expected a list of convexguid.ocp.Problem (got {phases!r})")
        names = [p.name for p in phases]
        if len(set(names)) != len(names):
            raise SpecError(f"{name}: phases: every phase needs its own name (got {', '.join(names)})")
        for p in phases:
            if p.phase_of is not None and p.phase_of != name:
                raise SpecError(f"{name}: phase {p.name!r} is already a phase of {p.phase_of!r}")
            p.phase_of = name
        self.phases = phases
        self.links: list[tuple[str, ca.SX, bool]] = []
        """``(name, expression, equality)`` of every link, the continuities of :meth:`connect` among them."""
        self.connections: list[tuple[int, int, tuple[str, ...]]] = []

    def _index(self, phase: Problem, where: str) -> int:
        for i, p in enumerate(self.phases):
            if p is phase:
                return i
        raise SpecError(f"{self.name}: {where}: {getattr(phase, 'name', phase)!r} is not one of its phases")

    def connect(self, first: Problem, second: Problem, states: Sequence[str] | None = None) -> None:
        """The named states (default: every state the two share by name) continuous from the end of ``first`` to the
        start of ``second`` (a later phase, not necessarily the next: an engine's acceleration across a coast that
        does not carry it)."""
        where = f"connect({first.name}, {second.name})"
        i, j = self._index(first, where), self._index(second, where)
        if j <= i:
            raise SpecError(f"{self.name}: {where}: the second phase must come later than the first")
        by_name = [{v.name: v.symbol for v in p.states} for p in (first, second)]
        shared = [n for n in by_name[0] if n in by_name[1]]
        names = tuple(shared if states is None else states)
        missing = [n for n in names if n not in by_name[0] or n not in by_name[1]]
        if missing or not names:
            raise SpecError(f"{self.name}: {where}: states {', '.join(missing) or '(none shared)'} are not states of "
                            f"both phases (shared: {', '.join(shared) or 'none'})")
        for n in names:
            self.links.append((f"{first.name}.{n}->{second.name}",
                               second.start(by_name[1][n]) - first.end(by_name[0][n]), True))
        self.connections.append((i, j, names))

    def link(self, name: str, expression) -> None:
        """``expression == 0`` on the phases' end values (symbols from :meth:`Problem.start`, :meth:`Problem.end`
        and :attr:`Problem.duration`), e.g. a total time, or an orbit's energy carried across a staging."""
        self._add_link("link", name, expression, equality=True)

    def link_constraint(self, name: str, expression) -> None:
        """``expression <= 0`` on the phases' end values, e.g. a coast of at least 600 s,
        ``600 - coast.duration``, or a whole maneuver within its window."""
        self._add_link("link_constraint", name, expression, equality=False)

    def _add_link(self, call: str, name: str, expression, equality: bool) -> None:
        where = f"{self.name}: {call} {name!r}"
        expression = column(where, expression)
        if expression.shape[1] != 1 or expression.shape[0] < 1:
            raise SpecError(f"{where}: expected a column of expressions (got shape {expression.shape})")
        if name in {link[0] for link in self.links}:
            raise SpecError(f"{where}: the name is already taken")
        known = {key for p in self.phases for key in p.ends}
        unknown = sorted({str(s) for s in ca.symvar(expression)} - known)
        if unknown:
            raise SpecError(f"{where}: uses {', '.join(unknown)}; a link is stated on phase ends "
                            "(phase.start(state), phase.end(state), phase.duration)")
        self.links.append((name, expression, equality))

    def check(self) -> None:
        """Refuse a statement that cannot be solved, one line naming what is wrong."""
        for p in self.phases:
            p.check()
        check_phases_size(self.name, self.phases)
        if all(p.objective is None for p in self.phases):
            raise SpecError(f"{self.name}: objective: no phase states one; give one phase (or several: they add up) "
                            "minimize_time(), minimize_energy(), minimize_fuel() or minimize_terminal(...)")

    def guess(self, programs) -> np.ndarray:
        """The first guess: each phase's straight line, a state left free at a phase's end taking its value from
        the straight line through the values stated along the states it is connected to (in time, over the
        phases' guessed durations), and each user's :meth:`Problem.initial_guess` as given."""
        durations = [p.tf if p.tf is not None else p.tf_guess for p in self.phases]
        starts = np.concatenate([[0.0], np.cumsum(durations)])
        anchors: dict[tuple[int, str], list[tuple[float, float]]] = {}
        groups = {(i, v.name): (i, v.name) for i, p in enumerate(self.phases) for v in p.states}

        def root(key):
            while groups[key] != key:
                key = groups[key]
            return key

        for i, j, names in self.connections:
            for n in names:
                groups[root((j, n))] = root((i, n))
        for i, p in enumerate(self.phases):
            for v in p.states:
                for value, at in ((v.initial, starts[i]), (v.final, starts[i + 1])):
                    if value is not None:
                        anchors.setdefault(root((i, v.name)), []).append((float(at), value))
        pieces = []
        for i, (p, program) in enumerate(zip(self.phases, programs, strict=True)):
            start, end, control = p.straight_line()
            for k, v in enumerate(p.states):
                points = sorted(anchors.get(root((i, v.name)), []))
                if not points:
                    continue
                t, y = zip(*points, strict=True)
                if v.initial is None:
                    start[k] = np.interp(starts[i], t, y)
                if v.final is None:
                    end[k] = np.interp(starts[i + 1], t, y)
            pieces.append(program.initial_guess() if p.guess_nodes is not None else
                          program.straight_guess(start, end, control))
        return np.concatenate(pieces)

    def solve(self, max_iterations: int = 300, verification_points: int = 20, log=None, backend: str = "auto"):
        """Transcribe every phase, plan by SCP, check each phase densely and every link on the flown ends: a
        :class:`~convexguid.solution.Solution` whose tables run over the whole maneuver (a ``phase`` column gives
        each row's phase, its index from 0; ``log`` and ``backend`` as for :meth:`Problem.solve`)."""
        from convexguid.ocp.solve import solve_phases  # the SCP engine and SciPy load at the first solve

        started = time.perf_counter()
        return solve_phases(self, started, max_iterations, verification_points, log, backend)
