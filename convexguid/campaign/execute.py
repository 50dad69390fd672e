"""Running a campaign's runs: the task a worker executes, and the executors (in process, or on Dask).

A worker receives a :class:`RunTask`: the problem file's data (a dict, already read by the caller), the file's
absolute path (for messages, and for files the problem names relative to itself), the run's overrides and the
figures to collect. It never reads the campaign file and never depends on its working directory. It returns a
small dictionary (status, message, objective, verified, wall time, figures), not the solution with its
trajectories, so what travels back to the client stays a few hundred bytes per run.

Whatever a run raises becomes an outcome with status ``error`` and a one-line reason; a worker that dies under
a run (Dask gives up on it after its retries) does too. The executors hand each outcome to a callback as it
arrives, in completion order.

dask and distributed are imported here, when a campaign runs on them, never by ``import convexguid``.
"""

from __future__ import annotations

import contextlib
import logging
import math
import signal
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from convexguid.bench_common import one_line
from convexguid.errors import SpecError
from convexguid.problem_files import parse_problem
from convexguid.spec.loader import MISSING, apply_overrides, value_at
from convexguid.threads import limit_threads

if TYPE_CHECKING:
    from distributed import Client

    from convexguid.campaign.definition import Campaign
    from convexguid.campaign.plan import Run

REASON_LENGTH = 300
"""Longest reason (characters) an error outcome keeps."""

TRIM_THRESHOLD_KEY = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
"""Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536`` to hand freed memory back to the system; a fixed
threshold also switches off glibc's adaptive mmap threshold, so every mid-sized numpy array is mapped and unmapped
afresh, which made the flat-attitude solve 1.6x slower (validation/BENCHMARKS_campaign.md). A solve keeps little
memory between runs, so the local cluster leaves the variable unset."""


@dataclass(frozen=True)
class RunTask:
    """What a worker needs for one run (see the module docstring)."""

    run_id: int
    problem: dict[str, Any]
    source: str
    overrides: tuple[str, ...]
    figures: tuple[str, ...]


def make_tasks(campaign: Campaign, runs: Sequence[Run]) -> list[RunTask]:
    """The tasks of ``runs``."""
    figures = tuple(campaign.spec.figures)
    return [RunTask(run.run_id, campaign.problem_data, campaign.problem_source, run.overrides, figures)
            for run in runs]


def run_task(task: RunTask) -> dict[str, Any]:
    """Solve (or simulate) one run and summarise it; never raises (an exception is an ``error`` outcome)."""
    # imported in the worker that runs the task: the scheduler unpickling it does not load the solver
    from convexguid.api import solve

    started = time.perf_counter()
    try:
        if task.source.endswith(".py"):  # a problem module: build() with the run's parameters
            from convexguid.ocp.module import load_module_problem

            solution = load_module_problem(task.source, task.overrides).solve()
        else:
            solution = solve(parse_problem(apply_overrides(task.problem, task.overrides, task.source), task.source))
        summary = solution.summary()
        outcome = {"status": solution.status, "message": one_line(solution.message, REASON_LENGTH),
                   "objective": summary["objective"],
                   "verified": solution.verification.passed if solution.verification is not None else None,
                   "figures": figure_values(summary, task.figures)}
    except Exception as exc:  # noqa: BLE001 - every failure of a run is recorded as its row, never the campaign's end
        outcome = error_outcome(task, exc)
    outcome["run_id"] = task.run_id
    outcome["wall_time_s"] = time.perf_counter() - started
    return outcome


def error_outcome(task: RunTask, exc: BaseException, wall_time_s: float | None = None) -> dict[str, Any]:
    """The outcome of a run that raised ``exc`` (or whose worker died)."""
    return {"run_id": task.run_id, "status": "error",
            "message": one_line(f"{type(exc).__name__}: {exc}", REASON_LENGTH), "objective": None,
            "verified": None, "figures": dict.fromkeys(task.figures), "wall_time_s": wall_time_s}


