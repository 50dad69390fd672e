"""Plots of a solution: its family's own figures (:attr:`convexguid.families.base.Family.plot`), drawn with the
shared writer :func:`convexguid.figure_files.save_figure`.
"""

from __future__ import annotations

from pathlib import Path

from convexguid.families import get_family
from convexguid.figure_files import save_figure
from convexguid.solution import Solution


def plot_solution(solution: Solution, out_dir: Path) -> list[Path]:
    """Write the PNG figures of the solution's family into ``out_dir`` (created if missing); return the paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    return get_family(solution.family).plot(solution, out_dir, save_figure)
