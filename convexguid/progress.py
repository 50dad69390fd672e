"""Progress of long runs, and Ctrl-C that acts within a second.

Long computations say where they are with :func:`report`: the SCP engine every iteration, the check-repair loop
every dense check, the simulators every step, the Monte Carlo every finished run. Outside :func:`run` (the Python
API, the tests) it returns at once and shows nothing.

The command line runs its work through :func:`run`, which

* runs the work in a worker thread, so that the main thread stays free to answer Ctrl-C even while the worker is
  inside a long native call (the convex solvers release the interpreter lock while they work). On Ctrl-C it asks
  the work to stop -- the worker's next :func:`report` raises :class:`KeyboardInterrupt`, so the run ends between
  two iterations or steps and pools are shut down on the way out -- waits at most :data:`STOP_GRACE_S` for that,
  and raises :class:`KeyboardInterrupt` itself. The command then writes nothing and exits 130.
* shows the last report as one status line on stderr, from :data:`SHOW_AFTER_S` after the start (quick runs
  show nothing), redrawn a few times a second and erased at the end; text printed meanwhile (the iteration
  table) erases it first, so the two never mix. It shows under ``--quiet`` too: quiet means no tables, not
  no sign of life.

Where it shows: on a terminal. Set ``CONVEXGUID_PROGRESS=1`` to force it elsewhere (then a plain line every
:data:`HEARTBEAT_S` seconds, for logs) and ``CONVEXGUID_PROGRESS=0`` to turn it off. Captured output (the tests,
a pipe) therefore sees nothing unless asked.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TextIO, TypeVar

SHOW_AFTER_S = 1.0
"""A run shorter than this shows no status line."""

REDRAW_S = 0.2
"""The status line is redrawn (and Ctrl-C noticed) this often, s."""

HEARTBEAT_S = 10.0
"""Interval of the plain status lines when the display is forced on and stderr is not a terminal, s."""

STOP_GRACE_S = 2.0
"""After Ctrl-C, how long the work may take to reach its next report and stop before the command exits anyway."""

ENVIRONMENT = "CONVEXGUID_PROGRESS"
"""``1`` forces the status display on, ``0`` off; unset: on when stderr is a terminal."""

_T = TypeVar("_T")
_current = threading.local()


@dataclass
class _Job:
    """One run: the last report (what the status line shows) and the request to stop."""

    label: str
    started: float = field(default_factory=time.monotonic)
    stage: str = ""
    done: int | None = None
    total: int | None = None
    stop: threading.Event = field(default_factory=threading.Event)

    def status(self) -> str:
        where = self.stage
        if self.done is not None:
            where += f" {self.done}" + (f"/{self.total}" if self.total else "")
            if self.total:
                where += f" ({100 * self.done / self.total:.0f}%)"
        elapsed = time.monotonic() - self.started
        return f"{self.label}: {where + ', ' if where else ''}{elapsed:.0f} s (Ctrl-C stops)"


def report(stage: str, done: int | None = None, total: int | None = None) -> None:
    """Where the current run is: ``stage`` (e.g. ``"SCP iteration"``), ``done`` of ``total`` (give ``total`` only
    when it is what the run will reach, not a mere upper bound, since the line shows the percentage).

    Raises
    ------
    KeyboardInterrupt
        If Ctrl-C asked the run (:func:`run`) to stop.
    """
    job: _Job | None = getattr(_current, "job", None)
    if job is None:
        return
    if job.stop.is_set():
        raise KeyboardInterrupt
    job.stage, job.done, job.total = stage, done, total


def display_mode(stream: TextIO) -> str | None:
    """``"live"`` (a line redrawn in place), ``"lines"`` (a heartbeat line now and then) or None (nothing)."""
    wanted = os.environ.get(ENVIRONMENT, "").strip()
    terminal = stream.isatty()
    if wanted == "0" or (wanted != "1" and not terminal):
        return None
    return "live" if terminal else "lines"


class _StatusLine:
    """The status line of one run on ``stream``; every method holds ``lock``, shared with :class:`_ErasingStdout`."""

    def __init__(self, job: _Job, stream: TextIO, mode: str) -> None:
        self.job, self.stream, self.mode = job, stream, mode
        self.lock = threading.Lock()
        self.drawn = False
        self.last = -float("inf")

    def refresh(self) -> None:
        now = time.monotonic()
        if now - self.job.started < SHOW_AFTER_S or (self.mode == "lines" and now - self.last < HEARTBEAT_S):
            return
        with self.lock:
            text = self.job.status()
            if self.mode == "live":
                self.stream.write("\r\x1b[K" + text)
                self.drawn = True
            else:
                self.stream.write(text + "\n")
            self.stream.flush()
            self.last = now

    def erase(self) -> None:
        with self.lock:
            self._erase()

    def _erase(self) -> None:  # the caller holds the lock
        if self.drawn:
            self.stream.write("\r\x1b[K")
            self.stream.flush()
            self.drawn = False


class _ErasingStdout:
    """``sys.stdout`` while a live status line shows: each write erases the line first."""

    def __init__(self, real: TextIO, line: _StatusLine) -> None:
        self.real, self.line = real, line

    def write(self, text: str) -> int:
        with self.line.lock:
            self.line._erase()
            return self.real.write(text)

    def __getattr__(self, name: str):
        return getattr(self.real, name)


def run(work: Callable[[], _T], label: str, stream: TextIO | None = None) -> _T:
    """``work()`` in a worker thread, with the status line and Ctrl-C handling described in the module docstring.

    Returns what ``work`` returns and raises what it raises; :class:`KeyboardInterrupt` on Ctrl-C.
    """
    stream = stream if stream is not None else sys.stderr
    job = _Job(label)
    outcome: dict[str, object] = {}
    finished = threading.Event()  # waited on instead of Thread.join, which Ctrl-C can leave believing it ended

    def target() -> None:
        _current.job = job
        try:
            outcome["value"] = work()
        except BaseException as exc:  # noqa: BLE001 - handed to the main thread, which raises it
            outcome["error"] = exc
        finally:
            finished.set()

    mode = display_mode(stream)
    line = _StatusLine(job, stream, mode) if mode is not None else None
    real_stdout = sys.stdout
    if line is not None and mode == "live":
        sys.stdout = _ErasingStdout(real_stdout, line)
    worker = threading.Thread(target=target, name=f"convexguid {label}", daemon=True)
    try:
        worker.start()
        while not finished.wait(REDRAW_S):
            if line is not None:
                line.refresh()
    except KeyboardInterrupt:
        job.stop.set()
        finished.wait(STOP_GRACE_S)
        raise
    finally:
        if line is not None:
            line.erase()
        sys.stdout = real_stdout
    if "error" in outcome:
        raise outcome["error"]  # type: ignore[misc]
    return outcome["value"]  # type: ignore[return-value]
