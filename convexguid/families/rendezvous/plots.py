"""Rendezvous plots: position and velocity histories with node markers (Wang & Tang Figs. 3-4),
the trajectory in the orbit plane, and the thrust profile."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from convexguid.families.rendezvous.case import AXES  # noqa: E402
from convexguid.figure_files import write_figure  # noqa: E402
from convexguid.solution import Solution  # noqa: E402


def _components(solution: Solution, template: str) -> list[tuple[str, str]]:
    cols = solution.dense.columns
    return [(axis, template.format(axis=axis)) for axis in AXES if template.format(axis=axis) in cols]


def _history(solution: Solution, template: str, title: str, ylabel: str, path: Path, save) -> Path:
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    components = _components(solution, template)
    for (axis, col), color in zip(components, ("C0", "C1", "C2")[: len(components)], strict=True):
        ax.plot(solution.dense.t, solution.dense.columns[col], color=color, lw=1.4, label=axis)
        if solution.nodes is not None and col in solution.nodes.columns and solution.method == "scp_arcs":
            ax.plot(solution.nodes.t, solution.nodes.columns[col], "o", color=color, mfc="none", ms=4)
    note = " (circles: nodes)" if solution.method == "scp_arcs" else ""
    return save(fig, ax, f"{solution.problem}: {title}{note}", ylabel, path)


def plot_rendezvous(solution: Solution, out_dir: Path, save) -> list[Path]:
    """Figures of a ``rendezvous`` solution; ``save`` labels, writes and closes a time-history figure."""
    if solution.dense is None or "x_m" not in solution.dense.columns:
        return []
    paths = [_history(solution, "{axis}_m", "relative position (Fig. 3)", "position [m]",
                      out_dir / "position.png", save),
             _history(solution, "v{axis}_mps", "relative velocity (Fig. 4)", "velocity [m/s]",
                      out_dir / "velocity.png", save)]
    cols = solution.dense.columns
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    ax.plot(solution.dense.t, cols["thrust_accel_mps2"], color="k", lw=1.2, label="|a u|")
    ax2 = ax.twinx()
    angle = np.degrees(np.arctan2(cols["uy"], cols["ux"]))
    burning = cols["thrust_accel_mps2"] > 0
    ax2.plot(solution.dense.t[burning], angle[burning], ".", color="C3", ms=2, label="in-plane direction")
    ax2.set_ylabel("atan2(u_y, u_x) [deg]", color="C3")
    paths.append(save(fig, ax, f"{solution.problem}: thrust profile", "thrust acceleration [m/s^2]",
                      out_dir / "thrust.png"))
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    burn = cols["thrust_accel_mps2"] > 0
    ax.plot(cols["x_m"], cols["y_m"], color="0.6", lw=1.0, label="coast")
    ax.plot(np.where(burn, cols["x_m"], np.nan), np.where(burn, cols["y_m"], np.nan), color="C3", lw=2.0,
            label="burn")
    ax.plot(cols["x_m"][0], cols["y_m"][0], "ks", label="start")
    ax.plot(0, 0, "k*", ms=10, label="target")
    ax.set_xlabel("x (opposite to orbital velocity) [m]")
    ax.set_ylabel("y (radial, up) [m]")
    ax.set_title(f"{solution.problem}: trajectory in the orbit plane", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths.append(write_figure(fig, out_dir / "trajectory_xy.png"))
    return paths
