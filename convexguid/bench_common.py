"""The skeleton every family's ``convexguid bench`` shares; each family supplies only its rows and columns.

A benchmark times methods on one problem (the SCP, IPOPT on the same NLP, the family's own alternatives) and
writes one markdown document. Shared here: running a method ``repeat`` times and keeping the fastest, or a
``failed: ...`` row when it raises (:func:`timed_method`); IPOPT's success and the note when CasADi is missing
(:func:`ipopt_outcome`, :func:`ipopt_availability`); table cells and grids; the document (title, machine,
versions, threads, date, command, caption, table, notes: :func:`bench_document`). Each family's benchmark lives
in its package (``convexguid/families/<name>/bench.py``) and is reached through
:attr:`convexguid.families.base.Family.bench`.
"""

from __future__ import annotations

import datetime
import importlib.metadata
import os
import platform
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from convexguid.reference import casadi_available

_T = TypeVar("_T")
_R = TypeVar("_R")


def cell(value: float | int | None, fmt: str) -> str:
    """A table cell: ``value`` formatted with ``fmt``, or ``-`` where it does not apply."""
    return "-" if value is None else format(value, fmt)


def one_line(text: str, limit: int = 60) -> str:
    """``text`` on one line, cut to ``limit`` characters."""
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def best_of(repeat: int, run: Callable[[], _T], wall: Callable[[_T], float]) -> tuple[_T, list[_T]]:
    """The fastest of ``repeat`` (at least one) calls of ``run`` by ``wall``, and all of them."""
    runs = [run() for _ in range(max(1, repeat))]
    return min(runs, key=wall), runs


def markdown_grid(columns: Sequence[str], align: Sequence[str], body: Sequence[Sequence[str]]) -> str:
    """A markdown table: header ``columns``, alignment row ``align`` (``":---"``, ``"---:"``), rows of ``body``."""
    lines = ["| " + " | ".join(columns) + " |", "| " + " | ".join(align) + " |"]
    lines += ["| " + " | ".join(c.replace("|", "\\|") for c in row) + " |" for row in body]
    return "\n".join(lines)


def package_version(package: str) -> str:
    """Installed version of ``package``, or ``not installed``."""
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def environment_lines(packages: Sequence[str]) -> list[str]:
    """Markdown bullets: machine, ``packages``' versions, BLAS/OpenMP thread variables, date (UTC)."""
    machine = platform.processor() or platform.machine()
    versions = ", ".join(f"{p} {package_version(p)}" for p in packages)
    threads = ", ".join(f"{v}={os.environ.get(v, 'unset')}" for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"))
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return [
        f"- Machine: {machine}, {os.cpu_count()} logical CPUs ({platform.platform()}, "
        f"Python {platform.python_version()})",
        f"- Versions: {versions}",
        f"- BLAS/OpenMP threads: one per solve and per worker, set by convexguid (convexguid.threads); the "
        f"environment had {threads}",
        f"- Date: {when}",
    ]


def failure(exc: BaseException) -> tuple[str, str]:
    """``(status, message)`` of a method that raised: ``failed: <one line>`` for the table, the whole text."""
    text = f"{type(exc).__name__}: {exc}"
    return f"failed: {one_line(text)}", text


def timed_method(repeat: int, run: Callable[[], _T], wall: Callable[[_T], float],
                 row: Callable[[_T, list[_T]], _R], failed: Callable[[str, str], _R]) -> _R:
    """The row of the fastest of ``repeat`` runs (``row(best, runs)``), or ``failed(status, message)`` when a run
    raises: one failing method must not abort the benchmark."""
    try:
        best, runs = best_of(repeat, run, wall)
    except Exception as exc:  # noqa: BLE001 - reported in the table, the benchmark goes on
        return failed(*failure(exc))
    return row(best, runs)


def ipopt_outcome(result: Any) -> tuple[bool, str]:
    """``(ok, message)`` of an IPOPT reference result (its ``success`` and ``status``)."""
    return bool(result.success), "" if result.success else f"IPOPT returned {result.status}"


def ipopt_availability(what: str) -> tuple[bool, str | None]:
    """Whether IPOPT runs here (CasADi installed), and the document's note when it does not (``what``: the rows or
    column left out)."""
    if casadi_available():
        return True, None
    return False, f"IPOPT {what} skipped: casadi is not installed (pip install 'convexguid[bench]')."


def bench_document(title: str, packages: Sequence[str], command: str, caption: str, table: str,
                   notes: Sequence[str] = (), ipopt_note: str | None = None) -> str:
    """A benchmark's markdown document: ``# title``, the machine and ``packages``' versions, the command, the
    caption, IPOPT's note if any, the table and the ``notes`` as bullets."""
    lines = [f"# {title}", "", *environment_lines(packages), f"- Command: `{command}`", "", caption]
    if ipopt_note:
        lines += ["", ipopt_note]
    lines += ["", table, ""]
    if notes:
        lines += [f"- {note}" for note in notes] + [""]
    return "\n".join(lines)
