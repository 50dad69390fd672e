"""Plots of a campaign report (PNG, matplotlib imported when called).

- Sweep: each quantity against the first numeric grid key, one line per value of the other grid axes; with
  samples, the mean with a one-standard-deviation bar over the converged and verified samples, each sample a
  faint dot. A run that did not converge and verify is a marker on the bottom edge at its grid value, one marker
  per status, so the boundary of feasibility is visible where the curve ends.
- Monte Carlo (no grid): a histogram of each quantity over the converged and verified runs, and each quantity
  against each dispersed key (failures again on the bottom edge).

Figures are built with :class:`matplotlib.figure.Figure` (no pyplot state, no display needed).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from convexguid.campaign.definition import Campaign
from convexguid.campaign.plan import Run
from convexguid.campaign.table import grid_points, is_ok, numeric_keys, quantities
from convexguid.figure_files import write_figure

MAX_SERIES = 8
"""Lines per sweep plot at most (further combinations of the other grid keys are left out)."""
MAX_PANELS = 6
"""Quantities (rows) and dispersed keys (columns) per Monte Carlo figure at most."""
FAILURE_MARKERS = {"infeasible": "x", "unverified": "v", "max_iterations": "s", "solver_error": "D", "error": "X"}


def write_plots(campaign: Campaign, runs: Sequence[Run], rows: Sequence[dict[str, Any]], directory: Path
                ) -> list[tuple[str, Path]]:
    """Write the plots that apply into ``directory``; return their (title, path) pairs."""
    numeric = [k for axis in campaign.spec.grid for k in axis.names if k in numeric_keys(runs, axis.names)]
    plots: list[tuple[str, Path]] = []
    if numeric:
        plots += [_sweep(campaign, rows, numeric[0], name, directory) for name in quantities(campaign)
                  if any(r[name] is not None for r in rows)]
    if campaign.spec.random and not campaign.spec.grid:
        plots.append(_histograms(campaign, rows, directory))
        if campaign.spec.dispersions:
            plots.append(_scatter(campaign, rows, directory))
    return plots


def _file_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", text).strip("_")


def _mark_failures(ax, rows: Sequence[dict[str, Any]], x_key: str, labelled: set[str]) -> None:
    """A marker on the bottom edge at the x of each run that did not converge and verify, one per status."""
    transform = ax.get_xaxis_transform()
    for row in rows:
        if is_ok(row) or row[x_key] is None:
            continue
        status = row["status"] if row["status"] != "converged" else "unverified"
        label = None if status in labelled else status
        labelled.add(status)
        ax.plot([row[x_key]], [0.03], FAILURE_MARKERS.get(status, "+"), color="tab:red", transform=transform,
                clip_on=False, label=label, markersize=7)


def _sweep(campaign: Campaign, rows: Sequence[dict[str, Any]], x_key: str, name: str, directory: Path
           ) -> tuple[str, Path]:
    from matplotlib.figure import Figure  # matplotlib only when the report is drawn

    others = [k for axis in campaign.spec.grid if x_key not in axis.names for k in axis.names]
    series: dict[tuple, list[dict[str, Any]]] = {}
    for row in rows:
        series.setdefault(tuple(row[k] for k in others), []).append(row)
    fig = Figure(figsize=(7, 4.2))
    ax = fig.subplots()
    labelled: set[str] = set()
    for values, group in list(series.items())[:MAX_SERIES]:
        label = ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}" for k, v in zip(others, values,
                                                                                               strict=True))
        _sweep_line(ax, campaign, group, x_key, name, label or None)
        _mark_failures(ax, group, x_key, labelled)
    ax.set_xlabel(x_key)
    ax.set_ylabel(name)
    ax.set_title(f"{campaign.spec.name}: {name} against {x_key}", fontsize=9)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    fig.tight_layout()
    path = directory / f"sweep_{_file_name(name)}.png"
    write_figure(fig, path, dpi=110)
    return f"{name} against {x_key}", path


def _sweep_line(ax, campaign: Campaign, rows: Sequence[dict[str, Any]], x_key: str, name: str,
                label: str | None) -> None:
    """The converged-and-verified values of ``name`` along ``x_key``: a line, or with samples means and bars."""
    ok = [r for r in rows if is_ok(r) and r[name] is not None and r[x_key] is not None]
    if not campaign.spec.random:
        ok.sort(key=lambda r: r[x_key])
        ax.plot([r[x_key] for r in ok], [r[name] for r in ok], "o-", markersize=4, label=label)
        return
    points = grid_points(campaign, ok)
    x = np.array([group[0][x_key] for _, group in points])
    y = [np.array([r[name] for r in group]) for _, group in points]
    order = np.argsort(x)
    mean = np.array([v.mean() for v in y])[order]
    std = np.array([v.std(ddof=1) if v.size > 1 else 0.0 for v in y])[order]
    line = ax.errorbar(x[order], mean, yerr=std, fmt="o-", markersize=4, capsize=3, label=label)
    for xi, values in zip(x, y, strict=True):
        ax.plot(np.full(values.size, xi), values, ".", color=line[0].get_color(), alpha=0.25, markersize=3)


def _histograms(campaign: Campaign, rows: Sequence[dict[str, Any]], directory: Path) -> tuple[str, Path]:
    from matplotlib.figure import Figure  # matplotlib only when the report is drawn

    names = [n for n in quantities(campaign) if any(r[n] is not None for r in rows)][: 2 * MAX_PANELS]
    columns = min(3, max(1, len(names)))
    fig = Figure(figsize=(4 * columns, 3.2 * -(-max(1, len(names)) // columns)))
    axes = np.atleast_1d(fig.subplots(-(-max(1, len(names)) // columns), columns)).ravel()
    for ax, name in zip(axes, names, strict=False):
        values = [r[name] for r in rows if is_ok(r) and r[name] is not None]
        ax.hist(values, bins="auto", color="tab:blue", alpha=0.8)
        ax.set_xlabel(name, fontsize=8)
        ax.set_ylabel("runs", fontsize=8)
        ax.set_title(f"{len(values)} converged and verified of {len(rows)}", fontsize=8)
        ax.grid(alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    fig.suptitle(f"{campaign.spec.name}: histograms", fontsize=10)
    fig.tight_layout()
    path = directory / "histograms.png"
    write_figure(fig, path, dpi=100)
    return "histograms", path


def _scatter(campaign: Campaign, rows: Sequence[dict[str, Any]], directory: Path) -> tuple[str, Path]:
    from matplotlib.figure import Figure  # matplotlib only when the report is drawn

    names = [n for n in quantities(campaign) if any(r[n] is not None for r in rows)][:MAX_PANELS]
    keys = [d.key for d in campaign.spec.dispersions][:MAX_PANELS]
    fig = Figure(figsize=(2.9 * len(keys) + 0.6, 2.4 * max(1, len(names)) + 0.6))
    axes = np.atleast_2d(fig.subplots(max(1, len(names)), len(keys), squeeze=False))
    labelled: set[str] = set()
    for i, name in enumerate(names):
        for j, key in enumerate(keys):
            ax = axes[i, j]
            ok = [r for r in rows if is_ok(r) and r[name] is not None]
            ax.plot([r[key] for r in ok], [r[name] for r in ok], ".", markersize=3, color="tab:blue")
            _mark_failures(ax, rows, key, labelled)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            if i == len(names) - 1:
                ax.set_xlabel(key, fontsize=7)
            if j == 0:
                ax.set_ylabel(name, fontsize=7)
    if axes[0, 0].get_legend_handles_labels()[0]:
        axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"{campaign.spec.name}: figures against the dispersed values", fontsize=10)
    fig.tight_layout()
    path = directory / "scatter.png"
    write_figure(fig, path, dpi=100)
    return "figures against the dispersed values", path
