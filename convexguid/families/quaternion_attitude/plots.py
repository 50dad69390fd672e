r"""Plots of a ``quaternion_attitude`` solution, after Wang, Xu, Li (seed 003) Figs. 3-7.

* ``boresight_sky.png`` (Fig. 6): the inertial direction of each constrained body axis along the dense track
  on an equirectangular map of the celestial sphere (azimuth :math:`\operatorname{atan2}(y, x)`, elevation
  :math:`\arcsin z`, inertial frame), with every cone's boundary (keep-in dashed), the eigenaxis slew from
  the first to the last dense attitude (dotted grey) and start/end markers. Lines are split where the
  azimuth wraps at :math:`\pm 180` deg.
* ``boresight_sphere_3d.png`` (Fig. 7): the same on a wireframe unit sphere, keep-out cones also as faint surfaces.
* ``quaternion.png``, ``torques.png``, ``body_rates.png`` (Figs. 3-5): dense histories, node values as open
  circles, :math:`\pm` the bounds of the verification checks ``torque_Nm`` and ``rate_degps`` (per-axis
  torque bounds, checks ``torque_x_Nm``, ``torque_y_Nm``, ``torque_z_Nm``, each in its component's colour).
* ``cone_angles.png``: the dense ``keep_out_<name>_deg`` / ``keep_in_<name>_deg`` columns with each
  half-angle dashed in the same colour (and, dotted, the figure ``eigenaxis_min_angle_deg`` when present);
  ``forbidden_angles.png`` likewise for ``forbidden_<name>_deg`` columns and their verification bounds.

The body axis :math:`b` of a body-relative-to-inertial quaternion q points along
:math:`C_{BI}(q)^T b = C_{IB}(q)\,b` in inertial axes (``quat_rotate(quat_conjugate(q), b)``). The cone
geometry comes from the figure ``cones`` (a tuple of
:class:`~convexguid.families.quaternion_attitude.figures.ConeGeometry`, the numbers the summary JSON writes, so
the limits drawn are the summary's); without cones only the time histories and angle plots are drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import ArrayLike, NDArray  # noqa: E402

from convexguid.figure_files import Save, write_figure  # noqa: E402
from convexguid.geometry import eigenaxis_path  # noqa: E402
from convexguid.rotations import quat_conjugate, quat_rotate  # noqa: E402
from convexguid.solution import Solution  # noqa: E402
from convexguid.verification import TORQUE_AXIS_CHECKS  # noqa: E402

"""``save(fig, ax, title, ylabel, path)``: label a time-history axis, write the figure and close it."""

DEFAULT_BORESIGHT = np.array([0.0, 0.0, 1.0])
"""Body axis tracked on the sky when no keep-out cone names one."""
CONE_COLORS = ("C3", "C2", "C1", "C4", "C5", "C6", "C8", "C9")
"""Colour of the i-th cone, the same in every figure."""
TRACK_COLORS = ("k", "C0", "C7")
"""Colour of the planned path of the first, second, ... tracked body axis."""
EIGENAXIS_SAMPLES = 361
CIRCLE_SAMPLES = 361


@dataclass(frozen=True, eq=False)
class SkyCone:
    """A pointing cone: ``body_axis`` must stay outside (``keep_out``) or inside ``half_angle_deg`` of
    ``inertial_dir``; both directions are unit vectors."""

    name: str
    body_axis: NDArray
    inertial_dir: NDArray
    half_angle_deg: float
    keep_out: bool
    color: str

    @property
    def column(self) -> str:
        """Dense column with the angle between the body axis and the inertial direction, deg."""
        return f"{'keep_out' if self.keep_out else 'keep_in'}_{self.name}_deg"


@dataclass(frozen=True, eq=False)
class SkyTrack:
    """Inertial directions of one body axis along the planned track and along the eigenaxis slew, ``(n, 3)``."""

    label: str
    color: str
    planned: NDArray
    eigenaxis: NDArray


def _unit(v: ArrayLike) -> NDArray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def sky_cones(solution: Solution) -> list[SkyCone]:
    """Cones of the figure ``cones`` (empty list without figures), coloured by their position."""
    cones = solution.figures.cones if solution.figures is not None else ()
    return [SkyCone(str(c.name), _unit(c.body_axis), _unit(c.inertial_dir), float(c.half_angle_deg),
                    bool(c.keep_out), CONE_COLORS[i % len(CONE_COLORS)])
            for i, c in enumerate(cones)]


def inertial_axis(q: ArrayLike, body_axis: ArrayLike) -> NDArray:
    """Inertial components :math:`C_{BI}(q)^T b` of the body axis b for quaternions q (scalar-last, B rel. I)."""
    q = np.asarray(q, dtype=float)
    return quat_rotate(quat_conjugate(q), np.broadcast_to(_unit(body_axis), q.shape[:-1] + (3,)))


def az_el_deg(v: ArrayLike) -> tuple[NDArray, NDArray]:
    """Azimuth in (-180, 180] and elevation in [-90, 90] (deg) of inertial directions ``(..., 3)``."""
    v = _unit(v)
    az = np.degrees(np.arctan2(v[..., 1], v[..., 0]))
    el = np.degrees(np.arcsin(np.clip(v[..., 2], -1.0, 1.0)))
    return az, el


POLE_TOL_DEG = 1e-7
"""Points closer than this to a pole have no meaningful azimuth (see :func:`sky_coordinates`)."""


def sky_coordinates(points: ArrayLike) -> tuple[NDArray, NDArray]:
    """Azimuth and elevation (deg) of a sampled curve ``(n, 3)``; a point at a pole, whose azimuth is
    arbitrary, takes the azimuth of the nearest later (else earlier) point off the pole, so the curve does
    not run along the map's top or bottom edge."""
    az, el = az_el_deg(points)
    pole = 90.0 - np.abs(el) < POLE_TOL_DEG
    off = np.flatnonzero(~pole)
    if pole.any() and off.size:
        at = np.flatnonzero(pole)
        az[at] = az[off[np.minimum(np.searchsorted(off, at), off.size - 1)]]
    return az, el


