"""Whether a fresh validation report says what the committed one says, number by number.

Two machines that agree on every answer within its tolerance still print different last digits now and then
(a value of 85.32098 on one machine and 85.32102 on another prints as 85.321 on both, but 0.0811353 and
0.0811347 straddle a rounding boundary). So a report is compared as text whose numbers carry a tolerance:
two lines *agree* when they read the same once every number is taken out (their *skeletons*) and each pair of
numbers is within

.. math::

    |a - b| \\le \\mathrm{REL}\\,\\max(|a|, |b|) + \\mathrm{ABS} + (\\delta_a + \\delta_b)/2,

with :math:`\\delta` the resolution each number was printed at (one unit of its last digit; 0 for an
integer, which is a count and must match exactly up to the relative term). ``REL`` is the tolerance the
robustness benchmark holds a minimum-time objective to (1e-4 relative); ``ABS`` (1e-6, in the report's units:
s, deg, rad, m, N m) takes in round-off-sized values such as a final error of 3e-9 rad.

:func:`reconcile` keeps each committed line a fresh one agrees with and lists the lines that do not:
``convexguid validate`` writes the result (so an unchanged tree stays unchanged on any machine whose answers
are within tolerance), ``convexguid validate --check`` reports the list and writes nothing.
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass

REL = 1e-4
"""Relative agreement of two printed numbers (the minimum-time objective's reproduction tolerance)."""

ABS = 1e-6
"""Absolute agreement of two printed numbers, in the report's own units (round-off-sized values)."""

_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d+|\d+)(?:[eE][-+]?\d+)?(?!\w|\.\d)")


@dataclass(frozen=True)
class PrintedNumber:
    """A number as the report prints it: its value and the resolution its digits carry."""

    value: float
    resolution: float

    @classmethod
    def parse(cls, text: str) -> PrintedNumber:
        mantissa, _, exponent = text.lower().partition("e")
        decimals = len(mantissa.partition(".")[2]) if "." in mantissa else None
        if decimals is None and not exponent:
            return cls(float(text), 0.0)
        return cls(float(text), 10.0 ** (int(exponent or 0) - (decimals or 0)))

    def agrees(self, other: PrintedNumber) -> bool:
        if math.isnan(self.value) or math.isnan(other.value):
            return math.isnan(self.value) and math.isnan(other.value)
        allowed = REL * max(abs(self.value), abs(other.value)) + ABS + 0.5 * (self.resolution + other.resolution)
        return abs(self.value - other.value) <= allowed


def skeleton(line: str) -> str:
    """``line`` with every number replaced by ``#``."""
    return _NUMBER.sub("#", line)


def numbers(line: str) -> list[PrintedNumber]:
    """The numbers printed in ``line``, in order."""
    return [PrintedNumber.parse(m.group()) for m in _NUMBER.finditer(line)]


def lines_agree(committed: str, fresh: str) -> bool:
    """Same skeleton, and every number of one within tolerance of the other's (see the module docstring)."""
    if skeleton(committed) != skeleton(fresh):
        return False
    return all(a.agrees(b) for a, b in zip(numbers(committed), numbers(fresh), strict=True))


@dataclass(frozen=True)
class LineDifference:
    """A line of the committed report (``None`` if the fresh one adds it) and what the fresh report has there."""

    section: str
    committed: str | None
    fresh: str | None

    def describe(self) -> str:
        where = f"[{self.section}] " if self.section else ""
        if self.committed is None:
            return f"{where}added: {self.fresh}"
        if self.fresh is None:
            return f"{where}missing: {self.committed}"
        return f"{where}committed: {self.committed}\n    now:       {self.fresh}"


@dataclass(frozen=True)
class Reconciled:
    """The report to write (committed lines kept wherever the fresh ones agree) and the lines that do not."""

    text: str
    differences: tuple[LineDifference, ...]


def reconcile(committed: str | None, fresh: str) -> Reconciled:
    """Merge a fresh report into the committed one (``None``: there is none yet), line by line.

    Lines are paired by their skeletons (:class:`difflib.SequenceMatcher`); a pair that agrees keeps the
    committed line, anything else takes the fresh text and is listed as a difference under the ``## `` section
    it belongs to.
    """
    if committed is None:
        return Reconciled(fresh, ())
    old, new = committed.splitlines(), fresh.splitlines()
    matcher = difflib.SequenceMatcher(None, [skeleton(s) for s in old], [skeleton(s) for s in new], autojunk=False)
    out: list[str] = []
    differences: list[LineDifference] = []
    section = ""
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        if tag == "equal":
            for a, b in zip(old[i1:i2], new[j1:j2], strict=True):
                section = _section(b, section)
                if lines_agree(a, b):
                    out.append(a)
                else:
                    out.append(b)
                    differences.append(LineDifference(section, a, b))
            continue
        removed, added = old[i1:i2], new[j1:j2]
        for k in range(max(len(removed), len(added))):
            a = removed[k] if k < len(removed) else None
            b = added[k] if k < len(added) else None
            section = _section(b or "", section)
            differences.append(LineDifference(section, a, b))
        out += added
    text = "\n".join(out) + ("\n" if fresh.endswith("\n") else "")
    return Reconciled(text, tuple(differences))


def _section(line: str, current: str) -> str:
    return line[3:].strip() if line.startswith("## ") else current
