"""Progress of a running campaign: the counts a callback receives, and the line the command prints on stderr."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from typing import TextIO

from convexguid.progress import HEARTBEAT_S, display_mode


@dataclass(frozen=True)
class Progress:
    """Where a campaign stands after a run arrived (or before the first).

    ``done`` counts every row in the table, runs of earlier sessions included (``resumed`` of them);
    ``failures`` the rows that are not converged and verified; ``elapsed_s`` the time since this session started.
    """

    total: int
    done: int
    failures: int
    resumed: int
    elapsed_s: float

    @property
    def eta_s(self) -> float | None:
        """Seconds left at this session's pace so far (None before its first run)."""
        ran = self.done - self.resumed
        return self.elapsed_s / ran * (self.total - self.done) if ran > 0 else None


def duration_text(seconds: float | None) -> str:
    """``1 h 02 min``, ``3 min 05 s``, ``12 s``; ``?`` if unknown."""
    if seconds is None:
        return "?"
    s = round(seconds)
    if s >= 3600:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    return f"{s // 60} min {s % 60:02d} s" if s >= 60 else f"{s} s"


class ProgressLine:
    """Prints :class:`Progress` as one line: rewritten in place on a terminal, else at most every ``interval_s``
    seconds (and at the last run).

    Where it shows is decided as for every long run (:func:`convexguid.progress.display_mode`): on a terminal, or
    off one when ``CONVEXGUID_PROGRESS=1``; ``mode`` (``"live"``, ``"lines"`` or None for nothing) overrides that.
    """

    def __init__(self, name: str, stream: TextIO | None = None, interval_s: float = HEARTBEAT_S,
                 mode: str | None = "auto"):
        self.name = name
        self.stream = stream if stream is not None else sys.stderr
        self.interval_s = interval_s
        self._last = -float("inf")
        self._mode = display_mode(self.stream) if mode == "auto" else mode
        self._tty = self._mode == "live"
        self._open = False

    def __call__(self, p: Progress) -> None:
        if self._mode is None:
            return
        now = time.monotonic()
        last = p.done == p.total
        if not self._tty and not last and now - self._last < self.interval_s:
            return
        self._last = now
        resumed = f" ({p.resumed} from before)" if p.resumed else ""
        line = (f"{self.name}: {p.done}/{p.total} runs{resumed}, {p.failures} failed, "
                f"ETA {duration_text(0.0 if last else p.eta_s)}")
        if self._tty:
            self.stream.write("\r\x1b[K" + line + ("\n" if last else ""))
            self._open = not last
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def close(self) -> None:
        """End a line left open on a terminal (after an interrupt)."""
        if self._open:
            self.stream.write("\n")
            self.stream.flush()
            self._open = False
