"""Figure files: a labelled time history saved, a figure written atomically, a redrawn figure kept or replaced.

Every figure is written to a temporary file renamed into place, and a PNG carries no metadata that names the
matplotlib version or a date, so one drawing is one file's bytes. It carries instead the record of what it shows
(:class:`~convexguid.plot_record.PlotRecord`): a figure drawn again is written only when what it shows changed
beyond the tolerance (:func:`write_figure` leaves an agreeing file as it is, bytes and modification time;
:func:`keep_unchanged_pictures` puts an agreeing committed file back over a fresh one). A plot redrawn from data
that differ in their last bits may shade a few edge pixels differently, and its file would otherwise change
although nobody could see it.

The families' plot modules and the campaign report draw with these; matplotlib is imported when something is
drawn.
"""

from __future__ import annotations

import filecmp
import shutil
from collections.abc import Callable, Iterable
from pathlib import Path

from convexguid.outputs import atomic_file
from convexguid.plot_record import RECORD_KEY, PlotRecord

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
    suffix, e.g. ``.png``; ``dpi`` as for ``savefig``, the figure's own if None) and close it; return ``path``.

    A PNG carries its :class:`~convexguid.plot_record.PlotRecord` and no version; a PNG already at ``path`` whose
    record agrees is left as it is (same bytes, same modification time).
    """
    import matplotlib.pyplot as plt  # matplotlib only when something is drawn

    try:
        fmt = Path(path).suffix.lstrip(".") or "png"
        extra = {"dpi": dpi} if dpi else {}
        if fmt == "png":
            record = PlotRecord.of_figure(fig, dpi)
            previous = PlotRecord.of_file(path)
            if previous is not None and record.agrees(previous):
                return path
            extra["metadata"] = {"Software": None, RECORD_KEY: record.encode()}
        with atomic_file(path, "wb") as fh:
            fig.savefig(fh, format=fmt, **extra)
    finally:
        plt.close(fig)
    return path


def same_plot(first: Path, second: Path) -> bool:
    """The two figure files show the same: their plot records agree (:meth:`PlotRecord.agrees`), or, for files
    without one (not PNG), their bytes are equal. A PNG drawn before records existed is the same as nothing."""
    records = PlotRecord.of_file(first), PlotRecord.of_file(second)
    if None not in records:
        return records[0].agrees(records[1])
    return first.suffix != ".png" and filecmp.cmp(first, second, shallow=False)


def keep_unchanged_pictures(fresh: Iterable[Path], committed_folder: Path) -> None:
    """Put the committed file back (its bytes and modification time) over each fresh picture that shows the same
    (:func:`same_plot`)."""
    for path in fresh:
        committed = committed_folder / path.name
        if committed.is_file() and same_plot(path, committed):
            shutil.copy2(committed, path)
