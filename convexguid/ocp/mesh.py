"""Error-driven mesh refinement of a Hermite-Simpson transcription (Betts, *Practical Methods for Optimal Control
and Estimation Using Nonlinear Programming*, 2nd ed., SIAM 2010, Sec. 4.7: estimate the discretization error of
every interval, subdivide where it is, predict the reduction from the method's order and the order reduction seen).

* Grids. A transcription's nodes sit at shares :math:`0 = \\tau_0 < \\dots < \\tau_N = 1` of the final time;
  :func:`checked_shares` validates them, :func:`is_uniform` says when they are the equal intervals (the program then
  takes the equal-step build, bit for bit), :func:`split_shares` splits chosen intervals into equal pieces.
* The local error (:func:`interval_errors`). Each interval is integrated from its own start node under the planned
  control as it is flown (:func:`held_control`: the transcription's interpolant clipped to the control's bounds)
  with SciPy's DOP853 (rtol 1e-10) and compared with the next node, each state in its scale: the error the
  interval adds to the flown trajectory (Betts' estimate integrates the collocation residual instead; both vanish
  as the interval shrinks at the method's order).
* The split (:func:`pieces_wanted`). Betts' error model: an interval's error falls as :math:`h^{p - r + 1}` with
  :math:`p = 4` for Hermite-Simpson and an order reduction :math:`0 \\le r \\le p`, estimated from the error of the
  interval it was split from (:func:`order_reduction`; none known: :data:`ASSUMED_ORDER_REDUCTION`). An interval
  whose error :math:`\\eta` exceeds the tolerance :math:`\\epsilon` is split into the fewest pieces
  :math:`m \\ge 2` with :math:`\\eta\\, m^{-(p - r + 1)} \\le \\epsilon`, at most :data:`MAX_PIECES`.
* A control that chatters between neighbouring values (:func:`control_jumps`) satisfies the collocation equations,
  not the flown dynamics; its intervals (:func:`chattering_intervals`) are split as well.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.integrate import solve_ivp

from convexguid.errors import SolverError, SpecError
from convexguid.ocp.declarations import point_kind
from convexguid.ocp.parts import NumericFunction

if TYPE_CHECKING:  # the transcriptions import this module
    from convexguid.ocp.problem import Problem
    from convexguid.ocp.transcription import Transcription

LOCAL_ERROR_TOLERANCE = 1e-6
"""Largest local error of an interval, as a share of each state's scale, that refinement leaves unsplit."""

HERMITE_SIMPSON_ORDER = 4
"""Betts' :math:`p` of Hermite-Simpson collocation: the local error of a step :math:`h` is :math:`O(h^{p + 1})`."""

ASSUMED_ORDER_REDUCTION = 0
"""The order reduction assumed for an interval whose error was never measured on a coarser interval (the smooth
case: halving it divides its error by 32; where that proves optimistic the next refinement measures it)."""

MAX_PIECES = 4
"""At most this many pieces per interval in one refinement (Betts' bound on the points added to one interval)."""

MAX_RATE_EVALUATIONS = 50_000
"""Evaluations of the dynamics one interval's flight may take (DOP853 takes 12 a step: about 4000 steps; the
classics' flights take a few hundred). A plan flown where its dynamics blow up (a density exp(-h / H) at a
position guessed deep below the surface) otherwise keeps the dense check integrating for as long as it is let."""

JUMP_SHARE = 0.5
"""A control whose value moves by more than this share of its range between neighbouring values is named."""


# --- grids --------------------------------------------------------------------------------------------------------
def uniform_shares(intervals: int) -> np.ndarray:
    return np.linspace(0.0, 1.0, intervals + 1)


def is_uniform(shares: np.ndarray) -> bool:
    """Whether the node shares are the equal intervals (to a few rounding errors)."""
    return bool(np.max(np.abs(shares - uniform_shares(shares.size - 1))) <= 1e-14)


