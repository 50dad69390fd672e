"""What a figure shows, as numbers with a tolerance: the record a PNG carries so that a figure drawn again replaces
its file only when what it shows changed beyond the tolerance.

The figure is drawn once more as SVG, with every data point (no path simplification), its generated ids numbered
in order of appearance, and no date or version: a list of everything drawn, in points (1/72 in) -- paths, marker
positions, texts, colours, line widths, the figure's size. The record keeps the digest of that drawing with the
numbers of its tags taken out (its *skeleton*: the structure, the styles and every text, tick labels included,
exactly), the resolution of the PNG, and the numbers themselves in steps of a quarter of the tolerance.

Two records agree when their skeletons are the same and every pair of numbers is within :data:`REL` (the
validation report's relative tolerance) of the figure's larger side, 0.05 pt on a 6.4 in figure, a twentieth
of a pixel at 120 dpi: the rule the report's lines follow (:mod:`convexguid.validation.reproduction`), the same
text once the numbers are taken out and every number within tolerance. A redrawing from data that differ in
their last bits agrees; a moved curve, a new point, a changed label, colour or line width does not.

matplotlib is imported by the caller (a figure exists); Pillow, which matplotlib writes PNG files with, reads the
record back.
"""

from __future__ import annotations

import base64
import hashlib
import io
import lzma
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from convexguid.validation.reproduction import REL

RECORD_KEY = "convexguid plot record"
"""Keyword of the PNG text chunk that holds the record."""

FORMAT = "convexguid-plot-record-1"
"""First word of an encoded record (a record of another format is no record)."""

STEPS_PER_TOLERANCE = 4
"""The numbers are stored in steps of the tolerance divided by this."""

LARGEST_STEP = 2**60
"""Numbers beyond this many steps (far off the figure) are stored as this many."""

_TAG = re.compile(r"<[^>]*>")
_NUMBER = re.compile(r"(?<![\w.#-])-?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
_GENERATED_ID = re.compile(r"\b[a-z][0-9a-f]{10}\b")  # matplotlib's clip-path and marker ids
_DRAWING_SETTINGS = {"path.simplify": False, "svg.fonttype": "none", "svg.hashsalt": "convexguid"}


@dataclass(frozen=True, eq=False)
class PlotRecord:
    """What a figure shows: ``skeleton`` (digest of the drawing without its numbers, and of the resolution),
    ``step`` (pt) and ``steps`` (the drawing's numbers, in steps)."""

    skeleton: str
    step: float
    steps: np.ndarray

    @classmethod
    def of_figure(cls, fig, dpi: float | None = None) -> PlotRecord:
        """The record of ``fig`` as it would be written at ``dpi`` (the figure's own if None)."""
        numbers: list[float] = []

        def take_numbers(tag: re.Match) -> str:
            return _NUMBER.sub(lambda number: numbers.append(float(number.group())) or "#", tag.group())

        skeleton = _TAG.sub(take_numbers, _drawing(fig)) + f"\ndpi {dpi or fig.dpi!r}"
        step = REL * 72.0 * float(max(fig.get_size_inches())) / STEPS_PER_TOLERANCE
        steps = np.clip(np.round(np.asarray(numbers, dtype=float) / step), -LARGEST_STEP, LARGEST_STEP)
        return cls(hashlib.sha256(skeleton.encode()).hexdigest(), step, steps.astype(np.int64))

    def agrees(self, other: PlotRecord) -> bool:
        """Same skeleton and every number within the tolerance (up to the rounding of each record to its steps)."""
        return (self.skeleton == other.skeleton and self.step == other.step
                and self.steps.shape == other.steps.shape
                and bool(np.all(np.abs(self.steps - other.steps) <= STEPS_PER_TOLERANCE + 1)))

    def encode(self) -> str:
        """One line of ASCII: the format, the skeleton digest, the step, and the steps (each minus the one two
        before it, as x and y alternate in a path; LZMA; base64)."""
        differences = self.steps.copy()
        differences[2:] -= self.steps[:-2]
        packed = base64.b64encode(lzma.compress(differences.astype("<i8").tobytes())).decode("ascii")
        return f"{FORMAT} {self.skeleton} {self.step!r} {packed}"

    @classmethod
    def decode(cls, text: str) -> PlotRecord | None:
        """The record :meth:`encode` wrote, or None for text that is not one."""
        parts = text.split(" ")
        if len(parts) != 4 or parts[0] != FORMAT:
            return None
        try:
            differences = np.frombuffer(lzma.decompress(base64.b64decode(parts[3], validate=True)), dtype="<i8")
            step = float(parts[2])
        except (ValueError, lzma.LZMAError):
            return None
        steps = differences.astype(np.int64)
        steps[0::2], steps[1::2] = np.cumsum(differences[0::2]), np.cumsum(differences[1::2])
        return cls(parts[1], step, steps)

    @classmethod
    def of_file(cls, path: str | Path) -> PlotRecord | None:
        """The record a PNG file carries, or None (no such file, not a PNG, drawn without a record)."""
        from PIL import Image

        try:
            with Image.open(path) as image:
                text = image.info.get(RECORD_KEY)
        except (OSError, ValueError, SyntaxError):
            return None
        return cls.decode(text) if isinstance(text, str) else None


def _drawing(fig) -> str:
    """``fig`` as SVG text with every data point, its generated ids numbered in order, and no date or version."""
    import matplotlib
    from matplotlib.lines import Line2D

    lines = fig.findobj(Line2D)
    buffer = io.StringIO()
    try:
        with matplotlib.rc_context(_DRAWING_SETTINGS):
            for line in lines:  # a line's path is simplified or not as the settings were when it was built
                line.recache(always=True)
            fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None})
    finally:
        for line in lines:  # rebuilt again under the settings the picture itself is drawn with
            line.recache(always=True)
    ids: dict[str, str] = {}
    return _GENERATED_ID.sub(lambda found: ids.setdefault(found.group(), f"id{len(ids)}"), buffer.getvalue())
