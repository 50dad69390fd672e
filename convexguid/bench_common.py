"""What every family's ``convexguid bench`` shares: table cells and grids, best-of timing, the environment lines.

Each family's benchmark lives in its package (``convexguid/families/<name>/bench.py``) and is
reached through :attr:`convexguid.families.base.Family.bench`.
"""

from __future__ import annotations

import datetime
import importlib.metadata
import os
import platform
from collections.abc import Callable, Sequence
from typing import TypeVar

_T = TypeVar("_T")


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
