"""Cross-method tables of the validation report: cases of one scenario solved by different methods, side by side.

A case joins a table through its problem file, ``reference.comparison: {table: <id>, label: <row label>}``
(optionally ``role`` and ``figures``, see :class:`~convexguid.spec.common.ComparisonEntry`). This module only
renders the results the validation run hands it: one row per case, ordered by role (baseline, minimum time,
minimum energy, then the rest in the order of the results); the sentences
under a table are computed from the rows present, found by their ``role`` (a sentence whose roles are missing
is left out). A column shows a figure of the solution (:meth:`~convexguid.solution.Solution.figure`, n/a where
the solution does not carry it) or a value computed from the solution; a row's ``figures`` names the figure
standing for a column where the default does not apply (e.g. a simulated controller's maneuver time), checked
against the fields of its family's figures type before anything is solved. Columns of compute times are
``timed``: :func:`comparison_sections` leaves them out (the committed report is the same on every run) and
:func:`comparison_timings` renders them, with the sentences that use them, for the timings file. Tables:

* ``multicone`` (Wang, Xu, Li, Table 2 layout): maneuver time, planning time, smallest cone margin on the dense
  grid, energy, verified; roles ``baseline`` (the paper's planner) and ``min_time``.
* ``forbidden_attitude`` (Guo, Li, Ma 2011): maneuver time, energy, smallest angle to the forbidden attitude,
  compute time, verified; roles ``baseline`` (the controller), ``min_time`` and ``min_energy``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from convexguid.errors import SpecError
from convexguid.families import get_family
from convexguid.solution import Solution
from convexguid.spec import ProblemSpec


@dataclass(frozen=True)
class Column:
    """One column: ``default`` gives the value from a solution unless the row's ``figures`` names a figure.

    A ``timed`` column holds compute times: it goes to the timings file, not to the report.
    """

    id: str
    header: str
    fmt: str
    default: Callable[[Solution], float | None]
    timed: bool = False


@dataclass(frozen=True)
class Row:
    """One case of a table, its column values by column id."""

    label: str
    role: str | None
    solution: Solution
    values: dict[str, float | None]


@dataclass(frozen=True)
class Table:
    """A cross-method table: heading, text above it, columns (then ``verified``), sentences below it.

    ``timing_notes`` are the sentences about its ``timed`` columns (timings file only).
    """

    id: str
    title: str
    intro: tuple[str, ...]
    columns: tuple[Column, ...]
    notes: Callable[[dict[str, Row], list[Row]], list[str]]
    timing_notes: Callable[[dict[str, Row], list[Row]], list[str]] | None = None


def _figure(name: str) -> Callable[[Solution], float | None]:
    """The figure ``name`` of a solution as a number (None where the solution does not carry it)."""

    def value(sol: Solution) -> float | None:
        return _number(sol.figure(name)) if name in sol.figure_names() else None

    return value


def _number(value: object) -> float | None:
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def _smallest_forbidden_angle(sol: Solution) -> float | None:
    """Smallest angle to a forbidden attitude on the dense check (its ``forbidden*`` constraints)."""
    checks = [c.worst for c in (sol.verification.checks if sol.verification else ()) if c.name.startswith("forbidden")]
    return min(checks) if checks else None


def _maneuver_time(fmt: str) -> Column:
    return Column("maneuver_time", "maneuver time [s]", fmt, _figure("maneuver_time_s"))


def _energy(fmt: str) -> Column:
    return Column("energy", "energy [N^2 m^2 s]", fmt, _figure("energy"))


def _compute_time(header: str, fmt: str) -> Column:
    return Column("compute_time", header, fmt, lambda sol: _number(sol.wall_time_s), timed=True)


def _multicone_notes(roles: dict[str, Row], rows: list[Row]) -> list[str]:
    text = []
    base, fast = roles.get("baseline"), roles.get("min_time")
    if base and fast and None not in (base.values["maneuver_time"], fast.values["maneuver_time"]):
        cut = 1 - fast.values["maneuver_time"] / base.values["maneuver_time"]
        text.append(f"The SCP's minimum-time plan is {100 * cut:.1f}% shorter than the path-transfer plan (the paper "
                    "reports path transfer cutting the maneuver time by about 85% and the planning time by about 33% "
                    "against RDRP, which is not reimplemented here; the planning times are in the timings file).")
    clearance = next((r.solution for r in rows if _carried(r.solution, "eigenaxis_min_angle_deg")), None)
    if clearance is not None:
        angles = clearance.figure("eigenaxis_min_angle_deg")
        cones = clearance.figure("cones") if "cones" in clearance.figure_names() else ()
        text.append("The eigenaxis slew passes this close to each cone's direction: "
                    + ", ".join(f"{k} {v:.3f} deg" for k, v in angles.items()) + _broken_cones(angles, cones) + ".")
    text.append("Margins are measured on the dense SciPy re-propagation.")
    return ["", " ".join(text)]


def _multicone_timing_notes(roles: dict[str, Row], rows: list[Row]) -> list[str]:
    base, fast = roles.get("baseline"), roles.get("min_time")
    text = []
    if base and fast and base.values["compute_time"] and fast.values["compute_time"] is not None:
        ratio = fast.values["compute_time"] / base.values["compute_time"]
        text.append(f"The SCP's minimum-time plan takes {ratio:.2f}x the path-transfer planning time.")
    text.append("Compute times are single runs of `convexguid validate`; `convexguid bench` repeats them against "
                "IPOPT.")
    return ["", " ".join(text)]


def _carried(sol: Solution, name: str) -> bool:
    """The solution carries the figure ``name`` and it is not empty."""
    return name in sol.figure_names() and bool(sol.figure(name))


def _broken_cones(angles: dict[str, float], cones: Sequence[dict]) -> str:
    """``; cones 1 and 2 (20 and 15 deg half-angles) are broken``: keep-out cones (the summary's ``cones``: each
    with ``name``, ``keep_out`` and ``half_angle_deg``) the eigenaxis slew enters, given its smallest angle to each
    cone's direction by name."""
    broken = [(i, c["half_angle_deg"]) for i, c in enumerate(cones, 1)
              if c["keep_out"] and c["name"] in angles and angles[c["name"]] < c["half_angle_deg"]]
    if not cones:
        return ""
    if not broken:
        return "; it breaks no cone"

    def _and(items: list[str]) -> str:
        return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]

    if len(broken) == 1:
        return f"; cone {broken[0][0]} ({broken[0][1]:g} deg half-angle) is broken"
    return (f"; cones {_and([str(i) for i, _ in broken])} ({_and([f'{h:g}' for _, h in broken])} deg half-angles) "
            "are broken")