def split_at_wrap(az: ArrayLike, el: ArrayLike) -> list[tuple[NDArray, NDArray]]:
    """Pieces of a sampled sky curve that do not jump across the map.

    Wherever consecutive azimuths differ by more than 180 deg the curve crossed the :math:`\\pm 180` deg
    meridian: the piece ends on that edge and the next one starts on the opposite edge, at the elevation
    interpolated linearly in the unwrapped azimuth.
    """
    az, el = np.asarray(az, dtype=float), np.asarray(el, dtype=float)
    pieces, start, head = [], 0, ([], [])
    for i in np.flatnonzero(np.abs(np.diff(az)) > 180.0):
        edge = 180.0 if az[i] > 0 else -180.0
        crossing = el[i] + (edge - az[i]) / (az[i + 1] + 2 * edge - az[i]) * (el[i + 1] - el[i])
        pieces.append((np.array([*head[0], *az[start:i + 1], edge]), np.array([*head[1], *el[start:i + 1], crossing])))
        start, head = i + 1, ([-edge], [crossing])
    pieces.append((np.array([*head[0], *az[start:]]), np.array([*head[1], *el[start:]])))
    return pieces


def cone_circle(direction: ArrayLike, half_angle_deg: float, n: int = CIRCLE_SAMPLES) -> NDArray:
    """``n`` unit vectors at ``half_angle_deg`` from ``direction``, a closed loop (first == last), ``(n, 3)``."""
    d = _unit(direction)
    e1 = _unit(np.cross(d, np.eye(3)[np.argmin(np.abs(d))]))
    e2 = np.cross(d, e1)
    phi = np.linspace(0.0, 2 * np.pi, n)[:, None]
    h = np.radians(half_angle_deg)
    return np.cos(h) * d + np.sin(h) * (np.cos(phi) * e1 + np.sin(phi) * e2)


def _axis_label(b: NDArray) -> str:
    """``+z`` for a coordinate axis, else the rounded components."""
    k = int(np.argmax(np.abs(b)))
    if np.isclose(abs(b[k]), 1.0):
        return f"{'+' if b[k] > 0 else '-'}{'xyz'[k]}"
    return "[" + ", ".join(f"{c:.2g}" for c in b) + "]"


