"""Plots of a solution: the family's own figures (:attr:`convexguid.families.base.Family.plot`), and the
labelling and saving helpers they share (every figure is written atomically: a temporary file renamed into
place).

matplotlib is imported only by the families' plot modules, when something is plotted.
"""

from __future__ import annotations

from pathlib import Path

from convexguid.families import get_family
from convexguid.outputs import atomic_file
from convexguid.solution import Solution


def plot_solution(solution: Solution, out_dir: Path) -> list[Path]:
    """Write the PNG figures of the solution's family into ``out_dir`` (created if missing); return the paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    return get_family(solution.family).plot(solution, out_dir, save_figure)


def save_figure(fig, ax, title: str, ylabel: str, path: Path, xlabel: str = "time [s]") -> Path:
    """Label an axis (a time history unless ``xlabel`` says otherwise), write the figure to ``path``, close it."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return write_figure(fig, path)


def write_figure(fig, path: Path, dpi: float | None = None) -> Path:
    """Write ``fig`` to ``path`` atomically (:func:`~convexguid.outputs.atomic_file`; the format from the
    suffix, e.g. ``.png``; ``dpi`` as for ``savefig``, the figure's own if None) and close it; return ``path``."""
    import matplotlib.pyplot as plt

    try:
        with atomic_file(path, "wb") as fh:
            fig.savefig(fh, format=Path(path).suffix.lstrip(".") or "png", **({"dpi": dpi} if dpi else {}))
    finally:
        plt.close(fig)
    return path
