"""An optimal control problem stated in Python: states, controls, a final time, dynamics, constraints, objective.

A :class:`Problem` collects CasADi symbols and what the user says of them; :meth:`Problem.solve` transcribes it
(Hermite-Simpson, a zero- or first-order hold or the mapped Chebyshev grid), hands it to the SCP engine with the
dense SciPy check (:mod:`convexguid.ocp.check`) and returns a :class:`~convexguid.solution.Solution` like every
family's.

What stays exact in every subproblem: bounds on states, controls and the final time, and boundary values.
What the engine linearizes, inside its trust region and exact penalty: the dynamics defects and the path
constraints ``g(x, u) <= 0`` (keep-out zones, cones written as inequalities). Objectives: minimum time (a free
final time), minimum energy (the integral of the squared controls, fixed final time).

A problem stated wrongly is refused before any solve with one line naming the expression
(:class:`~convexguid.errors.SpecError`): a name used twice, a dynamics entry for an unknown symbol or of the wrong
size, a state without dynamics, a boundary value outside a bound, a free final time without bounds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

import casadi as ca
import numpy as np

from convexguid.errors import SpecError
from convexguid.ocp.declarations import PathConstraint, Variable, column, number, point_kind, positive_scale
from convexguid.ocp.scaling import estimated_scales
from convexguid.ocp.size import check_problem_size

TRANSCRIPTION_METHODS = ("hermite-simpson", "zoh", "foh", "chebyshev", "flow")
"""The transcriptions :meth:`Problem.transcription` offers (:mod:`convexguid.ocp.hermite_simpson`,
:mod:`convexguid.ocp.hold`, :mod:`convexguid.ocp.chebyshev`; ``"flow"``: a closed-form flow, :meth:`Problem.flow`)."""


class Problem:
    """An optimal control problem, stated step by step (see the module docstring and ``examples/``)."""

    def __init__(self, name: str) -> None:
        if not isinstance(name, str) or not name.strip():
            raise SpecError(f"Problem: name: expected a non-empty string (got {name!r})")
        self.name = name
        self.states: list[Variable] = []
        self.controls: list[Variable] = []
        self.constraints: list[PathConstraint] = []
        self.rates: dict[str, ca.SX] = {}
        self.transitions: dict[str, ca.SX] = {}
        self.tf: float | None = None
        self.tf_bounds: tuple[float, float] | None = None
        self.tf_guess: float | None = None
        self.objective: str | None = None
        self.fuel_norm = 1
        self.terminal: ca.SX | None = None
        self.boundary_constraints: list[tuple[str, ca.SX, str]] = []
        self.parameter_names: list[str] = []
        self.guess_nodes: tuple[np.ndarray, np.ndarray] | None = None
        self.control_interpolation = "quadratic"
        self.intervals = 30
        self.mesh_tolerance: float | None = None
        self.method = "hermite-simpson"
        self.substeps = 4
        self.time = ca.SX.sym("t")
        self.phase_of: str | None = None
        """The name of the :class:`~convexguid.ocp.phases.Phases` this problem is a phase of (None: alone)."""
        self.ends: dict[str, tuple[str, int]] = {}
        """Each reference :meth:`start` and :meth:`end` made, by its name: ``("start" or "end", index)``, the index
        of a state, or -1 for the duration."""

    # --- declarations -----------------------------------------------------------------------------------------
    def _variable(self, kind: str, name: str, bounds, initial, final, scale, guess, unit: str = "") -> Variable:
        where = f"{self.name}: {kind} {name!r}"
        if not isinstance(name, str) or not name.isidentifier():
            raise SpecError(f"{self.name}: {kind} name: expected an identifier (got {name!r})")
        if name in {v.name for v in (*self.states, *self.controls)}:
            raise SpecError(f"{where}: the name is already taken; give every state and control its own name")
        lower, upper = (None, None) if bounds is None else bounds
        lower, upper = number(f"{where}: lower bound", lower), number(f"{where}: upper bound", upper)
        if lower is not None and upper is not None and lower > upper:
            raise SpecError(f"{where}: bounds: lower {lower:g} is above upper {upper:g}")
        initial, final = number(f"{where}: initial", initial), number(f"{where}: final", final)
        for label, value in (("initial", initial), ("final", final)):
            if value is not None and ((lower is not None and value < lower) or (upper is not None and value > upper)):
                raise SpecError(f"{where}: {label} value {value:g} is outside its bounds "
                                f"[{lower if lower is not None else '-inf'}, {upper if upper is not None else 'inf'}]")
        magnitudes = [abs(v) for v in (lower, upper, initial, final) if v is not None]
        stated = number(f"{where}: scale", scale)
        scale = stated or max([*magnitudes, 0.0]) or 1.0
        if scale <= 0:
            raise SpecError(f"{where}: scale: must be positive (got {scale:g})")
        if not isinstance(unit, str):
            raise SpecError(f"{where}: unit: expected a string such as 'm/s' (got {unit!r})")
        return Variable(name, ca.SX.sym(name), lower, upper, initial, final, scale,
                        number(f"{where}: guess", guess), unit,
                        scale_from="stated" if stated is not None else "values" if any(m > 0 for m in magnitudes)
                        else "none")

    def state(self, name: str, bounds: tuple[float | None, float | None] | None = None, initial: float | None = None,
              final: float | None = None, scale: float | None = None, unit: str = "") -> ca.SX:
        """A scalar state in ``unit``; ``initial``/``final`` fix its boundary values (None: free). Returns its
        symbol."""
        variable = self._variable("state", name, bounds, initial, final, scale, None, unit)
        self.states.append(variable)
        return variable.symbol

    def parameter(self, name: str, bounds: tuple[float | None, float | None] | None = None,
                  guess: float | None = None, scale: float | None = None, unit: str = "") -> ca.SX:
        """A static decision parameter (a design choice the plan may set: a coast time's share, a thrust level, a
        boundary position), usable in the dynamics, constraints and a terminal cost. Carried as a state with zero
        rate, free at both ends (the dynamics defects keep it constant; its own bounds hold at every node), so
        every transcription and the dense check take it as they are; it costs one value per node. Returns its
        symbol; its planned value is in ``solution.figures.parameters``."""
        variable = self._variable("parameter", name, bounds, None, None, scale, guess, unit)
        self.states.append(variable)
        self.rates[name] = ca.SX(0)
        self.parameter_names.append(name)
        return variable.symbol

    def control(self, name: str, bounds: tuple[float | None, float | None] | None = None,
                scale: float | None = None, guess: float | None = None, unit: str = "",
                period: float | None = None) -> ca.SX:
        """A scalar control (between nodes as the transcription holds it), in ``unit``. Returns its symbol.

        ``period`` (an angle that enters only through periodic functions, e.g. ``2 * math.pi`` for a thrust
        direction) lets the control turn through any angle: the collocation sees its values only through those
        functions, so a plan may hold a node's value and its neighbour's a whole turn apart; before the plan is
        flown and tabulated, each value is shifted by whole periods to within half a period of the one before it
        in time, which changes no value the dynamics see. A periodic control has no bounds. An unbounded control
        stated without a period gets one of 2 pi when a whole turn of it changes nothing the dynamics and path
        constraints evaluate (:mod:`convexguid.ocp.periodic`)."""
        variable = self._variable("control", name, bounds, None, None, scale, guess, unit)
        if period is not None:
            period = number(f"{self.name}: control {name!r}: period", period, allow_none=False)
            if period <= 0 or bounds is not None:
                raise SpecError(f"{self.name}: control {name!r}: period: expected a positive period and no bounds "
                                f"(got period {period!r}, bounds {bounds!r})")
            variable = replace(variable, period=period)
        self.controls.append(variable)
        return variable.symbol

    def final_time(self, fixed: float | None = None, bounds: tuple[float, float] | None = None,
                   guess: float | None = None) -> None:
        """The final time (the initial time is 0): ``fixed``, or free within ``bounds`` starting from ``guess``; a
        later call replaces an earlier one."""
        where = f"{self.name}: final_time"
        if (fixed is None) == (bounds is None):
            raise SpecError(f"{where}: give either fixed=<seconds> or bounds=(lower, upper)")
        if fixed is not None:
            self.tf = number(f"{where}: fixed", fixed, allow_none=False)
            if self.tf <= 0:
                raise SpecError(f"{where}: fixed: must be positive (got {self.tf:g})")
            self.tf_bounds = None
            return
        low, high = number(f"{where}: bounds", bounds[0], allow_none=False), number(f"{where}: bounds", bounds[1])
        if not 0 < low < (math.inf if high is None else high):
            raise SpecError(f"{where}: bounds: expected 0 < lower < upper (got ({low:g}, {high})): the final time "
                            "scales the dynamics, so its lower bound is a positive duration (a small share of the "
                            "guess where the source says 0)")
        if high is None and guess is None:
            raise SpecError(f"{where}: guess: needed when the final time has no upper bound")
        self.tf, self.tf_bounds = None, (low, math.inf if high is None else high)
        self.tf_guess = number(f"{where}: guess", guess) or 0.5 * (low + high)

    def dynamics(self, rates: Mapping[ca.SX, ca.SX]) -> None:
        """``{state symbol: its rate}``, each rate an expression of states, controls and :attr:`time`."""
        by_symbol = {str(v.symbol): v.name for v in self.states}
        for symbol, rate in rates.items():
            name = by_symbol.get(str(symbol))
            if name in self.parameter_names:
                raise SpecError(f"{self.name}: dynamics: {name} is a parameter (constant); give rates of states only")
            if name is None:
                raise SpecError(f"{self.name}: dynamics: {symbol} is not a state of this problem "
                                f"(states: {', '.join(by_symbol.values()) or 'none'})")
            rate = ca.SX(rate)
            if rate.shape != (1, 1):
                raise SpecError(f"{self.name}: dynamics of {name}: expected a scalar expression (got shape "
                                f"{rate.shape})")
            self.rates[name] = rate

    def flow(self, transitions: Mapping[ca.SX, ca.SX]) -> None:
        """The dynamics' flow in closed form, ``{state symbol: its value after the time`` :attr:`time` ``}``, each an
        expression of the states (their values at the start), the controls (held constant) and :attr:`time` (the
        time elapsed), e.g. a Clohessy-Wiltshire coast by its state transition matrix or a Kepler arc. With
        ``transcription(method="flow")`` each interval's defect is the node state less this flow from the node
        before (exact: a long coast needs no more intervals than its constraints do); the dynamics stay stated as
        well, and the dense check integrates them, so a flow that is not theirs shows as a final-state error. The
        dynamics must not depend on the time (a flow from each node's own start). A parameter's flow is itself."""
        by_symbol = {str(v.symbol): v.name for v in self.states}
        for symbol, value in transitions.items():
            name = by_symbol.get(str(symbol))
            if name is None or name in self.parameter_names:
                raise SpecError(f"{self.name}: flow: {symbol} is not a state of this problem (states: "
                                f"{', '.join(n for n in by_symbol.values() if n not in self.parameter_names)})")
            value = ca.SX(value)
            if value.shape != (1, 1):
                raise SpecError(f"{self.name}: flow of {name}: expected a scalar expression (got shape {value.shape})")
            self.transitions[name] = value

    def path_constraint(self, name: str, expression: ca.SX, unit: str = "",
                        during: tuple[float, float] | None = None, at_nodes: bool = True,
                        scale: float | None = None) -> None:
        """``expression <= 0`` along the trajectory, or over the share ``during = (start, end)`` of it (0 to 1 of
        the final time); nonconvex allowed: the engine linearizes it. ``at_nodes=False`` imposes it between the
        nodes only (Hermite-Simpson's midpoints), for a bound the nodes already hold as a hard state bound.
        ``scale`` is the constraint's magnitude (default: the change of its value when every state and control
        moves by its own scale, the largest on the straight-line guess): its rows are judged, by the engine and by
        the dense check, in the stricter of their stated unit and that magnitude, at most ten times stricter than
        the magnitude (:func:`~convexguid.ocp.constraint_units.constraint_divisors`)."""
        where = f"{self.name}: path_constraint {name!r}"
        expression = self._scalar(where, name, expression)
        magnitude = positive_scale(where, scale)
        window = (0.0, 1.0) if during is None else tuple(number(f"{where}: during", v, allow_none=False)
                                                          for v in during)
        if len(window) != 2 or not 0.0 <= window[0] < window[1] <= 1.0:
            raise SpecError(f"{where}: during: expected (start, end) with 0 <= start < end <= 1, shares of the final "
                            f"time (got {during!r})")
        self.constraints.append(PathConstraint(name, expression, unit, window, at_nodes=bool(at_nodes),
                                               scale=magnitude))

    def path_equality(self, name: str, expression: ca.SX, unit: str = "",
                      during: tuple[float, float] | None = None, at_midpoints: bool | None = None,
                      scale: float | None = None) -> None:
        """``expression == 0`` along the trajectory (or the share ``during`` of it), e.g. a thrust of fixed
        magnitude; nonconvex allowed (the engine linearizes it). The dense check judges ``|expression|`` between
        the nodes in its magnitude (its largest change on the flown track when every state and control moves by
        its own scale); where it breaks there the repair refines the grid (an equality cannot be tightened). An
        equality of the states alone (a singular arc's condition) holds at the nodes: at Hermite-Simpson's
        midpoints too it would fix more values than the collocation leaves free. ``at_midpoints`` says it
        otherwise (False: at the nodes only, e.g. a unit thrust direction whose midpoint value is the mean of its
        node values, as Wang & Tang's arcs hold it). Its rows are divided as an inequality's are (``scale``:
        :meth:`path_constraint`)."""
        self.path_constraint(name, expression, unit, during, scale=scale)
        if at_midpoints is None:
            at_midpoints = ca.depends_on(self.constraints[-1].expression, self.control_vector())
        self.constraints[-1] = replace(self.constraints[-1], equality=True, at_midpoints=bool(at_midpoints))

    def cone_constraint(self, name: str, vector, bound, unit: str = "",
                        during: tuple[float, float] | None = None) -> None:
        """``||vector|| <= bound``, a second-order cone on expressions affine in the states and controls (a thrust
        magnitude, an approach or glide-slope cone): kept exact in every convex subproblem, at every node (over
        the share ``during`` of the maneuver); the dense check judges it between the nodes."""
        where = f"{self.name}: cone_constraint {name!r}"
        entries = [ca.SX(e) for e in (vector if isinstance(vector, (list, tuple)) else [vector])]
        bound = ca.SX(bound)
        if not entries or any(e.shape != (1, 1) for e in entries) or bound.shape != (1, 1):
            raise SpecError(f"{where}: expected a list of scalar expressions and a scalar bound")
        variables = ca.vertcat(self.state_vector(), self.control_vector(), self.time)
        for label, e in [*((f"vector entry {i + 1}", e) for i, e in enumerate(entries)), ("bound", bound)]:
            if ca.depends_on(ca.jacobian(e, variables), variables):
                raise SpecError(f"{where}: {label} ({e}) is not affine in the states and controls, so the cone is "
                                "not convex as stated; state it with path_constraint (the engine linearizes it)")
            if ca.depends_on(e, self.time):
                raise SpecError(f"{where}: {label} ({e}) depends on the time; a cone is stated on states and "
                                "controls only")
        vector = ca.vertcat(*entries)
        self.path_constraint(name, ca.norm_2(vector) - bound, unit, during)
        self.constraints[-1] = replace(self.constraints[-1], cone=(bound, vector))

    def boundary_constraint(self, name: str, expression, at: str = "final") -> None:
        """``expression == 0`` on the initial or final state (``at``) and, at the final one, the final time
        (:attr:`time`). Affine in the states (and not using the time): hard linear rows in every subproblem, e.g.
        a final attitude as the vector part of the quaternion error (three rows: fixing all four components would
        also fix the norm, which the dynamics carry). Otherwise a nonlinear equality the engine linearizes like
        the dynamics, e.g. a circular final orbit :math:`v - \\sqrt{\\mu / r} = 0`; the dense check judges it on the
        re-propagated state."""
        where = f"{self.name}: boundary_constraint {name!r}"
        if at not in ("initial", "final"):
            raise SpecError(f"{where}: at: expected 'initial' or 'final' (got {at!r})")
        expression = column(where, expression)
        if expression.shape[1] != 1:
            raise SpecError(f"{where}: expected a column of expressions (got shape {expression.shape})")
        if ca.depends_on(expression, self.control_vector()):
            raise SpecError(f"{where}: {expression} uses a control; state it on the states (and the final time), or "
                            f"as point_equality(name, expression, at={0.0 if at == 'initial' else 1.0})")
        if at == "initial" and ca.depends_on(expression, self.time):
            raise SpecError(f"{where}: {expression} uses the time at the initial instant, which is 0; leave it out")
        if name in {b[0] for b in self.boundary_constraints}:
            raise SpecError(f"{where}: the name is already taken")
        self.boundary_constraints.append((name, expression, at))

    def boundary_is_affine(self, expression: ca.SX) -> bool:
        """Whether a boundary constraint is affine in the states and free of the time (then hard linear rows)."""
        states = self.state_vector()
        return not ca.depends_on(expression, self.time) and not ca.depends_on(ca.jacobian(expression, states), states)

    def start(self, state: ca.SX) -> ca.SX:
        """A symbol for the value of ``state`` at the start of this problem, for a link between phases
        (:meth:`~convexguid.ocp.phases.Phases.link`)."""
        return self._end_reference("start", state)

    def end(self, state: ca.SX) -> ca.SX:
        """A symbol for the value of ``state`` (or of :attr:`time`: the duration) at the end of this problem, for
        a link between phases (:meth:`~convexguid.ocp.phases.Phases.link`)."""
        return self._end_reference("end", state)

    @property
    def duration(self) -> ca.SX:
        """A symbol for this problem's duration (its final time), for a link between phases."""
        return self.end(self.time)

    def _end_reference(self, which: str, symbol: ca.SX) -> ca.SX:
        names = [str(v.symbol) for v in self.states]
        if str(symbol) == str(self.time) and which == "end":
            index, label = -1, "duration"
        elif str(symbol) in names:
            index, label = names.index(str(symbol)), str(symbol)
        else:
            raise SpecError(f"{self.name}: {which}({symbol}): expected a state of this problem"
                            f"{' or its time' if which == 'end' else ''} (states: {', '.join(names) or 'none'})")
        name = f"{self.name}.{label}.{which}"
        self.ends[name] = (which, index)
        return ca.SX.sym(name)

    def initial_guess(self, states, controls) -> None:
        """Start the SCP from these node values (arrays of ``intervals + 1`` rows, a column per state and per
        control, in their order of declaration) instead of the straight line."""
        states, controls = np.asarray(states, dtype=float), np.asarray(controls, dtype=float)
        shapes = ((len(self.states),), (len(self.controls),))
        if states.ndim != 2 or controls.ndim != 2 or (states.shape[1],) != shapes[0] or \
                (controls.shape[1],) != shapes[1] or states.shape[0] != controls.shape[0]:
            raise SpecError(f"{self.name}: initial_guess: expected arrays of (nodes, {shapes[0][0]}) states and "
                            f"(nodes, {shapes[1][0]}) controls (got {states.shape} and {controls.shape})")
        self.guess_nodes = (states, controls)

    def point_constraint(self, name: str, expression: ca.SX, at: float, unit: str = "",
                         scale: float | None = None) -> None:
        """``expression <= 0`` at the instant ``at`` (a share of the final time, on a node of the grid); ``scale``
        as for :meth:`path_constraint`."""
        self._point(name, expression, at, unit, equality=False, scale=scale)

    def point_equality(self, name: str, expression: ca.SX, at: float, unit: str = "",
                       scale: float | None = None) -> None:
        """``expression == 0`` at the instant ``at`` (a share of the final time, on a node of the grid), e.g. a
        control that must be zero as the maneuver ends (``at=1.0``). Linearized like the dynamics and never
        tightened by a repair; for the states alone at either end, :meth:`boundary_constraint` says it. ``scale``
        as for :meth:`path_constraint`."""
        self._point(name, expression, at, unit, equality=True, scale=scale)

    def _point(self, name: str, expression: ca.SX, at: float, unit: str, equality: bool,
               scale: float | None) -> None:
        where = f"{self.name}: {point_kind(equality)} {name!r}"
        expression = self._scalar(where, name, expression)
        share = number(f"{where}: at", at, allow_none=False)
        if not 0.0 <= share <= 1.0:
            raise SpecError(f"{where}: at: expected a share of the final time in [0, 1] (got {at!r})")
        self.constraints.append(PathConstraint(name, expression, unit, at=share, equality=equality,
                                               at_midpoints=not equality, scale=positive_scale(where, scale)))

    def _scalar(self, where: str, name: str, expression) -> ca.SX:
        expression = ca.SX(expression)
        if expression.shape != (1, 1):
            raise SpecError(f"{where}: expected a scalar expression (got shape {expression.shape}); state one "
                            "constraint per call")
        if name in {c.name for c in self.constraints}:
            raise SpecError(f"{where}: the name is already taken")
        return expression

    def minimize_time(self) -> None:
        self.objective = "time"

    def minimize_energy(self) -> None:
        """Minimise the integral of the sum of the squared controls (a fixed final time)."""
        self.objective = "energy"

    def minimize_fuel(self, norm: int = 1) -> None:
        """Minimise the integral of the control's 1-norm (``norm=1``: one thruster pair per axis) or 2-norm
        (``norm=2``: one gimballed engine, the thrust magnitude, a second-order cone per control value); the
        final time may be fixed or free."""
        if norm not in (1, 2):
            raise SpecError(f"{self.name}: minimize_fuel: norm: expected 1 or 2 (got {norm!r})")
        self.objective, self.fuel_norm = "fuel", norm

    def minimize_terminal(self, expression) -> None:
        """Minimise a function of the final state (and of :attr:`time`, the final time), e.g. ``-mass`` for the
        most mass left: a linear cost when it is affine, else an epigraph the engine linearizes."""
        expression = ca.SX(expression)
        if expression.shape != (1, 1):
            raise SpecError(f"{self.name}: minimize_terminal: expected a scalar expression (got shape "
                            f"{expression.shape})")
        self.objective, self.terminal = "terminal", expression

    def minimize_integral(self, integrand, terminal=0.0, name: str = "cost", scale: float | None = None) -> ca.SX:
        """Minimise the integral over the maneuver of ``integrand`` (of states, controls and :attr:`time`: a Lagrange
        cost), plus ``terminal``, a function of the final state and time as in :meth:`minimize_terminal` (a Bolza
        cost). The integral is carried as a state ``name`` that starts at 0 with the integrand as its rate, so every
        transcription integrates it as it integrates the dynamics, the dense check re-propagates it with them, and
        the tables show it accumulate; ``scale`` is that state's (default: estimated from the integrand, as any
        state's). Returns its symbol."""
        where = f"{self.name}: minimize_integral"
        integrand = ca.SX(integrand)
        if integrand.shape != (1, 1):
            raise SpecError(f"{where}: integrand: expected a scalar expression (got shape {integrand.shape})")
        cost = self.state(name, initial=0.0, scale=scale)
        self.rates[name] = integrand
        self.minimize_terminal(cost + terminal)
        return cost

    def transcription(self, intervals: int, method: str = "hermite-simpson", substeps: int = 4,
                      control: str = "quadratic", mesh_tolerance: float | None = None) -> None:
        """``intervals`` equal intervals, transcribed by ``method``: ``"hermite-simpson"`` (collocation, the control
        quadratic between nodes through a midpoint value, or with ``control="linear"`` linear between the node
        values), ``"zoh"`` (the control constant on each interval), ``"foh"`` (linear between nodes) or
        ``"chebyshev"`` (pseudospectral collocation on ``intervals + 1`` mapped Chebyshev nodes); the holds
        integrate the dynamics across each interval by ``substeps`` Runge-Kutta steps; ``"flow"`` holds the control
        constant on each interval as ``"zoh"`` does but maps each node to the next by the closed-form flow
        (:meth:`flow`).

        ``mesh_tolerance`` asks for accuracy beyond the dense check's: the plan is verified only when every
        interval's local error (the state flown across it from its start node, less its end node, in the states'
        scales) is within it, and the grid is refined where it is not (Betts 2010, Sec. 4.7). Without it the grid
        is refined only where the plan fails the check. The optimum of a coarse grid can be feasible as flown and
        still short of the continuous one: Rao and Mease's hypersensitive problem (tf = 10) costs 6.740452 on 50
        intervals, 0.25% above the published 6.7239254; with ``mesh_tolerance=1e-5``, 6.724332 on 56."""
        where = f"{self.name}: transcription"
        fewest = 1 if method == "flow" else 2  # a closed-form flow is exact across one interval
        if isinstance(intervals, bool) or not isinstance(intervals, int) or intervals < fewest:
            raise SpecError(f"{where}: intervals: expected an integer >= {fewest} (got {intervals!r})")
        if method not in TRANSCRIPTION_METHODS:
            raise SpecError(f"{where}: method: expected one of {', '.join(TRANSCRIPTION_METHODS)} (got {method!r})")
        if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
            raise SpecError(f"{where}: substeps: expected an integer >= 1 (got {substeps!r})")
        if control not in ("quadratic", "linear") or (control == "linear" and method != "hermite-simpson"):
            raise SpecError(f"{where}: control: expected 'quadratic' or 'linear' with hermite-simpson (got "
                            f"{control!r} with {method})")
        if mesh_tolerance is not None:
            mesh_tolerance = number(f"{where}: mesh_tolerance", mesh_tolerance)
            if not mesh_tolerance > 0:
                raise SpecError(f"{where}: mesh_tolerance: expected a positive number (got {mesh_tolerance!r})")
        self.intervals, self.method, self.substeps, self.control_interpolation = intervals, method, substeps, control
        self.mesh_tolerance = mesh_tolerance

    # --- checks and solve -------------------------------------------------------------------------------------
    def check(self) -> None:
        """Refuse a statement that cannot be solved (one line naming what is wrong), before any solve."""
        if not self.states:
            raise SpecError(f"{self.name}: no states; declare them with problem.state(...)")
        missing = [v.name for v in self.states if v.name not in self.rates]
        if missing:
            raise SpecError(f"{self.name}: dynamics: no rate given for state(s) {', '.join(missing)}")
        if self.tf is None and self.tf_bounds is None:
            raise SpecError(f"{self.name}: final_time: not stated; call problem.final_time(fixed=...) or "
                            "problem.final_time(bounds=(lower, upper))")
        if self.method == "flow":
            missing = [v.name for v in self.states if v.name not in self.transitions
                       and v.name not in self.parameter_names]
            if missing:
                raise SpecError(f"{self.name}: transcription: method 'flow' needs the flow of every state; none given "
                                f"for {', '.join(missing)} (problem.flow({{state: value after time}}))")
            if any(ca.depends_on(rate, self.time) for rate in self.rates.values()):
                raise SpecError(f"{self.name}: transcription: method 'flow' needs dynamics that do not depend on the "
                                "time (the flow starts afresh at every node)")
        if self.objective is None and self.phase_of is None:
            raise SpecError(f"{self.name}: objective: not stated; call problem.minimize_time(), "
                            "problem.minimize_energy(), problem.minimize_fuel(), problem.minimize_terminal(...) or "
                            "problem.minimize_integral(...)")
        if self.objective == "time" and self.tf_bounds is None:
            raise SpecError(f"{self.name}: minimize_time: the final time is fixed; give final_time(bounds=...)")
        if self.objective == "energy" and self.tf is None:
            raise SpecError(f"{self.name}: minimize_energy: needs a fixed final time (final_time(fixed=...))")
        if self.objective in ("energy", "fuel") and not self.controls:
            raise SpecError(f"{self.name}: minimize_{self.objective}: the problem has no controls")
        for c in self.constraints:
            # (the mapped Chebyshev grid's nodes are not equally spaced: its program checks them)
            if c.at is not None and self.method != "chebyshev" and \
                    abs(c.at * self.intervals - round(c.at * self.intervals)) > 1e-9:
                raise SpecError(f"{self.name}: {point_kind(c.equality)} {c.name!r}: at = {c.at:g} of the final time "
                                f"is not a node of the {self.intervals}-interval grid; choose intervals so that at x "
                                "intervals is a whole number")
        known = {str(v.symbol) for v in (*self.states, *self.controls)} | {str(self.time)}
        terminal = [("minimize_terminal", self.terminal)] if self.terminal is not None else []
        if self.terminal is not None and ca.depends_on(self.terminal, self.control_vector()):
            raise SpecError(f"{self.name}: minimize_terminal: {self.terminal} uses a control; a terminal cost is a "
                            "function of the final state and time")
        for label, expression in [*((f"dynamics of {k}", e) for k, e in self.rates.items()),
                                  *((f"path_constraint {c.name!r}", c.expression) for c in self.constraints),
                                  *((f"boundary_constraint {b[0]!r}", b[1]) for b in self.boundary_constraints),
                                  *terminal]:
            unknown = sorted({str(s) for s in ca.symvar(expression)} - known)
            if unknown:
                raise SpecError(f"{self.name}: {label}: uses {', '.join(unknown)}, which is not a state or control "
                                "of this problem")
        check_problem_size(self)

    def straight_line(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The straight-line guess: each state's first and last value (its initial and final ones, the other given
        one where only one is, else its guess, else 0 or its bound nearest to 0) and each control's value (its
        guess, else the middle of finite bounds, else 0)."""
        start = np.array([v.initial if v.initial is not None else v.final if v.final is not None else
                          v.guess if v.guess is not None else v.fallback_guess() for v in self.states])
        end = np.array([v.final if v.final is not None else start[i] for i, v in enumerate(self.states)])
        control = np.array([v.guess if v.guess is not None else 0.5 * (v.lower + v.upper)
                            if v.lower is not None and v.upper is not None else 0.0 for v in self.controls])
        return start, end, control

    def state_scales(self) -> np.ndarray:
        """Each state's magnitude: its scale, or what its rate can do over the horizon when nothing stated gives its
        size (:func:`~convexguid.ocp.scaling.estimated_scales`). The defects and the final-state check use it too."""
        return estimated_scales(self)

    @property
    def free_time(self) -> bool:
        return self.tf_bounds is not None

    def solve(self, max_iterations: int = 300, verification_points: int = 20, log=None, backend: str = "auto"):
        """Transcribe, plan by SCP, check densely with SciPy: a :class:`~convexguid.solution.Solution` (``log``: a
        function given each SCP iteration's record; ``backend``: what solves the convex subproblems, a name
        :func:`convexguid.backends.available_backends` lists, or ``auto``)."""
        from convexguid.ocp.solve import solve_problem  # the SCP engine and SciPy load at the first solve

        return solve_problem(self, max_iterations, verification_points, log, backend)

    def state_vector(self) -> ca.SX:
        return ca.vertcat(*(v.symbol for v in self.states))

    def control_vector(self) -> ca.SX:
        return ca.vertcat(*(v.symbol for v in self.controls)) if self.controls else ca.SX(0, 1)

    def rate_vector(self) -> ca.SX:
        return ca.vertcat(*(self.rates[v.name] for v in self.states))

    def bounds_array(self, variables: list[Variable]) -> tuple[np.ndarray, np.ndarray]:
        low = np.array([-np.inf if v.lower is None else v.lower for v in variables])
        high = np.array([np.inf if v.upper is None else v.upper for v in variables])
        return low, high