def tracked_axes(cones: Sequence[SkyCone]) -> list[NDArray]:
    """Distinct body axes of the cones, the first keep-out cone's first (+z when there is none)."""
    ordered = sorted(cones, key=lambda c: not c.keep_out)
    axes: list[NDArray] = [ordered[0].body_axis if ordered and ordered[0].keep_out else DEFAULT_BORESIGHT]
    for cone in ordered:
        if not any(np.allclose(cone.body_axis, a) for a in axes):
            axes.append(cone.body_axis)
    return axes


def _dense_quaternions(solution: Solution) -> NDArray:
    return np.column_stack([solution.dense.columns[f"q{i}"] for i in (1, 2, 3, 4)])


def sky_tracks(solution: Solution, cones: Sequence[SkyCone]) -> list[SkyTrack]:
    """Planned and eigenaxis-slew directions of every tracked body axis (see :func:`tracked_axes`)."""
    q = _dense_quaternions(solution)
    slew = eigenaxis_path(q[0], q[-1], EIGENAXIS_SAMPLES)
    return [SkyTrack(f"body {_axis_label(b)}", TRACK_COLORS[j % len(TRACK_COLORS)], inertial_axis(q, b),
                     inertial_axis(slew, b))
            for j, b in enumerate(tracked_axes(cones))]


def _sky_curve(ax, points: NDArray, label: str | None = None, **style) -> None:
    """Plot unit vectors ``(n, 3)`` on the azimuth/elevation map, split at the azimuth wrap."""
    for k, (az, el) in enumerate(split_at_wrap(*sky_coordinates(points))):
        ax.plot(az, el, label=label if k == 0 else None, **style)


def _cone_style(cone: SkyCone) -> dict:
    return {"color": cone.color, "ls": "-" if cone.keep_out else "--", "lw": 1.2}


def _cone_text(cone: SkyCone) -> str:
    return cone.name if cone.keep_out else f"{cone.name} (keep-in)"


def _finish(fig, ax, title: str, path: Path) -> Path:
    """Title, legend, write and close a non-time-history figure."""
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="best", framealpha=0.85)
    fig.tight_layout()
    return write_figure(fig, path)


def _plot_sky(solution: Solution, cones: Sequence[SkyCone], tracks: Sequence[SkyTrack], path: Path) -> Path:
    """Equirectangular azimuth/elevation map of the paths and cones (Fig. 6)."""
    fig, ax = plt.subplots(figsize=(8.0, 4.6), dpi=120)
    for cone in cones:
        _sky_curve(ax, cone_circle(cone.inertial_dir, cone.half_angle_deg), **_cone_style(cone))
        az, el = az_el_deg(cone.inertial_dir)
        ax.text(np.clip(az, -160, 160), np.clip(el, -84, 84), _cone_text(cone), color=cone.color, ha="center",
                va="center", fontsize=8)
    for j, track in enumerate(tracks):
        _sky_curve(ax, track.eigenaxis, "eigenaxis slew" if j == 0 else None, color="0.55", ls=":", lw=1.4)
        _sky_curve(ax, track.planned, f"planned, {track.label}", color=track.color, lw=1.8)
        az, el = sky_coordinates(track.planned)
        ax.plot(az[0], el[0], "o", color=track.color, ms=6)
        ax.plot(az[-1], el[-1], "*", color=track.color, ms=8)
    ax.plot([], [], "ko", ms=6, label="start")
    ax.plot([], [], "k*", ms=8, label="end")
    ax.set(xlim=(-180, 180), ylim=(-90, 90), xticks=np.arange(-180, 181, 60), yticks=np.arange(-90, 91, 30),
           xlabel="inertial azimuth atan2(y, x) [deg]", ylabel="inertial elevation [deg]", aspect="equal")
    ax.grid(alpha=0.3)
    return _finish(fig, ax, f"{solution.problem}: pointing paths on the celestial sphere (Fig. 6; dashed: keep-in)",
                   path)


def _cone_surface(ax, cone: SkyCone) -> None:
    """Boundary circle and name of a cone; a keep-out cone also as a faint surface from the sphere centre."""
    rim = cone_circle(cone.inertial_dir, cone.half_angle_deg, 73)
    s = np.array([0.0, 1.0])[:, None]
    if cone.keep_out:
        ax.plot_surface(s * rim[:, 0], s * rim[:, 1], s * rim[:, 2], color=cone.color, alpha=0.15, lw=0)
    ax.plot(*rim.T, **_cone_style(cone))
    ax.text(*(1.12 * cone.inertial_dir), _cone_text(cone), color=cone.color, fontsize=8)


