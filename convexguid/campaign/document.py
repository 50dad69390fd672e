"""The campaign report: one markdown page beside the results table, with its plots.

What varies, the runs by status, the statistics of each figure by status (mean, standard deviation, quantiles),
for a grid the results at each grid point, the plots (:mod:`convexguid.campaign.plots`), and the runs that did not
converge and verify with the command that replays each. Nothing on the page depends on how long anything took
or on the order runs arrived in (wall times stay in the table), so running an unchanged campaign again rewrites
the same page.
"""

from __future__ import annotations

import os
import shlex
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from convexguid.bench_common import markdown_grid, one_line
from convexguid.campaign.definition import Campaign
from convexguid.campaign.plan import Run, yaml_text
from convexguid.campaign.plots import write_plots
from convexguid.campaign.table import TABLE_FILE, grid_points, is_ok, quantities
from convexguid.solution import write_text_atomic

REPORT_FILE = "report.md"
LISTED_FAILURES = 20
"""Runs listed under "Runs that did not converge and verify" (the table has them all)."""
LISTED_GRID_POINTS = 200
"""Grid points listed in the table of results by grid point."""


def number(value: float | None) -> str:
    """A table cell for a number (``-`` for none)."""
    return "-" if value is None or not np.isfinite(value) else f"{value:.6g}"


def display_path(path: str | Path) -> str:
    """``path`` relative to the working directory when it lies below it (as in the commands a user types)."""
    relative = os.path.relpath(path)
    return relative if not relative.startswith("..") else str(path)


def replay_command(campaign: Campaign, overrides: Sequence[str]) -> str:
    """The shell command that replays one run."""
    sets = " ".join(f"--set {shlex.quote(o)}" for o in overrides)
    return f"convexguid {campaign.command} {shlex.quote(display_path(campaign.problem_source))} {sets}".rstrip()


def write_report(campaign: Campaign, runs: Sequence[Run], rows: Sequence[dict[str, Any]], directory: Path) -> Path:
    """Write ``report.md`` and its plots into ``directory``; return the report's path."""
    plots = write_plots(campaign, runs, rows, directory)
    lines = [f"# Campaign {campaign.spec.name}", ""]
    if campaign.spec.description:
        lines += [" ".join(campaign.spec.description.split()), ""]
    lines += _setup(campaign, runs, rows)
    lines += _outcome(rows)
    lines += _statistics(campaign, rows)
    lines += _by_grid_point(campaign, rows)
    if plots:
        lines += ["## Plots", ""] + [f"![{title}]({path.name})\n" for title, path in plots]
    lines += _failures(campaign, rows)
    path = directory / REPORT_FILE
    write_text_atomic(path, "\n".join(lines).rstrip("\n") + "\n")
    return path


def _setup(campaign: Campaign, runs: Sequence[Run], rows: Sequence[dict[str, Any]]) -> list[str]:
    spec = campaign.spec
    lines = [f"- Campaign file: `{display_path(campaign.source)}`; problem file: "
             f"`{display_path(campaign.problem_source)}` (family `{campaign.family.name}`, replayed with "
             f"`convexguid {campaign.command}`)"]
    if spec.set:
        lines.append(f"- Every run: {', '.join(f'`{o}`' for o in spec.set)}")
    for axis in spec.grid:
        values = ", ".join(yaml_text(list(p) if len(p) > 1 else p[0]) for p in axis.points())
        lines.append(f"- Grid: `{', '.join(axis.names)}` = {values} ({len(axis.values)} values)")
    for d in spec.dispersions:
        if d.distribution == "normal":
            mean = d.mean if d.mean is not None else campaign.nominal[d.key]
            lines.append(f"- Dispersion: `{d.key}` ~ normal(mean {mean:g}, std {d.std:g})")
        else:
            lines.append(f"- Dispersion: `{d.key}` ~ uniform({d.low:g}, {d.high:g})")
    if spec.random:
        seeded = f"; `{spec.seed_key}` receives each sample's own seed" if spec.seed_key else ""
        lines.append(f"- Samples: {spec.samples} per grid point, campaign seed {spec.seed}{seeded}")
    lines.append(f"- Runs: {len(runs)}, of which {len(rows)} in the results table (`{TABLE_FILE}`)")
    return lines + [""]


