"""Plots of a ``flat_attitude`` solution: dense curves with the node values as circles (as in Cai et al. Figs. 1-3),
and one angle history per keep-out cone."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from convexguid.figure_files import Save  # noqa: E402
from convexguid.solution import Solution  # noqa: E402

"""``save(fig, ax, title, ylabel, path)``: label a time-history axis, write the figure and close it."""

PLOT_GROUPS: list[tuple[str, str, str, str]] = [
    # (file stem, title, "dense column|node column" template, y label)
    ("euler_angles", "Euler angles (3-2-1)", "{axis}_planned_deg|{axis}_deg", "angle [deg]"),
    ("body_rates", "Body rates", "omega{i}_degps|omega{i}_degps", "rate [deg/s]"),
    ("torques", "Control torques", "u{i}_Nm|u{i}_Nm", "torque [N m]"),
]

_AXES = ("roll", "pitch", "yaw")


def _series(template: str) -> list[tuple[str, str, str]]:
    """(label, dense column, node column) for the three components named by ``template``."""
    dense_t, node_t = template.split("|")
    out = []
    for i, axis in enumerate(_AXES, start=1):
        label = axis if "{axis}" in dense_t else f"{dense_t.split('{')[0]}{i}"
        out.append((label, dense_t.format(axis=axis, i=i), node_t.format(axis=axis, i=i)))
    return out


def plot_flat_attitude(solution: Solution, out_dir: Path, save: Save) -> list[Path]:
    """Write one PNG per plot group and per keep-out cone; return the paths."""
    paths = []
    for stem, title, template, ylabel in PLOT_GROUPS:
        fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
        for (label, dense_col, node_col), color in zip(_series(template), ("C0", "C1", "C2"), strict=True):
            if solution.dense is not None and dense_col in solution.dense.columns:
                ax.plot(solution.dense.t, solution.dense.columns[dense_col], color=color, label=label, lw=1.4)
            if solution.nodes is not None and node_col in solution.nodes.columns:
                ax.plot(solution.nodes.t, solution.nodes.columns[node_col], "o", color=color, mfc="none", ms=4)
        paths.append(save(fig, ax, f"{solution.problem}: {title} (circles: nodes)", ylabel,
                          out_dir / f"{stem}.png"))
    for name, values in (solution.dense.columns.items() if solution.dense else []):
        if name.startswith("keep_out_"):
            paths.append(_plot_keep_out(solution, name, values, out_dir, save))
    return paths


def _plot_keep_out(solution: Solution, column: str, values, out_dir: Path, save: Save) -> Path:
    fig, ax = plt.subplots(figsize=(6.4, 3.0), dpi=120)
    ax.plot(solution.dense.t, values, label="propagated")
    if solution.verification is not None:
        check = {c.name: c for c in solution.verification.checks}.get(column)
        if check is not None:
            ax.axhline(check.bound, color="r", ls="--", label="keep-out half-angle")
    return save(fig, ax, f"{solution.problem}: {column}", "angle [deg]", out_dir / f"{column}.png")
