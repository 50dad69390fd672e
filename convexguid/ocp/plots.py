"""Plots of a user's problem: each state and each control against time, on the dense re-propagation (lines) and
at the nodes (markers)."""

from __future__ import annotations

from pathlib import Path

from convexguid.figure_files import save_figure
from convexguid.solution import Solution


def plot_ocp(solution: Solution, out_dir: Path) -> list[Path]:
    """``states.png`` and ``controls.png`` (one axis each, every variable in its own units) in ``out_dir``."""
    import matplotlib.pyplot as plt  # matplotlib only when something is drawn

    out_dir.mkdir(parents=True, exist_ok=True)
    nodes, dense = solution.nodes, solution.dense
    paths = []
    for title, names in (("states", solution.figures.states), ("controls", solution.figures.controls)):
        if not names:
            continue
        fig, ax = plt.subplots(figsize=(7, 4))
        units = solution.figures.units or {}
        for name in names:
            label = f"{name} [{units[name]}]" if name in units else name
            line = ax.plot(dense.t, dense.columns[name], label=label)[0] if dense is not None else None
            ax.plot(nodes.t, nodes.columns[name], "o", ms=3, color=line.get_color() if line else None,
                    label=None if line else label)
        paths.append(save_figure(fig, ax, f"{solution.problem}: {title} (lines: dense re-propagation, dots: nodes)",
                                 "value (each in its own unit)", out_dir / f"{title}.png"))
    return paths