def checked_shares(shares, where: str) -> np.ndarray:
    """``shares`` as floats, refused unless they start at 0, end at 1 and increase, with at least two intervals."""
    shares = np.asarray(shares, dtype=float).ravel()
    if shares.size < 3 or shares[0] != 0.0 or shares[-1] != 1.0 or np.any(np.diff(shares) <= 0.0):
        raise SpecError(f"{where}: grid: expected increasing node shares of the final time from 0 to 1 with at least "
                        f"two intervals (got {shares.size} shares from {shares[0] if shares.size else None} to "
                        f"{shares[-1] if shares.size else None})")
    return shares


def split_shares(shares: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """The node shares with interval ``k`` split into ``pieces[k]`` equal parts (the old nodes kept exactly)."""
    parts = [shares[k] + np.arange(m) / m * (shares[k + 1] - shares[k]) for k, m in enumerate(pieces)]
    return np.concatenate([*parts, shares[-1:]])


def require_point_constraints_on_nodes(problem: Problem, shares: np.ndarray, grid_name: str) -> None:
    """Refuse a point constraint whose instant is not a node of the grid (it is imposed at a node only)."""
    for c in problem.constraints:
        if c.at is not None and np.min(np.abs(shares - c.at)) > 1e-9:
            raise SpecError(f"{problem.name}: {point_kind(c.equality)} {c.name!r}: at = {c.at:g} of the final time is "
                            f"not a node of the {grid_name} (nodes at shares {', '.join(f'{v:.4g}' for v in shares)})")


# --- the plan as flown -------------------------------------------------------------------------------------------
def held_control(program: Transcription, z: np.ndarray):
    """The planned control as a function of time, as the transcription holds it between nodes, within its bounds
    (the actuator delivers no more: where Hermite-Simpson's quadratic overshoots a bound between nodes, as it does
    next to a switch of a bang-bang control, the flight gets the bound)."""
    planned = program.control_function(program.unwrapped(z))
    low, high = program.problem.bounds_array(program.problem.controls)
    return lambda t: np.clip(planned(t), low, high)


def state_names(program: Transcription) -> tuple[str, ...]:
    """The program's state names in their order (what :func:`fly` names a rate that is not a number by)."""
    return tuple(v.name for v in program.problem.states)


class _NotANumber(Exception):
    """A rate that is not a number: ``(t, indices of the states)``."""


class _TooManyEvaluations(Exception):
    pass


def fly(rate, control, span: tuple[float, float], start: np.ndarray, names: tuple[str, ...] = (), **options):
    """SciPy's DOP853 (rtol 1e-10) flight of :math:`x' = f(x, u(t), t)` (``rate``, ``control``) over ``span`` from
    ``start`` (``options``: ``t_eval``, ``atol``, ``dense_output``); :class:`~convexguid.errors.SolverError` past
    :data:`MAX_RATE_EVALUATIONS`, or where a rate is not a number (naming the state from ``names``)."""
    count = 0

    def counted(t, x):
        nonlocal count
        count += 1
        if count > MAX_RATE_EVALUATIONS:
            raise _TooManyEvaluations
        value = rate(x, control(t), t)
        if not np.all(np.isfinite(value)):
            raise _NotANumber(t, np.flatnonzero(~np.isfinite(value)))
        return value

    try:
        return solve_ivp(counted, span, start, method="DOP853", rtol=1e-10, **options)
    except _TooManyEvaluations:
        raise SolverError(f"the plan could not be flown from t = {span[0]:.6g} to {span[1]:.6g}: more than "
                          f"{MAX_RATE_EVALUATIONS} evaluations of the dynamics (stiff or blowing up along the "
                          "plan)") from None
    except _NotANumber as nan:
        t, rows = nan.args
        which = ", ".join(names[i] if i < len(names) else f"#{i}" for i in rows)
        raise SolverError(f"the plan could not be flown past t = {t:.6g}: the rate of {which} is not a number there "
                          "(a division by zero?)") from None


def interval_flows(program: Transcription, z: np.ndarray, control=None) -> list:
    """Each interval integrated from its own start node under ``control`` (default :func:`held_control`) with DOP853
    (rtol 1e-10), SciPy's result with its dense output ``sol``, one per interval."""
    u = held_control(program, z) if control is None else control
    rate, scales = NumericFunction(program.rate), program.state_scales
    states, times = program.states(z), program.final_time(z) * program.node_shares()
    return [fly(rate, u, (times[k], times[k + 1]), states[k], state_names(program), atol=1e-12 * scales,
                dense_output=True)
            for k in range(program.N)]


def interval_errors(program: Transcription, z: np.ndarray, flows: list | None = None) -> np.ndarray:
    """Each interval's local error (Betts 2010, Sec. 4.7): the state integrated from the interval's start node under
    the plan as flown (:func:`interval_flows`, given or made) less the next node, each state divided by its scale,
    the largest of them; shape ``(N,)``."""
    flows = interval_flows(program, z) if flows is None else flows
    ends = np.array([flow.y[:, -1] for flow in flows])
    errors = np.max(np.abs(ends - program.states(z)[1:]) / program.state_scales, axis=1)
    return np.where(np.isnan(errors), np.inf, errors)  # a flight that cannot be integrated: the worst error


def control_jumps(program: Transcription, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The control values' shares in time order, and whether each control moves by more than :data:`JUMP_SHARE` of
    its range between each pair of neighbouring values, shape ``(C - 1, nu)``."""
    shares = program.control_value_shares()
    order = np.argsort(shares, kind="stable")
    values = program.control_values(program.unwrapped(z))[order]
    low, high = program.problem.bounds_array(program.problem.controls)
    spread = np.where(np.isfinite(high - low), high - low, np.ptp(values, axis=0))
    jumps = (np.abs(np.diff(values, axis=0)) > JUMP_SHARE * spread) & (spread > 0)
    return shares[order], jumps


def chattering_intervals(program: Transcription, z: np.ndarray) -> np.ndarray:
    """Whether some control jumps (:func:`control_jumps`) between two neighbouring values inside each interval, or
    between a node and the values on either side of it (both intervals), shape ``(N,)``."""
    shares, jumps = control_jumps(program, z)
    nodes = program.node_shares()
    marked = np.zeros(program.N, dtype=bool)
    for pair in np.flatnonzero(jumps.any(axis=1)):
        first = np.searchsorted(nodes, shares[pair], side="right") - 1
        last = np.searchsorted(nodes, shares[pair + 1], side="left") - 1
        marked[np.clip(first, 0, program.N - 1): np.clip(last, 0, program.N - 1) + 1] = True
    return marked


# --- the split ----------------------------------------------------------------------------------------------------
def order_reduction(program: Transcription, errors: np.ndarray) -> np.ndarray:
    """Each interval's order reduction :math:`r` (Betts 2010, Sec. 4.7): from the error :math:`\\theta` of the
    interval it was split from into :math:`m` pieces and its own :math:`\\eta`,
    :math:`\\hat r = p + 1 - \\ln(\\theta / \\eta) / \\ln m`, rounded into ``[0, p]``; :data:`ASSUMED_ORDER_REDUCTION`
    for an interval not split from a measured one."""
    p = HERMITE_SIMPSON_ORDER
    reduction = np.full(program.N, float(ASSUMED_ORDER_REDUCTION))
    origin = getattr(program, "split_from", None)
    if origin is None:
        return reduction
    parent_errors, pieces = origin
    measured = (pieces > 1) & (parent_errors > 0) & (errors > 0)
    estimate = p + 1 - np.log(parent_errors[measured] / errors[measured]) / np.log(pieces[measured])
    reduction[measured] = np.clip(np.round(estimate), 0, p)
    return reduction


def pieces_wanted(errors: np.ndarray, reduction: np.ndarray, tolerance: float) -> np.ndarray:
    """The fewest pieces ``m`` in ``[2, MAX_PIECES]`` bringing each interval's predicted error
    :math:`\\eta\\, m^{-(p - r + 1)}` to the tolerance (Betts 2010, Sec. 4.7)."""
    exponent = HERMITE_SIMPSON_ORDER - reduction + 1
    ratio = np.maximum(errors / tolerance, 1.0)
    return np.clip(np.ceil(ratio ** (1.0 / exponent) - 1e-9), 2, MAX_PIECES).astype(int)


@dataclass(frozen=True)
class MeshPlan:
    """Which intervals to split into how many pieces, and the sentence saying why."""

    pieces: np.ndarray
    errors: np.ndarray
    """Each interval's local error before the split (:func:`interval_errors`)."""
    flows: list
    """Each interval's integration (:func:`interval_flows`): the states at the new nodes."""
    description: str


def plan_refinement(program: Transcription, z: np.ndarray, broken: np.ndarray, max_intervals: int,
                    tolerance: float = LOCAL_ERROR_TOLERANCE) -> MeshPlan | None:
    """The pieces of every interval (1: kept): those whose local error exceeds ``tolerance``, those where the
    dense check ``broken`` a constraint and those where a control chatters are split (:func:`pieces_wanted`; at
    least in two); with none of them, those within a tenth of the largest error. The worst first while the total
    stays within ``max_intervals``; None when not one interval can be split."""
    N = program.N
    flows = interval_flows(program, z)
    errors = interval_errors(program, z, flows)
    wanted = pieces_wanted(errors, order_reduction(program, errors), tolerance)
    reasons = {"local": errors > tolerance, "broken": np.asarray(broken, dtype=bool) & (errors <= tolerance)}
    reasons["chatter"] = chattering_intervals(program, z) & ~reasons["local"] & ~reasons["broken"]
    flagged = reasons["local"] | reasons["broken"] | reasons["chatter"]
    largest = float(errors.max())
    if not flagged.any():
        flagged = errors >= 0.1 * largest
    pieces, count, held_back = np.ones(N, dtype=int), N, 0
    for k in sorted(np.flatnonzero(flagged), key=lambda k: -errors[k]):
        extra = min(wanted[k] - 1, max_intervals - count)
        if extra < 1:
            held_back += 1
            continue
        pieces[k] += extra
        count += extra
    split = int(np.sum(pieces > 1))
    if split == 0:
        return None
    phrases = {"local": f"where the local error exceeded {tolerance:g}",
               "broken": "where the dense check broke a constraint", "chatter": "where a control chatters"}
    why: list[str] = []
    for name, marked in reasons.items():
        if marked.any():
            why.append(f"{int(marked.sum())} {'more ' if why else ''}{phrases[name]}")
    if not why:
        why = [f"the local error nowhere exceeded {tolerance:g}: those within a tenth of the largest"]
    cap = f"; {held_back} more held back by the cap of {max_intervals}" if held_back else ""
    return MeshPlan(pieces, errors, flows, f"{split} of {N} intervals split ({', '.join(why)}; largest local error "
                                    f"{largest:.2g}{cap}): {count} intervals")


def refined_program(program: Transcription, z: np.ndarray, plan: MeshPlan) -> tuple[Transcription, np.ndarray]:
    """The program on the grid ``plan`` splits, the plan ``z`` carried onto it, the new nodes' states from each
    interval's integration (then every new interval's defect is its own truncation error, and the last piece's also
    the local error its interval had; the collocated cubic would leave defects of a lower order there). Each new
    interval remembers the error of the interval it came from and into how many pieces that was split
    (:func:`order_reduction` reads them)."""
    times = program.final_time(z) * program.node_shares()

    def flown(k: int, shares: np.ndarray) -> np.ndarray:
        return plan.flows[k].sol(times[k] + shares * (times[k + 1] - times[k])).T

    fine, start = program.refined(z, plan.pieces, flown)
    fine.split_from = (np.repeat(plan.errors, plan.pieces), np.repeat(plan.pieces, plan.pieces))
    return fine, start