def _plot_sphere(solution: Solution, cones: Sequence[SkyCone], tracks: Sequence[SkyTrack], path: Path) -> Path:
    """Unit sphere with the cones and the paths (Fig. 7), viewed from the mean planned direction."""
    fig = plt.figure(figsize=(6.4, 6.0), dpi=120)
    ax = fig.add_subplot(projection="3d")
    lon, lat = np.meshgrid(np.linspace(-np.pi, np.pi, 25), np.linspace(-np.pi / 2, np.pi / 2, 13))
    ax.plot_wireframe(np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat), color="0.8", lw=0.4)
    for cone in cones:
        _cone_surface(ax, cone)
    for j, track in enumerate(tracks):
        ax.plot(*track.eigenaxis.T, color="0.55", ls=":", lw=1.4, label="eigenaxis slew" if j == 0 else None)
        ax.plot(*track.planned.T, color=track.color, lw=2.0, label=f"planned, {track.label}")
        ax.plot(*track.planned[0], "o", color=track.color, ms=6)
        ax.plot(*track.planned[-1], "*", color=track.color, ms=9)
    azim, elev = az_el_deg(np.mean(tracks[0].planned, axis=0))
    ax.view_init(elev=float(np.clip(elev, -60, 60)), azim=float(azim))
    ax.set(xlim=(-1, 1), ylim=(-1, 1), zlim=(-1, 1), xlabel="x_I", ylabel="y_I", zlabel="z_I")
    ax.set_box_aspect((1, 1, 1))
    ax.tick_params(labelsize=7)
    return _finish(fig, ax, f"{solution.problem}: pointing paths in 3-D (Fig. 7; o start, * end)", path)


def _check_bound(solution: Solution, name: str) -> float | None:
    """Bound of the verification check ``name`` (None without it)."""
    checks = {c.name: c for c in solution.verification.checks} if solution.verification else {}
    return checks[name].bound if name in checks else None


def _history(solution: Solution, stem: str, title: str, columns: Sequence[tuple[str, str]], ylabel: str,
             check: str | None, out_dir: Path, save: Save, axis_checks: Sequence[str] = ()) -> Path:
    """Dense components with node circles and symmetric ``check`` bound lines.

    ``axis_checks`` name one check per column (e.g. ``torque_x_Nm``, ...): those the verification has are
    drawn in place of ``check``, in the colour of the (first) column they bound, one line per distinct bound.
    """
    dense, nodes = solution.dense, solution.nodes
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    for k, (label, column) in enumerate(c for c in columns if c[1] in dense.columns):
        ax.plot(dense.t, dense.columns[column], color=f"C{k}", lw=1.3, label=label)
        if nodes is not None and column in nodes.columns:
            ax.plot(nodes.t, nodes.columns[column], "o", color=f"C{k}", mfc="none", ms=4)
    per_axis: dict[float, list[tuple[int, str]]] = {}  # bound -> the components sharing it
    for k, ((label, _), name) in enumerate(zip(columns, axis_checks, strict=False)):
        axis_bound = _check_bound(solution, name)
        if axis_bound is not None:
            per_axis.setdefault(axis_bound, []).append((k, label))
    for axis_bound, sharing in per_axis.items():
        color = f"C{sharing[0][0]}"
        ax.axhline(axis_bound, color=color, ls="--", lw=0.9, label=f"{', '.join(lb for _, lb in sharing)} limit")
        ax.axhline(-axis_bound, color=color, ls="--", lw=0.9)
    bound = _check_bound(solution, check) if check and not per_axis else None
    if bound is not None:
        ax.axhline(bound, color="r", ls="--", lw=0.9, label="limit")
        ax.axhline(-bound, color="r", ls="--", lw=0.9)
    note = " (circles: nodes)" if nodes is not None else ""
    return save(fig, ax, f"{solution.problem}: {title}{note}", ylabel, out_dir / f"{stem}.png")


@dataclass(frozen=True)
class AngleCurve:
    """A dense angle column with its limit and, optionally, its minimum along the eigenaxis slew (deg)."""

    label: str
    column: str
    color: str
    limit: float | None
    eigenaxis_min: float | None = None