def figure_values(summary: dict[str, Any], figures: Sequence[str]) -> dict[str, float | None]:
    """Each figure (a dotted path into ``summary``; list items by index) as a float; None where the summary
    does not have it or it is null.

    Raises
    ------
    SpecError
        If a figure is text, a list or a mapping rather than a number.
    """
    values: dict[str, float | None] = {}
    for figure in figures:
        node = value_at(summary, figure)
        node = None if node is MISSING else node
        if node is not None and not isinstance(node, (bool, int, float)):
            raise _not_a_number(figure, node)
        values[figure] = float(node) if node is not None and math.isfinite(float(node)) else None
    return values


def _not_a_number(figure: str, value: Any) -> SpecError:
    """The error for a figure whose value is text, a list or a mapping; it names an item to ask for instead."""
    if isinstance(value, list):
        kind, hint = "a list", f"name a number inside it, e.g. {figure}.0"
    elif isinstance(value, dict):
        kind, hint = "a mapping", f"name a number inside it, e.g. {figure}.{next(iter(value), 'key')}"
    else:
        kind, hint = type(value).__name__, "name a numeric figure"
    return SpecError(f"figures: {figure} is {kind}, not a number (got {one_line(repr(value))}); {hint}")


OutcomeSink = Callable[[RunTask, dict[str, Any]], None]
"""Receives each task with its outcome, as it arrives."""


def run_serial(tasks: Sequence[RunTask], sink: OutcomeSink, work: Callable[[Any], dict[str, Any]] = run_task
               ) -> None:
    """Run the tasks one after another in this process (``work(task)`` gives each outcome)."""
    for task in tasks:
        sink(task, work(task))


def run_on_dask(tasks: Sequence[RunTask], sink: OutcomeSink, client: Client,
                work: Callable[[Any], dict[str, Any]] = run_task) -> None:
    """Submit every task to the cluster of ``client``; hand over each outcome as it completes.

    ``work(task)`` computes an outcome on a worker and never raises (:func:`run_task` by default; any task with
    ``run_id`` and ``figures`` attributes will do). Whatever ends this early (an interrupt, an exception of
    ``sink``) cancels the tasks still pending.
    """
    from distributed import as_completed  # Dask only for a run on a cluster (--serial needs none)

    session = uuid.uuid4().hex[:8]
    futures = {client.submit(work, task, key=f"convexguid-run-{task.run_id}-{session}", pure=False): task
               for task in tasks}
    try:
        for future in as_completed(futures, loop=client.loop):
            task = futures[future]
            try:
                outcome = future.result()
            except Exception as exc:  # noqa: BLE001 - the task did not run to its end (a worker died under it)
                outcome = error_outcome(task, exc)
            future.release()
            sink(task, outcome)
    finally:
        client.cancel(list(futures))


@contextlib.contextmanager
def dask_client(scheduler: str | None, workers: int | None, connect_timeout_s: float, source: str
                ) -> Iterator[Client]:
    """A client of the scheduler at ``scheduler``, or of a new local cluster of ``workers`` single-threaded worker
    processes (every core if None) closed at the end. Every worker limits its BLAS/OpenMP threads to one
    (:mod:`convexguid.threads`).

    Raises
    ------
    SpecError
        If no scheduler answers at ``scheduler`` within ``connect_timeout_s`` (nothing has run).
    """
    import dask  # Dask only for a run on a cluster (--serial needs none)
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=connect_timeout_s, set_as_default=False)
        except Exception as exc:  # noqa: BLE001 - any failure to connect is the address's fault
            raise SpecError(f"{source}: --scheduler: no Dask scheduler answers at {scheduler!r} within "
                            f"{connect_timeout_s:g} s ({one_line(str(exc), 120)}); give the address the scheduler "
                            "prints, e.g. tcp://host:8786") from None
        with client:
            client.run(limit_threads)
            yield client
        return
    with _workers_ignore_interrupts(), dask.config.set({TRIM_THRESHOLD_KEY: None}):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                               silence_logs=logging.ERROR)
    with cluster, Client(cluster, set_as_default=False) as client:
        client.run(limit_threads)
        yield client


@contextlib.contextmanager
def _workers_ignore_interrupts() -> Iterator[None]:
    """Ignore SIGINT while the local workers start, so the processes they spawn inherit that: Ctrl-C then reaches
    the client alone, which cancels the runs and closes the cluster in order (without it every worker prints a
    traceback)."""
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
