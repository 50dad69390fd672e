"""What a :class:`~convexguid.ocp.problem.Problem`'s declarations make: a scalar :class:`Variable` (state, control
or parameter) and a :class:`PathConstraint`, and the check every number a user gives goes through."""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from convexguid.errors import SpecError


@dataclass(frozen=True)
class Variable:
    """A scalar state or control: its symbol, bounds (``None``: none), boundary values and typical magnitude."""

    name: str
    symbol: ca.SX
    lower: float | None
    upper: float | None
    initial: float | None
    final: float | None
    scale: float
    guess: float | None
    unit: str = ""
    period: float | None = None
    """For an angle control without bounds: the period (2 pi) its values may be shifted by, see
    :meth:`Problem.control`."""
    scale_from: str = "stated"
    """Where ``scale`` came from: ``"stated"`` by the user, ``"values"`` the largest magnitude of its bounds and
    boundary values, ``"none"`` (1) when nothing gives its size; a state's scale of the last two kinds may be
    estimated from its rate instead (:meth:`Problem.state_scales`)."""

    def fallback_guess(self) -> float:
        """A state's guess when nothing stated gives one: 0, or the nearest bound where its bounds exclude 0 (an
        airspeed bounded to [10, 350] ft/s guessed at 0 starts the dynamics at a division by zero). The middle of
        the bounds (180 ft/s) was tried on Zhao's dynamic soaring: from it the SCP ended ``max_iterations`` on 30
        and 40 intervals; from the nearest bound it converges on 30 and 40 (docs/ocp.md, dynamic soaring)."""
        return float(np.clip(0.0, -np.inf if self.lower is None else self.lower,
                             np.inf if self.upper is None else self.upper))


def point_kind(equality: bool) -> str:
    """The call that states a constraint at one instant, as messages name it."""
    return "point_equality" if equality else "point_constraint"


@dataclass(frozen=True)
class PathConstraint:
    """``expression <= 0`` in ``unit``: over the share ``during`` of the maneuver (every node and midpoint there,
    checked densely between them), or at the one instant ``at`` (a share of the final time)."""

    name: str
    expression: ca.SX
    unit: str
    during: tuple[float, float] = (0.0, 1.0)
    at: float | None = None
    equality: bool = False
    """``expression == 0`` instead (a path equality: linearized like the inequalities, never tightened)."""
    at_nodes: bool = True
    """False: imposed between the nodes only (Hermite-Simpson's midpoints), for a bound the nodes hold hard."""
    at_midpoints: bool = True
    """False: imposed at the nodes only (a path equality of the states alone, see :meth:`Problem.path_equality`)."""
    cone: tuple[ca.SX, ca.SX] | None = None
    """For a second-order cone ``||vector|| <= bound``: ``(bound, vector)``, affine in states and controls (kept
    exact in every subproblem); ``expression`` is then ``||vector|| - bound``, what the dense check evaluates."""
    scale: float | None = None
    """The stated magnitude (None: estimated); what its rows are divided by follows from it
    (:func:`~convexguid.ocp.constraint_units.constraint_divisors`)."""
    judged: bool = True
    """False: held by the transcription, not judged by the dense check (an end's rate condition, implied by a bound
    the check judges itself: :mod:`convexguid.ocp.pinned`)."""
    holds_bound: tuple[int, bool] | None = None
    """``(state, upper)``: the row holds that state's upper (else lower) bound between the nodes, where the nodes hold
    it hard (:func:`~convexguid.ocp.hermite_simpson.with_bounds_between_nodes`); a repair of the bound tightens it."""

    def applies(self, share: float, node: bool) -> bool:
        """Whether the constraint is imposed at the point ``share`` of the maneuver (a node or a midpoint)."""
        if self.at is not None:
            return node and abs(share - self.at) < 1e-9
        if (node and not self.at_nodes) or (not node and not self.at_midpoints):
            return False
        return self.during[0] - 1e-12 <= share <= self.during[1] + 1e-12


def column(where: str, expression) -> ca.SX:
    """``expression`` as a column of CasADi expressions: a scalar, a column, or a list or tuple of scalars (stacked);
    anything else is one line naming ``where``."""
    try:
        if isinstance(expression, (list, tuple)):
            return ca.vertcat(*(ca.SX(e) for e in expression)) if expression else ca.SX(0, 1)
        return ca.SX(expression)
    except (NotImplementedError, TypeError, RuntimeError) as error:
        raise SpecError(f"{where}: expected an expression or a list of them (got {type(expression).__name__}: "
                        f"{str(error).splitlines()[0] if str(error) else 'not an expression'})") from None


def positive_scale(where: str, value: object) -> float | None:
    """A stated constraint magnitude (``scale=``): None, or a positive number; else one line naming ``where``."""
    scale = number(f"{where}: scale", value)
    if scale is not None and not scale > 0:
        raise SpecError(f"{where}: scale: must be positive (got {value!r})")
    return scale


def number(where: str, value: object, allow_none: bool = True) -> float | None:
    """``value`` as a float; one line naming ``where`` when it is not a finite number (None passes if allowed)."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SpecError(f"{where}: expected a finite number{' or None' if allow_none else ''} (got {value!r})")
    return float(value)