def _forbidden_notes(roles: dict[str, Row], rows: list[Row]) -> list[str]:
    text = []
    base, plan, fast = roles.get("baseline"), roles.get("min_energy"), roles.get("min_time")
    if base and plan and base.values["energy"] and plan.values["energy"] is not None:
        e_base, e_plan = base.values["energy"], plan.values["energy"]
        text.append(f"At the controller's maneuver time the SCP plan uses {100 * (1 - e_plan / e_base):.1f}% less "
                    f"energy ({e_plan:.4g} against {e_base:.4g} N^2 m^2 s)"
                    + (";" if fast and fast.values["maneuver_time"] is not None else "."))
    if fast and fast.values["maneuver_time"] is not None:
        finish = f"the minimum-time plan finishes in {fast.values['maneuver_time']:.1f} s."
        text.append(finish if text else finish[0].upper() + finish[1:])
    tracked = roles.get("tracked")
    if tracked is None or tracked.values["energy"] is None:
        text.append("The controller flies a disturbed closed loop and needs no plan; the SCP plans open loop without "
                    "the disturbance torque and would need a tracking loop.")
        return ["", " ".join(text)]
    text.append("The controller flies a disturbed closed loop and needs no plan; the SCP plans open loop without "
                "the disturbance torque.")
    e_track, angle = tracked.values["energy"], tracked.values["forbidden_angle"]
    versus = (f", {100 * (1 - e_track / base.values['energy']):.1f}% less than the controller"
              if base and base.values["energy"] else "")
    kept = "n/a" if angle is None else f"{angle:.2f} deg"
    verdict = "verified" if tracked.solution.ok else "NOT verified"
    text.append(f"Flown closed loop by the LPMPC tracker under the same disturbance, the minimum-energy plan uses "
                f"{e_track:.4g} N^2 m^2 s{versus}, and keeps theta_b at {kept} ({verdict} on the flight).")
    return ["", " ".join(text)]


TABLES: dict[str, Table] = {table.id: table for table in (
    Table("multicone", "Multi-cone slew: path transfer against the SCP (Wang, Xu, Li, Table 2 layout)", (),
          (_maneuver_time(".3f"), _compute_time("planning (compute) time [s]", ".3f"),
           Column("cone_margin", "smallest cone margin [deg]", ".3f", _figure("min_cone_margin_deg")),
           _energy(".4g")),
          _multicone_notes, _multicone_timing_notes),
    Table("forbidden_attitude",
          "Forbidden attitude: potential-function controller against the SCP planner (Guo, Li, Ma 2011)",
          ("Same spacecraft, boundary attitudes and limits (|u_i| <= 0.5 N m, |w_i| <= 1.91 deg/s, theta_b > 10 deg); "
           "the controller's maneuver time is to within 0.1 deg of the command.",),
          (_maneuver_time(".2f"), _energy(".4g"),
           Column("forbidden_angle", "smallest theta_b [deg]", ".2f", _smallest_forbidden_angle),
           _compute_time("compute time [s]", ".3f")),
          _forbidden_notes),
)}
"""The cross-method tables, by the id a problem file's ``reference.comparison.table`` gives."""