def _outcome(rows: Sequence[dict[str, Any]]) -> list[str]:
    counts = Counter(row["status"] for row in rows)
    body = [[status, str(n), str(sum(r["verified"] is True for r in rows if r["status"] == status))]
            for status, n in sorted(counts.items(), key=lambda item: (-item[1], item[0]))]
    ok = sum(is_ok(row) for row in rows)
    return ["## Outcome", "", markdown_grid(["status", "runs", "verification passed"], [":---", "---:", "---:"],
                                             body), "", f"Converged and verified: {ok} of {len(rows)} runs.", ""]


def statistics(values: Sequence[float]) -> list[float | None]:
    """n, mean, standard deviation (n - 1), min, 5 %, median, 95 %, max of ``values``."""
    v = np.asarray(values, dtype=float)
    q = np.quantile(v, [0.0, 0.05, 0.5, 0.95, 1.0])
    std = float(v.std(ddof=1)) if v.size > 1 else None
    return [float(v.size), float(v.mean()), std, *map(float, q)]


def _statistics(campaign: Campaign, rows: Sequence[dict[str, Any]]) -> list[str]:
    body = []
    statuses = [s for s, _ in Counter(row["status"] for row in rows).most_common()]
    for name in quantities(campaign):
        for status in statuses:
            values = [r[name] for r in rows if r["status"] == status and r[name] is not None]
            if values:
                n, *rest = statistics(values)
                body.append([f"`{name}`", status, f"{n:.0f}", *map(number, rest)])
    if not body:
        return ["## Figures", "", "No run gave a value of any figure.", ""]
    columns = ["figure", "status", "runs", "mean", "std", "min", "5 %", "median", "95 %", "max"]
    return ["## Figures", "", "Over the runs of each status that give the figure (std with n - 1).", "",
            markdown_grid(columns, [":---", ":---"] + ["---:"] * 8, body), ""]


def _by_grid_point(campaign: Campaign, rows: Sequence[dict[str, Any]]) -> list[str]:
    spec = campaign.spec
    if not spec.grid:
        return []
    keys = [k for axis in spec.grid for k in axis.names]
    names = quantities(campaign)
    points = grid_points(campaign, rows)
    body = []
    for values, group in points[:LISTED_GRID_POINTS]:
        if spec.random:
            ok = [r for r in group if is_ok(r)]
            cells = [f"{len(ok)}/{len(group)}"] + [_mean_std([r[n] for r in ok if r[n] is not None]) for n in names]
        else:
            row = group[0]
            cells = [row["status"] + ("" if row["verified"] is not False else " (unverified)")]
            cells += [number(row[n]) for n in names]
        body.append([number(v) if isinstance(v, float) else str(v) for v in values] + cells)
    what = ("Converged and verified samples of each grid point, mean ± std" if spec.random
            else "One run per grid point")
    more = (f" The first {LISTED_GRID_POINTS} of {len(points)} grid points." if len(points) > LISTED_GRID_POINTS
            else "")
    columns = [f"`{k}`" for k in keys] + ["ok" if spec.random else "status"] + [f"`{n}`" for n in names]
    align = [":---" if isinstance(v, str) else "---:" for v in points[0][0]] + [":---"] + ["---:"] * len(names)
    return ["## By grid point", "", f"{what}.{more}", "", markdown_grid(columns, align, body), ""]


def _mean_std(values: Sequence[float]) -> str:
    if not values:
        return "-"
    mean = float(np.mean(values))
    return number(mean) if len(values) == 1 else f"{number(mean)} ± {number(float(np.std(values, ddof=1)))}"


def _failures(campaign: Campaign, rows: Sequence[dict[str, Any]]) -> list[str]:
    failed = [row for row in rows if not is_ok(row)]
    example = rows[0] if rows else None
    lines = ["## Replaying a run", "",
             "Every row of the table keeps its `--set` overrides (column `overrides`); with them the problem file "
             "gives that run again, e.g. run 0:", "", "```bash",
             replay_command(campaign, example["overrides"]) if example else "", "```", ""]
    if not failed:
        return lines
    body = [[str(r["run_id"]), r["status"], one_line(r["message"] or "", 120).replace("`", "'"),
             f"`{replay_command(campaign, r['overrides'])}`"] for r in failed[:LISTED_FAILURES]]
    more = f" (the first {LISTED_FAILURES} of {len(failed)})" if len(failed) > LISTED_FAILURES else ""
    return lines + ["## Runs that did not converge and verify", "",
                    f"{len(failed)} runs{more}:", "",
                    markdown_grid(["run", "status", "message", "replay"], ["---:", ":---", ":---", ":---"], body), ""]
