"""Figures of an ``lpmpc`` simulation, after Feng, Chen, Yang (2018) Figs. 2-8.

Figs. 2-4: Euler angles, body rates and torques of the nominal and of every law in the single case;
Figs. 5-6: the Monte Carlo envelopes (least and largest over the runs) of LPMPC and LQR tracking;
Fig. 7: their terminal errors run by run; Fig. 8: their energies run by run.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from convexguid.figure_files import Save  # noqa: E402
from convexguid.solution import Solution  # noqa: E402

AXES = ("roll", "pitch", "yaw")


def _laws(solution: Solution) -> list[str]:
    return ["nominal"] + [run.controller for run in solution.figures.runs]


def _histories(solution: Solution, out_dir: Path, save: Save, stem: str, title: str, ylabel: str,
               column: Callable[[str, int], str]) -> Path:
    dense = solution.dense
    fig, axes = plt.subplots(3, 1, figsize=(6.4, 7.2), dpi=120, sharex=True)
    for i, ax in enumerate(axes):
        for law in _laws(solution):
            style = {"color": "k", "ls": "--", "lw": 1.0} if law == "nominal" else {"lw": 1.1}
            ax.plot(dense.t, dense.columns[column(law, i)], label=law, **style)
        ax.set_ylabel(column("", i).lstrip("_"), fontsize=8)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    return save(fig, axes[-1], f"{solution.problem}: {title}", ylabel, out_dir / f"{stem}.png")


def _envelopes(solution: Solution, out_dir: Path, save: Save, stem: str, title: str, ylabel: str,
               column: Callable[[str, int], str]) -> Path:
    dense = solution.dense
    fig, axes = plt.subplots(3, 1, figsize=(6.4, 7.2), dpi=120, sharex=True)
    for i, ax in enumerate(axes):
        for key, color in (("lpmpc", "C0"), ("lqr", "C3")):
            name = column(f"mc_{key}", i)
            ax.fill_between(dense.t, dense.columns[name + "_min"], dense.columns[name + "_max"], color=color,
                            alpha=0.3, label=f"{key} (min-max over runs)")
        ax.plot(dense.t, dense.columns[column("nominal", i)], "k--", lw=1.0, label="nominal")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    return save(fig, axes[-1], f"{solution.problem}: {title}", ylabel, out_dir / f"{stem}.png")


def _angle(law: str, i: int) -> str:
    return f"{law}_{AXES[i]}_deg"


def _rate(law: str, i: int) -> str:
    return f"{law}_omega{i + 1}_degps"


def _torque(law: str, i: int) -> str:
    return f"{law}_u{i + 1}_Nm"


def plot_lpmpc(solution: Solution, out_dir: Path, save: Save) -> list[Path]:
    """Write the figures the solution has data for; return their paths."""
    if solution.dense is None or solution.figures is None or not solution.figures.runs:
        return []
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = [_histories(solution, out_dir, save, "euler_angles", "3-2-1 Euler angles (Fig. 2)", "angle [deg]",
                        _angle),
             _histories(solution, out_dir, save, "body_rates", "body rates (Fig. 3)", "rate [deg/s]", _rate),
             _histories(solution, out_dir, save, "torques", "applied torques (Fig. 4)", "torque [N m]", _torque)]
    mc = solution.figures.monte_carlo
    if mc is None:
        return paths
    paths += [_envelopes(solution, out_dir, save, "mc_euler_angles", "Monte Carlo angles (Fig. 5)", "angle [deg]",
                         _angle),
              _envelopes(solution, out_dir, save, "mc_body_rates", "Monte Carlo rates (Fig. 6)", "rate [deg/s]",
                         _rate)]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    for key, color in (("lpmpc", "C0"), ("lqr", "C3")):
        angle = [r[f"{key}_angle_error_deg"] for r in mc.per_run]
        ax.scatter(angle, [r[f"{key}_rate_error_degps"] for r in mc.per_run], s=8, color=color, label=key)
    ax.set_xscale("log")
    ax.set_yscale("log")
    paths.append(save(fig, ax, f"{solution.problem}: terminal errors run by run (Fig. 7)", "final rate error [deg/s]",
                      out_dir / "mc_terminal_scatter.png", xlabel="final attitude error [deg]"))
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    runs = range(1, len(mc.per_run) + 1)
    ax.plot(runs, [r["lqr_energy_N2m2s"] for r in mc.per_run], ".", color="C3", label="LQR tracking")
    ax.plot(runs, [r["lpmpc_energy_N2m2s"] for r in mc.per_run], ".", color="C0", label="LPMPC")
    paths.append(save(fig, ax, f"{solution.problem}: energy run by run (Fig. 8)", "energy [N^2 m^2 s]",
                      out_dir / "mc_energy.png", xlabel="Monte Carlo run"))
    return paths
