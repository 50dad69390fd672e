"""What every transcription of a :class:`~convexguid.ocp.problem.Problem` shares: the layout of the decision vector,
bounds and boundary values, the objectives, the repair margins, and the engine's
:class:`~convexguid.scp.problem.NonconvexProgram` interface.

Decision vector ``z = [x_0 .. x_N, v_1 .. v_C, (s), (J), (t_f)]``: the states at the :math:`N + 1` nodes, the
transcription's control values (Hermite-Simpson: nodes then interval midpoints; zero-order hold: one per interval;
first-order hold: one per node), for minimum fuel the slacks :math:`s \\ge |v|` of every control value's entries
(1-norm) or :math:`s \\ge \\|v\\|` of every control value (2-norm, a second-order cone), the objective's epigraph
variable :math:`J` when the objective is not linear in ``z`` (fuel with a free final time, a nonlinear terminal
cost), and the final time when it is free. A subclass says how
the control values make the control between nodes and writes the dynamics defects of each interval
(:mod:`convexguid.ocp.hermite_simpson`, :mod:`convexguid.ocp.hold`).

Boundary values and bounds are the hard linear constraints :math:`Az = b`, :math:`Gz \\le h`; path constraints hold
where the transcription imposes them and cone constraints at the nodes (kept exact: second-order cones on affine
maps of ``z``), each less the margin a dense-check repair may have added there (:class:`Margins`). With the mean
step :math:`h = t_f/N` and the transcription's quadrature weights :math:`w_j` per mean step (an uneven grid's in its
intervals' lengths, :mod:`convexguid.ocp.hermite_simpson`), minimum time is the linear
cost :math:`t_f`, minimum energy :math:`h \\sum_j w_j v_j^2` (weighted residuals :math:`r = v`), minimum fuel
:math:`h \\sum_j w_j s_j` with :math:`-s \\le v \\le s` linear: a linear cost when the final time is fixed, else
:math:`\\min J` subject to :math:`h \\sum_j w_j s_j - J \\le 0` (an epigraph the engine linearizes like any
constraint); a terminal cost :math:`\\phi(x_N, t_f)` is a linear cost when affine, else :math:`\\min J` subject to
:math:`\\phi - J \\le 0`. Jacobians and the Lagrangian Hessian are CasADi's exact sparse derivatives.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.ocp import linear_rows, periodic
from convexguid.ocp.boundary import nonlinear_equalities
from convexguid.ocp.constraint_units import constraint_divisors
from convexguid.ocp.curvature import ElementCurvature, interval_of_rows
from convexguid.ocp.element_hessian import ElementHessian, element_hessian
from convexguid.ocp.guess import flown_free_states
from convexguid.ocp.parts import DERIVATIVES, AffineCones, Margins, SparsityPattern, SymbolicNLP
from convexguid.ocp.scaling import following_plan
from convexguid.ocp.terminal import terminal_cost_is_linear, terminal_gradient, terminal_scale
from convexguid.scp.problem import ConstraintBlock, CurvatureModel, Evaluation, LinearConstraints, OutputConstraints

if TYPE_CHECKING:  # the problem module imports this one when it solves
    from convexguid.ocp.problem import Problem


@dataclass(frozen=True)
class Symbols:
    """The decision vector and its parts as CasADi symbols, handed to a subclass writing its intervals."""

    z: ca.SX
    X: ca.SX
    """States, ``nx x (N + 1)``."""
    V: ca.SX
    """Control values, ``nu x C``."""
    tf: ca.SX
    h: ca.SX
    """The mean step ``t_f / N`` (every interval's on equal intervals)."""


class Transcription:
    """The transcribed problem as a :class:`~convexguid.scp.problem.NonconvexProgram` (a subclass supplies the
    control values' meaning and the interval defects)."""

    method = ""
    """The name :meth:`~convexguid.ocp.problem.Problem.transcription` knows it by."""
    INTERPOLATION_SAMPLES: tuple[float, ...] = ()
    """Shares of each interval where a bounded control's interpolant is held within its bounds (none where the
    interpolant never leaves the box its values are in)."""

    def __init__(self, problem: Problem, margins: Margins | None = None, intervals: int | None = None) -> None:
        problem.check()
        self.problem = problem
        self.state_scales = problem.state_scales()
        self.N = intervals if intervals is not None else problem.intervals
        self.nx, self.nu = len(problem.states), len(problem.controls)
        self.free_time = problem.free_time
        self.fuel = problem.objective == "fuel"
        self.fuel_norm = problem.fuel_norm if self.fuel else 0
        self.control_start = (self.N + 1) * self.nx
        self.num_control_values = self.control_values_per_axis() * self.nu
        self.slack_start = self.control_start + self.num_control_values
        self.slacks_per_value = self.nu if self.fuel_norm == 1 else 1
        self.num_slacks = self.control_values_per_axis() * self.slacks_per_value if self.fuel else 0
        self.epigraph = (self.fuel and self.free_time) or (problem.objective == "terminal"
                                                          and not terminal_cost_is_linear(problem))
        self.num_variables = self.slack_start + self.num_slacks + int(self.epigraph) + int(self.free_time)
        self._build()
        self.margins = margins if margins is not None else Margins.none(self.num_path, (self.N + 1) * self.nx,
                                                                        len(self.cone_rows))

    # --- what a subclass says ---------------------------------------------------------------------------------
    def control_values_per_axis(self) -> int:
        raise NotImplementedError

    def per_step_weights(self) -> np.ndarray:
        """Quadrature weights per mean step ``t_f / N`` of each control value (per axis, in the order of ``z``)."""
        raise NotImplementedError

    def intervals(self, s: Symbols, imposed) -> list[ca.SX]:
        """Each interval's scaled dynamics defects; path constraints through ``imposed(kind, k, share, x, u, t)``."""
        raise NotImplementedError

    def control_function(self, z: np.ndarray):
        """The planned control as a function of time (as the transcription holds it between nodes)."""
        raise NotImplementedError

    def node_controls(self, z: np.ndarray) -> np.ndarray:
        """The control at each node, shape ``(N + 1, nu)`` (what the node table shows)."""
        raise NotImplementedError

    def refined(self, z: np.ndarray) -> tuple[Transcription, np.ndarray]:
        """The same problem on a finer grid (twice the intervals unless a subclass splits fewer), and ``z`` carried
        onto it (margins start afresh)."""
        raise NotImplementedError

    def values_from_nodes(self, controls: np.ndarray) -> np.ndarray:
        """The control values, shape ``(C, nu)``, of a control given at the nodes (``(N + 1, nu)``)."""
        raise NotImplementedError

    def interval_control_columns(self, k: int, j: int) -> tuple[int, ...]:
        """Columns of control ``j``'s values that shape interval ``k`` (for the interpolated bounds)."""
        raise NotImplementedError

    def interval_weights(self, share: float) -> tuple[float, ...]:
        """Weights of :meth:`interval_control_columns` giving the control at ``share`` of the interval."""
        raise NotImplementedError

    def control_value_shares(self) -> np.ndarray:
        """The instant (a share of the final time) each control value stands for, in the order of ``z``."""
        raise NotImplementedError

    @cached_property
    def _turning_controls(self) -> list[int]:
        """The controls a turn changes nothing of, tried once (:func:`~convexguid.ocp.periodic.turning_controls`)."""
        return periodic.turning_controls(self.problem)

    @cached_property
    def control_periods(self) -> tuple[float | None, ...]:
        """Each control's period, stated or recognized (:func:`~convexguid.ocp.periodic.control_periods`)."""
        return periodic.control_periods(self.problem, self._turning_controls)

    @cached_property
    def control_scales(self) -> np.ndarray:
        """Each control's scale (:func:`~convexguid.ocp.periodic.control_scales`)."""
        return periodic.control_scales(self.problem, self._turning_controls)

    def unwrapped(self, z: np.ndarray) -> np.ndarray:
        """``z`` with every periodic control's values (stated or recognized: :mod:`convexguid.ocp.periodic`) shifted
        by whole periods to within half a period of the value before them in time; the same point of the program."""
        periodic = [(j, period) for j, period in enumerate(self.control_periods) if period is not None]
        if not periodic:
            return z
        z = np.array(z, dtype=float)
        values = self.control_values(z).copy()
        order = np.argsort(self.control_value_shares(), kind="stable")
        for j, period in periodic:
            ordered = values[order, j]
            steps = np.round(np.diff(ordered) / period)
            ordered[1:] -= period * np.cumsum(steps)
            values[order, j] = ordered
        z[self.control_start: self.slack_start] = values.ravel()
        return z

    def node_shares(self) -> np.ndarray:
        """Each node's time as a share of the final time (equal intervals unless a subclass says otherwise)."""
        return np.linspace(0.0, 1.0, self.N + 1)

    # --- layout ---------------------------------------------------------------------------------------------
    def restated(self, problem: Problem) -> Transcription:
        """Another statement of the problem (a constraint added, the controls held otherwise) on this grid, margins
        afresh."""
        return type(self)(problem, intervals=self.N)

    rescaled = following_plan  # (z): restated with its estimated scales grown to the plan's sizes, or None
    scales_followed = ""  # a restated program's list of the scales that grew ("v 0.1 -> 13.6")

    def with_margins(self, margins: Margins) -> Transcription:
        """The same program with other repair margins. Margins enter only as numbers (added to the path values, the
        cones and the state bounds at evaluation), so the symbolic build, its derivatives and the Hessian are
        shared, not built again (measured: 0.46 s a build on the multi-cone slew's transcription)."""
        program = copy.copy(self)
        program.margins = margins
        return program

    def states(self, z: np.ndarray) -> np.ndarray:
        """Node states, shape ``(N + 1, nx)``."""
        return np.asarray(z[: self.control_start]).reshape(self.N + 1, self.nx)

    def control_values(self, z: np.ndarray) -> np.ndarray:
        """The control values, shape ``(C, nu)``."""
        return np.asarray(z[self.control_start: self.slack_start]).reshape(self.control_values_per_axis(), self.nu)

    def final_time(self, z: np.ndarray) -> float:
        return float(z[-1]) if self.free_time else float(self.problem.tf)

    def final_values(self, z: np.ndarray) -> dict[str, float]:
        """The last node's states by name."""
        return {v.name: float(value) for v, value in zip(self.problem.states, self.states(z)[-1], strict=True)}

    def assemble(self, states: np.ndarray, values: np.ndarray, tf: float) -> np.ndarray:
        """``z`` from node states ``(N + 1, nx)``, control values ``(C, nu)`` and the final time (fuel slacks at the
        values' magnitudes, the epigraph at their integral)."""
        parts = [np.ravel(states), np.ravel(values)]
        if self.fuel:
            slacks = np.abs(np.ravel(values)) if self.fuel_norm == 1 else np.linalg.norm(values, axis=1)
            parts.append(slacks)
            if self.epigraph:
                parts.append([tf / self.N * float(self._slack_weights @ slacks)])
        elif self.epigraph:  # a nonlinear terminal cost: J at its value
            parts.append([float(self._terminal_value(states[-1], tf))])
        if self.free_time:
            parts.append([tf])
        return np.concatenate(parts)

    # --- symbolic maps --------------------------------------------------------------------------------------
    def _build(self) -> None:
        p, N, nx, nu = self.problem, self.N, self.nx, self.nu
        z = ca.SX.sym("z", self.num_variables)
        X = ca.reshape(z[: self.control_start], nx, N + 1)
        V = ca.reshape(z[self.control_start: self.slack_start], nu, self.control_values_per_axis())
        tf = z[-1] if self.free_time else p.tf
        x, u, t = p.state_vector(), p.control_vector(), p.time
        # the dynamics f(x, u, t) and every path constraint's value (None without any), built once: the
        # transcription, the grid refinement and the dense check all evaluate these
        self.rate = ca.Function("rate", [x, u, t], [p.rate_vector()])
        self.constraint_values = (ca.Function("g", [x, u, t], [ca.vertcat(*(c.expression for c in p.constraints))])
                                  if p.constraints else None)
        # each path equality's magnitude: the change of its value when every state and control moves by its scale
        equalities = [c.expression for c in p.constraints if c.equality]
        scales = np.concatenate([self.state_scales, self.control_scales])
        self.equality_magnitudes = (ca.Function("reach", [x, u, t], [ca.mtimes(ca.fabs(ca.jacobian(
            ca.vertcat(*equalities), ca.vertcat(x, u))), ca.DM(scales))]) if equalities else None)
        self.state_scale = ca.DM(self.state_scales)
        # what each path constraint's rows are divided by (the dense check judges its excess in the same unit)
        self.path_divisors = constraint_divisors(p, x, u, t, scales, p.tf_guess if self.free_time else p.tf)
        g = [ca.Function(f"g_{j}", [x, u, t], [c.expression]) for j, c in enumerate(p.constraints)]
        self.path_rows: list[tuple[str, int, int]] = []  # (node or mid, index, constraint) of each path row
        self.cone_rows: list[tuple[str, int, int]] = []  # the same for each stated cone where it holds
        self.equality_rows: list[tuple[str, int, int]] = []  # and for each path equality
        constraints, cones, equalities = [], [], []
        cone_maps = {j: ca.Function(f"cone_{j}", [x, u], [ca.vertcat(*c.cone)]) for j, c in enumerate(p.constraints)
                     if c.cone is not None}
        # a cone or an inequality on the controls alone is known exactly wherever the controls are interpolated: held
        # there too when the interpolant is curved (a quadratic through two values inside a cone or an annulus may
        # leave it between them: a Mars descent's throttle limits, 4.5% under between nodes after eight repairs)
        control_cones = {j for j, c in enumerate(p.constraints) if c.cone is not None and self.INTERPOLATION_SAMPLES
                         and not ca.depends_on(ca.vertcat(*c.cone), x)}
        control_rows = {j for j, c in enumerate(p.constraints) if c.cone is None and not c.equality
                        and self.INTERPOLATION_SAMPLES and not ca.depends_on(c.expression, x)}

        def imposed(kind: str, k: int, share: float, state, control, time) -> None:
            for j, c in enumerate(p.constraints):
                if not c.applies(share, kind == "node"):
                    continue
                if c.equality:
                    self.equality_rows.append((kind, k, j))
                    equalities.append(g[j](state, control, time) / self.path_divisors[j])
                elif c.cone is None:
                    self.path_rows.append((kind, k, j))
                    constraints.append(g[j](state, control, time) / self.path_divisors[j])
                elif kind == "node" or j in control_cones:  # affine in a node's values (a midpoint state is not)
                    self.cone_rows.append((kind, k, j))
                    cones.append(cone_maps[j](state, control))

        pieces = self.intervals(Symbols(z, X, V, tf, tf / N), imposed)  # one per interval (per node: pseudospectral)
        defect = ca.vertcat(*pieces)
        across = "at node" if len(pieces) == N + 1 else "across interval"
        self.defect_labels = tuple(f"{v.name} {across} {k}" for k in range(len(pieces)) for v in p.states)
        shares = self.node_shares()
        for k in range(N):
            applying = [j for j in sorted(control_cones | control_rows)
                        if p.constraints[j].applies(float(shares[k]), False)]
            for share in self.INTERPOLATION_SAMPLES if applying else ():
                sampled = ca.vertcat(*(sum(weight * z[column] for column, weight in zip(
                    self.interval_control_columns(k, i), self.interval_weights(share), strict=True))
                    for i in range(self.nu)))
                time = tf * float(shares[k] + share * (shares[k + 1] - shares[k]))
                for j in applying:
                    if j in control_rows:
                        self.path_rows.append(("sample", k, j))
                        constraints.append(g[j](ca.SX.zeros(self.nx), sampled, time) / self.path_divisors[j])
                    else:
                        self.cone_rows.append(("sample", k, j))
                        cones.append(cone_maps[j](ca.SX.zeros(self.nx), sampled))
        where = {"node": "at node", "mid": "at the midpoint of interval"}
        self.path_labels = tuple(f"{p.constraints[j].name} {where.get(kind, 'between the nodes of interval')} {k}"
                                 for kind, k, j in self.path_rows)
        path = ca.vertcat(*constraints) if constraints else ca.SX(0, 1)
        path_equalities = ca.vertcat(*equalities) if equalities else ca.SX(0, 1)
        boundary, self.boundary_equality_rows = nonlinear_equalities(self, X, tf)
        self.num_path = path.shape[0]
        self._build_cones(z, V, cones)
        objective = self._epigraph(z, X[:, N], tf) if self.epigraph else ca.SX(0, 1)
        self._symbols = (z, ca.vertcat(defect, path_equalities, boundary), path, objective)
        # each block's value and exact sparse Jacobian, one CasADi function each (a Jacobian built once: building
        # them is most of the transcription's time)
        blocks = {"defects": defect, "path": path, "path_equalities": path_equalities, "boundary": boundary,
                  "epigraph": objective}

        def differentiated() -> tuple[dict, dict, bool]:
            jacobians = {name: ca.jacobian(e, z) for name, e in blocks.items()}
            return ({name: ca.Function(name, [z], [blocks[name], jacobians[name]]) for name in blocks},
                    {name: SparsityPattern(jacobian.sparsity()) for name, jacobian in jacobians.items()},
                    # every map affine (linear dynamics, no nonlinear constraint): one convex program is the problem
                    not any(ca.depends_on(jacobian, z) for jacobian in jacobians.values()))

        functions, patterns, self.affine = DERIVATIVES.get("blocks", [z], list(blocks.values()), differentiated)
        self._defects, self._defect_pattern = functions["defects"], patterns["defects"]
        self._path, self._path_pattern = functions["path"], patterns["path"]
        self._path_equalities, self._path_equality_pattern = functions["path_equalities"], patterns["path_equalities"]
        self._boundary_equalities, self._boundary_pattern = functions["boundary"], patterns["boundary"]
        self._objective_epigraph, self._epigraph_pattern = functions["epigraph"], patterns["epigraph"]

    def _build_cones(self, z: ca.SX, V: ca.SX, stated: list) -> None:
        """The stated cones at their nodes, then (2-norm fuel) ``||v_j|| <= s_j`` for every control value, as one
        affine map (:class:`~convexguid.ocp.parts.AffineCones`, each cone in its own magnitude)."""
        parts = list(stated)
        if self.fuel_norm == 2:
            slacks = z[self.slack_start: self.slack_start + self.num_slacks]
            parts += [ca.vertcat(slacks[j], V[:, j]) for j in range(self.num_slacks)]
        self._cones = AffineCones.of(z, parts, len(stated), self.variable_scale()) if parts else None

    def _epigraph(self, z: ca.SX, final_state: ca.SX, tf) -> ca.SX:
        """The objective less its epigraph variable ``J`` (``<= 0``): the fuel with a free final time, or a
        nonlinear terminal cost."""
        J = z[self.slack_start + self.num_slacks]
        if self.fuel:
            slacks = z[self.slack_start: self.slack_start + self.num_slacks]
            return tf / self.N * ca.dot(ca.DM(self._slack_weights), slacks) - J
        return self._terminal_function(final_state, tf) - J

    @cached_property
    def _terminal_function(self) -> ca.Function:
        p = self.problem
        return ca.Function("terminal", [p.state_vector(), p.time], [p.terminal])

    def _terminal_value(self, final_state: np.ndarray, tf: float) -> float:
        return float(self._terminal_function(final_state, tf))

    @cached_property
    def _slack_weights(self) -> np.ndarray:
        return np.repeat(self.per_step_weights(), self.slacks_per_value)

    @cached_property
    def _hessian(self) -> ElementHessian:
        """The exact Lagrangian Hessian of the equalities, path rows and epigraph row, interval by interval."""
        z, equalities, path, epigraph = self._symbols
        return element_hessian(z, ca.vertcat(equalities, path, epigraph),
                               interval_of_rows(self, equalities.shape[0], epigraph.shape[0]))

    @cached_property
    def _weights_per_step(self) -> np.ndarray:
        return np.repeat(self.per_step_weights(), self.nu)

    # --- NonconvexProgram -----------------------------------------------------------------------------------
    def initial_guess(self) -> np.ndarray:
        """The user's node values when given (:meth:`~convexguid.ocp.problem.Problem.initial_guess`), else
        :meth:`initial_guess_straight`, its free positions flown (:func:`~convexguid.ocp.guess.flown_free_states`)."""
        p, N = self.problem, self.N
        tf = p.tf_guess if self.free_time else p.tf
        if p.guess_nodes is not None and p.guess_nodes[0].shape[0] == N + 1:
            return self.assemble(p.guess_nodes[0], self.values_from_nodes(p.guess_nodes[1]), tf)
        return flown_free_states(self, self.initial_guess_straight())

    def initial_guess_straight(self) -> np.ndarray:
        """States straight from their initial to their final values (the other given one where only one is),
        controls at their guess (else the middle of finite bounds, else 0), the final time at its guess."""
        return self.straight_guess(*self.problem.straight_line())

    def straight_guess(self, start: np.ndarray, end: np.ndarray, control: np.ndarray) -> np.ndarray:
        """``z`` with the states on the straight line from ``start`` to ``end`` (node by node), every control value at
        ``control`` and the final time at its guess."""
        p = self.problem
        s = np.linspace(0.0, 1.0, self.N + 1)[:, None]
        values = np.tile(control, (self.control_values_per_axis(), 1))
        return self.assemble(start + s * (end - start), values, p.tf_guess if self.free_time else p.tf)

    def variable_scale(self) -> np.ndarray:
        N = self.N
        states = self.state_scales
        controls = self.control_scales
        per_axis = self.control_values_per_axis()
        parts = [np.tile(states, N + 1), np.tile(controls, per_axis)]
        if self.fuel:
            parts.append(np.tile(controls, per_axis) if self.fuel_norm == 1
                         else np.full(per_axis, float(np.linalg.norm(controls))))
        if self.epigraph:
            horizon = self.problem.tf_guess if self.free_time else self.problem.tf
            parts.append([max(horizon * float(controls.sum()), 1e-6) if self.fuel else terminal_scale(self)])
        if self.free_time:
            parts.append([max(self.problem.tf_guess, 1e-6)])
        return np.concatenate(parts)

    @cached_property
    def _energy_rows(self) -> tuple[sp.coo_matrix, np.ndarray]:
        """Residual selection (every control value) and the quadrature's weights for them."""
        h = (self.problem.tf or 0.0) / self.N
        select = linear_rows.selection(np.arange(self.control_start, self.slack_start), 1.0, self.num_variables)
        return select, h * self._weights_per_step

    def residual_weights(self) -> np.ndarray:
        return self._energy_rows[1] if self.problem.objective == "energy" else np.zeros(0)

    def linear_cost(self) -> np.ndarray:
        cost = np.zeros(self.num_variables)
        if self.problem.objective == "time":
            cost[-1] = 1.0
        elif self.epigraph:
            cost[self.slack_start + self.num_slacks] = 1.0
        elif self.fuel:
            cost[self.slack_start: self.slack_start + self.num_slacks] = self.problem.tf / self.N * \
                self._slack_weights
        elif self.problem.objective == "terminal":
            cost += terminal_gradient(self)
        return cost

    def linear_constraints(self) -> LinearConstraints:
        """Boundary values, affine boundary rows, bounds (a repaired state bound less its margin), the bounded
        controls' interpolants and minimum fuel's slack rows (:mod:`convexguid.ocp.linear_rows`)."""
        return linear_rows.linear_constraints(self)

    def guarded_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The states' bounds, at every node: the steps keep short of them until they are nearly met
        (:meth:`~convexguid.scp.policies.TrustRegionPolicy.box`). A state's bound is often where its dynamics stop
        meaning anything (a mass, a density, a logarithm's argument); a control's is where bang-bang plans sit, and
        is left unguarded."""
        low, high = linear_rows.variable_bounds(self)
        states = np.arange(low.size) < self.control_start
        return np.where(states, low, -np.inf), np.where(states, high, np.inf)

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
                                      self._defect_pattern.coo(defect_jac) if jacobians else None, "scaled state",
                                      self.defect_labels),)
        if self.equality_rows:
            value, jacobian = self._path_equalities(z)
            equalities += (ConstraintBlock("path_equalities", np.asarray(value, dtype=float).ravel(),
                                           self._path_equality_pattern.coo(jacobian) if jacobians else None),)
        if self.boundary_equality_rows:
            value, jacobian = self._boundary_equalities(z)
            equalities += (ConstraintBlock("boundary_equalities", np.asarray(value, dtype=float).ravel(),
                                           self._boundary_pattern.coo(jacobian) if jacobians else None),)
        inequalities = ()
        if self.num_path:
            values = np.asarray(path, dtype=float).ravel() + self.margins.path
            inequalities = (ConstraintBlock("path_constraints", values,
                                            self._path_pattern.coo(path_jac) if jacobians else None,
                                            labels=self.path_labels),)
        if self.epigraph:
            value, jacobian = self._objective_epigraph(z)
            inequalities += (ConstraintBlock("objective_epigraph", np.asarray(value, dtype=float).ravel(),
                                             self._epigraph_pattern.coo(jacobian) if jacobians else None),)
        cones = (self._cones.block(z, self.margins.cone, jacobians),) if self._cones is not None else ()
        return Evaluation(residuals, residual_jacobian, inequalities, equalities, cones)

    def symbolic_nlp(self, z: ca.SX | None = None) -> SymbolicNLP:
        """The program as one CasADi NLP (:class:`SymbolicNLP`): what an independent solver of the same problem (the
        IPOPT reference, the benchmarks) reads; ``z`` (default: new symbols) stands for the decision vector."""
        z = ca.SX.sym("z", self.num_variables) if z is None else z
        objective = ca.dot(ca.DM(self.linear_cost()), z)
        if self.residual_weights().size:
            objective += ca.dot(ca.DM(self.residual_weights()), (ca.DM(self._energy_rows[0].toarray()) @ z) ** 2)
        lin = self.linear_constraints()
        blocks = (("dynamics_defects", self._defects(z)[0], 0.0, 0.0),
                  ("path_equalities", self._path_equalities(z)[0], 0.0, 0.0),
                  ("boundary_equalities", self._boundary_equalities(z)[0], 0.0, 0.0),
                  ("path_constraints", self._path(z)[0] + ca.DM(self.margins.path), -np.inf, 0.0),
                  ("objective_epigraph", self._objective_epigraph(z)[0], -np.inf, 0.0),
                  ("linear_equalities", ca.DM(lin.A.toarray()) @ z - lin.b, 0.0, 0.0),
                  ("linear_inequalities", ca.DM(lin.G.toarray()) @ z - lin.h, -np.inf, 0.0))
        return SymbolicNLP(z, objective, blocks)

    @cached_property
    def _element_curvature(self) -> ElementCurvature:
        return ElementCurvature(self._hessian)

    def curvature_model(self) -> CurvatureModel | None:
        """The constraints' exact curvature made convex interval by interval (:mod:`convexguid.ocp.curvature`),
        weighted by the multipliers of the equalities, the path rows and the epigraph row; None when affine."""
        if self.affine:  # no curvature to model: the Hessian is not even built
            return None
        return self._element_curvature.model(self._row_weights)

    def _row_weights(self, weights) -> np.ndarray:
        """One multiplier per row of :attr:`_hessian`: the equalities', the path rows' and the epigraph row's."""
        return np.concatenate([weights.equality, weights.inequality[: self.num_path + self._symbols[3].shape[0]]])

    def lagrangian_hessian(self, z: np.ndarray, weights) -> sp.csr_matrix:
        """CasADi's exact :math:`\\sum \\lambda_k \\nabla^2 e_k + \\sum \\mu_j \\nabla^2 g_j` (the energy residuals are
        linear in ``z``: no curvature of their own)."""
        return self._hessian.matrix(z, self._row_weights(weights))