def _angle_plot(solution: Solution, curves: Sequence[AngleCurve], stem: str, title: str, out_dir: Path,
                save: Save) -> Path:
    """Angle histories, each limit dashed (and eigenaxis minimum dotted) in the curve's colour."""
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    for curve in curves:
        ax.plot(solution.dense.t, solution.dense.columns[curve.column], color=curve.color, lw=1.3, label=curve.label)
        for value, style in ((curve.limit, "--"), (curve.eigenaxis_min, ":")):
            if value is not None:
                ax.axhline(value, color=curve.color, ls=style, lw=0.9)
    ax.plot([], [], "k--", lw=0.9, label="limit")
    if any(c.eigenaxis_min is not None for c in curves):
        ax.plot([], [], "k:", lw=0.9, label="min on eigenaxis slew")
    return save(fig, ax, f"{solution.problem}: {title}", "angle [deg]", out_dir / f"{stem}.png")


def cone_curves(solution: Solution, cones: Sequence[SkyCone]) -> list[AngleCurve]:
    """Curves of the dense ``keep_out_*`` / ``keep_in_*`` columns; limits from the cones, else from the checks."""
    known = {c.column: c for c in cones}
    eigen = (solution.figures.eigenaxis_min_angle_deg if solution.figures is not None else None) or {}
    curves = []
    for k, column in enumerate(c for c in solution.dense.columns if c.startswith(("keep_out_", "keep_in_"))):
        cone = known.get(column)
        kind, name = ("keep-out", column[9:-4]) if column.startswith("keep_out_") else ("keep-in", column[8:-4])
        curves.append(AngleCurve(f"{name} ({kind})", column, cone.color if cone else CONE_COLORS[k % len(CONE_COLORS)],
                                 cone.half_angle_deg if cone else _check_bound(solution, column), eigen.get(name)))
    return curves


def forbidden_curves(solution: Solution) -> list[AngleCurve]:
    """Curves of the dense ``forbidden_*`` columns with the bounds of their verification checks."""
    columns = [c for c in solution.dense.columns if c.startswith("forbidden_")]
    return [AngleCurve(column[10:-4], column, f"C{k}", _check_bound(solution, column))
            for k, column in enumerate(columns)]


def plot_quaternion_attitude(solution: Solution, out_dir: Path, save: Save) -> list[Path]:
    """Figures of a ``quaternion_attitude`` solution (Figs. 3-7 of Wang, Xu, Li); return their paths.

    Parameters
    ----------
    solution : Solution
        Dense columns ``q1..q4``, ``omega{i}_degps``, ``u{i}_Nm`` and the cone angle columns; optional nodes and
        figures (:class:`~convexguid.families.quaternion_attitude.figures.QuaternionAttitudeFigures`: ``cones``,
        ``eigenaxis_min_angle_deg``).
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
    cones = sky_cones(solution)
    paths = []
    if cones:
        tracks = sky_tracks(solution, cones)
        paths += [_plot_sky(solution, cones, tracks, out_dir / "boresight_sky.png"),
                  _plot_sphere(solution, cones, tracks, out_dir / "boresight_sphere_3d.png")]
    paths += [
        _history(solution, "quaternion", "attitude quaternion (Fig. 3)", [(f"q{i}", f"q{i}") for i in (1, 2, 3, 4)],
                 "quaternion [-]", None, out_dir, save),
        _history(solution, "torques", "control torques (Fig. 4)", [(f"u{i}", f"u{i}_Nm") for i in (1, 2, 3)],
                 "torque [N m]", "torque_Nm", out_dir, save, axis_checks=TORQUE_AXIS_CHECKS),
        _history(solution, "body_rates", "body rates (Fig. 5)", [(f"omega{i}", f"omega{i}_degps") for i in (1, 2, 3)],
                 "rate [deg/s]", "rate_degps", out_dir, save),
    ]
    for curves, stem, title in ((cone_curves(solution, cones), "cone_angles", "body axis to cone direction"),
                                (forbidden_curves(solution), "forbidden_angles", "Euler angle to forbidden attitudes")):
        if curves:
            paths.append(_angle_plot(solution, curves, stem, title, out_dir, save))
    return paths
