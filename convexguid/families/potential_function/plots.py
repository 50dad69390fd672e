"""Plots of a ``potential_function`` simulation, after Guo, Li, Ma (2011) Figs. 2-5.

Time histories of the quaternion, the body rate, the control torque and the Euler-axis angle
:math:`\\theta_b` to the forbidden attitude (with the limit :math:`\\theta_m`), the attitude error on a log
scale (with the 1 deg and 0.1 deg bands of the maneuver times) and, for a sweep, the family of
:math:`\\theta_b` curves of Fig. 4.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from convexguid.families.potential_function.runner import sweep_column  # noqa: E402
from convexguid.figure_files import Save  # noqa: E402
from convexguid.solution import Solution  # noqa: E402

"""``save(fig, ax, title, ylabel, path)``: label a time-history axis, write the figure and close it."""


def _bound(solution: Solution, name: str) -> float | None:
    """Bound of the verification check ``name`` (None without it)."""
    checks = {c.name: c for c in solution.verification.checks} if solution.verification else {}
    return checks[name].bound if name in checks else None


def _components(solution: Solution, stem: str, title: str, columns: list[tuple[str, str]], ylabel: str,
                limit: str | None, out_dir: Path, save: Save) -> Path:
    """One figure with several columns of the dense trajectory and optional symmetric limit lines."""
    dense = solution.dense
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    for label, column in columns:
        ax.plot(dense.t, dense.columns[column], lw=1.3, label=label)
    bound = _bound(solution, limit) if limit is not None else None
    if bound is not None:
        ax.axhline(bound, color="r", ls="--", lw=0.9, label="limit")
        ax.axhline(-bound, color="r", ls="--", lw=0.9)
    return save(fig, ax, f"{solution.problem}: {title}", ylabel, out_dir / f"{stem}.png")


def _theta_b(solution: Solution, out_dir: Path, save: Save) -> Path:
    dense = solution.dense
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    ax.plot(dense.t, dense.columns["theta_b_deg"], color="C0", lw=1.3, label="theta_b")
    ax.axhline(solution.figures.theta_m_deg, color="r", ls="--", lw=0.9, label="theta_m")
    return save(fig, ax, f"{solution.problem}: angle to the forbidden attitude", "theta_b [deg]",
                out_dir / "theta_b.png")


def _attitude_error(solution: Solution, out_dir: Path, save: Save) -> Path:
    dense = solution.dense
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    ax.semilogy(dense.t, np.maximum(dense.columns["theta_e_deg"], 1e-6), color="C0", lw=1.3, label="theta_e")
    for band, style in ((1.0, "--"), (0.1, ":")):
        ax.axhline(band, color="0.4", ls=style, lw=0.9, label=f"{band:g} deg")
    return save(fig, ax, f"{solution.problem}: attitude error to the command", "theta_e [deg]",
                out_dir / "attitude_error.png")


def _sweep(solution: Solution, out_dir: Path, save: Save) -> Path:
    dense = solution.dense
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    cases = solution.figures.sweep
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(cases)))
    for case, color in zip(cases, colors, strict=True):
        theta_m = case.theta_m_deg
        ax.plot(dense.t, dense.columns[sweep_column(theta_m)], color=color, lw=1.2, label=f"theta_m = {theta_m:g}")
        ax.axhline(theta_m, color=color, ls="--", lw=0.7)
    return save(fig, ax, f"{solution.problem}: theta_b for each theta_m (dashed: theta_m)", "theta_b [deg]",
                out_dir / "theta_b_sweep.png")


def plot_potential_function(solution: Solution, out_dir: Path, save: Save) -> list[Path]:
    """Figures of a ``potential_function`` solution (Figs. 2-5 of the paper); return their paths.

    Parameters
    ----------
    solution : Solution
        Result of :func:`convexguid.families.potential_function.runner.simulate_problem` (its figures a
        :class:`~convexguid.families.potential_function.figures.PotentialFunctionFigures`).
    out_dir : Path
        Directory for the PNG files.
    save : callable
        ``save(fig, ax, title, ylabel, path)`` labels a time-history axis, writes the figure and closes it.

    Returns
    -------
    list of Path
    """
    if solution.dense is None or "q1" not in solution.dense.columns:
        return []
    paths = [
        _components(solution, "quaternion", "attitude quaternion", [(f"q{i}", f"q{i}") for i in (1, 2, 3, 4)],
                    "quaternion [-]", None, out_dir, save),
        _components(solution, "body_rates", "body rates", [(f"omega{i}", f"omega{i}_degps") for i in (1, 2, 3)],
                    "rate [deg/s]", "rate_degps", out_dir, save),
        _components(solution, "torques", "control torques", [(f"u{i}", f"u{i}_Nm") for i in (1, 2, 3)],
                    "torque [N m]", "torque_Nm", out_dir, save),
        _attitude_error(solution, out_dir, save),
    ]
    if "theta_b_deg" in solution.dense.columns:
        paths.append(_theta_b(solution, out_dir, save))
    if solution.figures is not None and solution.figures.sweep:
        paths.append(_sweep(solution, out_dir, save))
    return paths
