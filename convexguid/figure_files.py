"""Figure files: a labelled time history saved, a figure written atomically, two pictures compared.

Every figure is written to a temporary file renamed into place, and a PNG carries no metadata that names the
matplotlib version, so one picture is one file's bytes. A report's pictures are replaced only when what they show
changed (:func:`keep_unchanged_pictures`): a plot redrawn from data that differ in their last bits may shade a
few edge pixels differently, and its file then changes although nobody could see it.

The families' plot modules and the campaign report draw with these; matplotlib is imported when something is
drawn.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from convexguid.outputs import atomic_file

Save = Callable[..., Path]
"""The figure writer a family's ``plot`` hook is handed: ``save(fig, ax, title, ylabel, path)``, :func:`save_figure`."""


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
    import matplotlib.pyplot as plt  # matplotlib only when something is drawn

    try:
        with atomic_file(path, "wb") as fh:
            fmt = Path(path).suffix.lstrip(".") or "png"
            fixed = {"metadata": {"Software": None}} if fmt == "png" else {}
            fig.savefig(fh, format=fmt, **({"dpi": dpi} if dpi else {}), **fixed)
    finally:
        plt.close(fig)
    return path


PIXEL_LEVEL = 0.1
"""A pixel differs when one of its channels moved by more than this (on the 0-1 scale)."""

PIXEL_SHARE = 1e-3
"""Two pictures are the same when at most this share of their pixels differ (anti-aliasing at line edges)."""


def same_picture(first: Path, second: Path) -> bool:
    """The two image files show the same picture: equal size, and at most :data:`PIXEL_SHARE` of the pixels
    differing by more than :data:`PIXEL_LEVEL`."""
    import matplotlib.image as mpimg  # matplotlib only when pictures are compared

    a, b = mpimg.imread(first), mpimg.imread(second)
    if a.shape != b.shape:
        return False
    differing = np.abs(a.astype(float) - b.astype(float)) > PIXEL_LEVEL
    if differing.ndim == 3:
        differing = differing.any(axis=-1)
    return float(differing.mean()) <= PIXEL_SHARE


def keep_unchanged_pictures(fresh: Iterable[Path], committed_folder: Path) -> None:
    """Put back the committed file over each fresh picture that :func:`same_picture` finds unchanged."""
    for path in fresh:
        committed = committed_folder / path.name
        if committed.is_file() and same_picture(path, committed):
            shutil.copyfile(committed, path)
