"""``run_campaign``: load a campaign, skip the runs its results table already has, run the others on Dask (or in
this process), append each row as it arrives, then write the report.

Order of events, so that bad input writes nothing: the campaign file, its problem file and every grid point are
validated; the results directory is read (a directory written by another campaign is refused); the scheduler is
reached (or the local cluster started); only then is the first row written. An interrupt (Ctrl-C, or a
``KeyboardInterrupt`` raised by the progress callback) cancels the pending runs, merges the rows that arrived
into the table and propagates; running the same campaign again resumes from there.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from convexguid.campaign.definition import load_campaign
from convexguid.campaign.document import write_report
from convexguid.campaign.execute import dask_client, make_tasks, run_on_dask, run_serial
from convexguid.campaign.plan import plan_runs
from convexguid.campaign.progress import Progress
from convexguid.campaign.table import ResultsTable, is_ok
from convexguid.errors import SpecError

DEFAULT_CONNECT_TIMEOUT_S = 10.0
"""How long ``--scheduler`` waits for the scheduler to answer."""


@dataclass(frozen=True)
class CampaignResult:
    """What a call of :func:`run_campaign` left behind.

    ``runs``: runs in the campaign; ``finished``: rows in the table; ``executed``: runs this call ran;
    ``counts``: rows by status; ``failed``: rows not converged and verified; ``elapsed_s``: time spent running
    (cluster start included, report excluded); ``workers``: processes that ran them (1 in process, 0 if none ran).
    """

    name: str
    directory: Path
    table: Path
    report: Path | None
    runs: int
    finished: int
    executed: int
    counts: dict[str, int]
    failed: int
    elapsed_s: float
    workers: int

    @property
    def ok(self) -> bool:
        """Every run finished, converged and verified."""
        return self.finished == self.runs and self.failed == 0

    def describe(self) -> str:
        """Two lines: the runs by status, and where the table and the report are."""
        counts = ", ".join(f"{status} {n}" for status, n in sorted(self.counts.items(), key=lambda i: -i[1]))
        ran = (f"{self.executed} ran now on {self.workers} worker{'s' * (self.workers != 1)} in "
               f"{self.elapsed_s:.1f} s" if self.executed else "none left to run")
        report = f", report {self.report}" if self.report is not None else ""
        return (f"{self.name}: {self.finished}/{self.runs} runs ({counts}; {self.failed} failed or unverified; "
                f"{ran})\nresults {self.table}{report}")


def run_campaign(campaign: str | Path, out: str | Path | None = None, *, scheduler: str | None = None,
                 workers: int | None = None, serial: bool = False,
                 progress: Callable[[Progress], None] | None = None,
                 connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S, report: bool = True) -> CampaignResult:
    """Run the campaign file ``campaign`` (see :mod:`convexguid.campaign.definition` for its keys).

    Parameters
    ----------
    out : path, optional
        Results directory (default ``campaigns/<campaign file stem>``): ``results.parquet``, ``report.md`` and
        the plots. A directory holding this campaign's results is resumed.
    scheduler : str, optional
        Address of a running ``dask.distributed`` scheduler (e.g. ``tcp://host:8786``); default a local cluster.
    workers : int, optional
        Worker processes of the local cluster (default: every core).
    serial : bool
        Run in this process, one run after another, without Dask.
    progress : callable, optional
        Receives a :class:`~convexguid.campaign.progress.Progress` before the first run and after each.
    report : bool
        Write ``report.md`` and its plots at the end.

    Raises
    ------
    SpecError
        Bad campaign or problem file, options that contradict, a results directory of another campaign, or a
        scheduler that does not answer; nothing is written then.
    KeyboardInterrupt
        After the rows that arrived are in the table (resume by running the campaign again).
    """
    source = str(campaign)
    _check_options(source, scheduler, workers, serial)
    loaded = load_campaign(campaign)
    runs = plan_runs(loaded)
    directory = Path(out) if out is not None else Path("campaigns") / Path(campaign).stem
    table = ResultsTable.open(directory, loaded, runs)
    by_id = {run.run_id: run for run in runs}
    pending = [run for run in runs if run.run_id not in table.finished]
    resumed = len(runs) - len(pending)
    failures = sum(not is_ok(row) for row in table.rows())
    started = time.perf_counter()

    def report_progress() -> None:
        if progress is not None:
            progress(Progress(len(runs), len(table.finished), failures, resumed, time.perf_counter() - started))

    def sink(task, outcome) -> None:
        nonlocal failures
        row = table.append(by_id[task.run_id], outcome)
        failures += not is_ok(row)
        report_progress()

    tasks = make_tasks(loaded, pending)
    used = 0
    try:
        if tasks and serial:
            used = 1
            report_progress()
            run_serial(tasks, sink)
        elif tasks:
            with dask_client(scheduler, workers, connect_timeout_s, source) as client:
                used = len(client.nthreads())
                report_progress()
                run_on_dask(tasks, sink, client)
    finally:
        table.compact()
    elapsed = time.perf_counter() - started
    rows = table.rows()
    report_path = None
    if report:
        report_path = write_report(loaded, runs, rows, directory)
    return CampaignResult(loaded.spec.name, directory, table.path, report_path, len(runs), len(rows), len(tasks),
                          dict(Counter(row["status"] for row in rows)), failures, elapsed, used)


def _check_options(source: str, scheduler: str | None, workers: int | None, serial: bool) -> None:
    if serial and scheduler is not None:
        raise SpecError(f"{source}: --serial: runs in this process, so it takes no --scheduler (got "
                        f"{scheduler!r}); give one of them")
    if workers is not None and (serial or scheduler is not None):
        raise SpecError(f"{source}: --workers: sizes the local cluster only (got {workers}); leave it out with "
                        "--serial or --scheduler")
    if workers is not None and workers < 1:
        raise SpecError(f"{source}: --workers: must be at least 1 (got {workers}); give a number of processes")