def check_comparisons(specs: Sequence[ProblemSpec]) -> None:
    """Check the ``reference.comparison`` blocks of the cases of one validation run before anything is solved.

    Raises
    ------
    SpecError
        For an unknown table or column id, a figure that is not a field of the row's family's figures type
        (:attr:`~convexguid.families.base.Family.figures`), or two rows of a table with the same role or label.
    """
    seen: dict[tuple[str, str, str], str] = {}
    for spec in specs:
        entry = spec.reference.comparison if spec.reference is not None else None
        if entry is None:
            continue
        where = f"{spec.source}: reference.comparison"
        table = TABLES.get(entry.table)
        if table is None:
            raise SpecError(f"{where}.table: unknown table (got {entry.table!r}); known tables: {', '.join(TABLES)}")
        columns = [c.id for c in table.columns]
        known = get_family(spec.family).figures.names()
        for column, figure in (entry.figures or {}).items():
            if column not in columns:
                raise SpecError(f"{where}.figures.{column}: not a column of table {entry.table!r} "
                                f"(got {column!r}); its columns: {', '.join(columns)}")
            if figure not in known:
                raise SpecError(f"{where}.figures.{column}: not a figure of family {spec.family!r} "
                                f"(got {figure!r}); its figures: {', '.join(sorted(known))}")
        for what, value in (("role", entry.role), ("label", entry.label)):
            if value is None:
                continue
            other = seen.setdefault((entry.table, what, value), spec.name)
            if other != spec.name:
                raise SpecError(f"{where}.{what}: {other!r} already has this {what} in table {entry.table!r} "
                                f"(got {value!r}); give each row of a table its own {what}")


def comparison_sections(results: Sequence) -> list[str]:
    """Markdown lines of every table with at least two rows among ``results`` (validation ``CaseResult``\\ s),
    without the ``timed`` columns."""
    lines: list[str] = []
    for table, rows in _tables(results):
        lines += render_table(table, rows)
    return lines


def comparison_timings(results: Sequence) -> list[str]:
    """The ``timed`` columns of the same tables (label, times, then the timing sentences), for the timings file."""
    lines: list[str] = []
    for table, rows in _tables(results):
        timed = [c for c in table.columns if c.timed]
        if not timed:
            continue
        lines += ["", f"## {table.title}", "", "| method | " + " | ".join(c.header for c in timed) + " |",
                  "|---|" + "---|" * len(timed)]
        lines += [f"| {row.label} | " + " | ".join(_cell(row.values[c.id], c.fmt) for c in timed) + " |"
                  for row in rows]
        if table.timing_notes is not None:
            lines += table.timing_notes(_roles(rows), rows)
    return lines


def _tables(results: Sequence) -> list[tuple[Table, list[Row]]]:
    """Each table with at least two rows among ``results``, its rows in role order."""
    rows: dict[str, list[Row]] = {}
    for r in results:
        entry = r.spec.reference.comparison if r.spec.reference is not None else None
        if entry is None or entry.table not in TABLES:
            continue
        figures = entry.figures or {}
        values = {c.id: (_figure(figures[c.id]) if c.id in figures else c.default)(r.solution)
                  for c in TABLES[entry.table].columns}
        rows.setdefault(entry.table, []).append(Row(entry.label, entry.role, r.solution, values))
    return [(table, sorted(rows[table_id], key=_role_order)) for table_id, table in TABLES.items()
            if len(rows.get(table_id, ())) >= 2]


ROLE_ORDER = ("baseline", "min_time", "min_energy", "tracked")
"""Rows of a table go in this order of their roles (rows without a role last, in problem order)."""


def _role_order(row: Row) -> int:
    return ROLE_ORDER.index(row.role) if row.role in ROLE_ORDER else len(ROLE_ORDER)


def _cell(value: float | None, fmt: str) -> str:
    return "n/a" if value is None else format(value, fmt)


def _roles(rows: list[Row]) -> dict[str, Row]:
    """The first row of each role."""
    roles: dict[str, Row] = {}
    for row in rows:
        if row.role is not None:
            roles.setdefault(row.role, row)
    return roles


def render_table(table: Table, rows: list[Row]) -> list[str]:
    """One table without its ``timed`` columns: heading, intro, one line per row (in the given order), the
    sentences of its roles."""
    columns = [c for c in table.columns if not c.timed]
    lines = ["", f"## {table.title}", ""]
    for paragraph in table.intro:
        lines += [paragraph, ""]
    lines += ["| method | " + " | ".join(c.header for c in columns) + " | verified |",
              "|---|" + "---|" * len(columns) + "---|"]
    for row in rows:
        cells = " | ".join(_cell(row.values[c.id], c.fmt) for c in columns)
        lines.append(f"| {row.label} | {cells} | {'yes' if row.solution.ok else 'NO'} |")
    return lines + table.notes(_roles(rows), rows)
