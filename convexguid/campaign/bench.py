"""Campaign benchmark: runs per second in process and on a local Dask cluster, the overhead Dask adds per task, and
the memory of a worker.

Run from the repository root (``OPENBLAS_NUM_THREADS=1`` so that each solve uses one core)::

    python -m convexguid.campaign.bench [--campaign FILE] [--repeat 2] [--output validation/BENCHMARKS_campaign.md]

Every executor runs the same runs of the campaign (by default the 200-run Monte Carlo of
``problems/campaigns/cai2018_dispersed_attitudes.yaml``), each row appended to a results table in a temporary
folder as in a real campaign, and the outcomes are checked equal across executors. The cluster is started before
the clock starts (its start-up is timed apart); the overhead per run is the time a campaign took beyond the solves
its workers timed (``workers x campaign time - sum of solve times``, per run). A separate pass times tasks that do
nothing, for the bare round trip through the scheduler.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import pickle
import resource
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from convexguid.bench_common import cell, environment_lines, markdown_grid
from convexguid.campaign.definition import load_campaign
from convexguid.campaign.execute import dask_client, make_tasks, run_on_dask, run_serial
from convexguid.campaign.plan import plan_runs
from convexguid.campaign.table import ResultsTable
from convexguid.outputs import write_text_atomic

DEFAULT_CAMPAIGN = Path("problems/campaigns/cai2018_dispersed_attitudes.yaml")
NOOP_TASKS = 2000
EXECUTORS = (("serial", None, None), ("1 worker", 1, None), ("2 workers", 2, None),
             ("1 worker, Dask's MALLOC_TRIM_THRESHOLD_", 1, "65536"))
"""Label, local workers (None: in process), ``MALLOC_TRIM_THRESHOLD_`` of the workers (None: unset, our default)."""
PACKAGES = ("numpy", "scipy", "clarabel", "daqp", "dask", "distributed", "pyarrow")


@dataclass(frozen=True)
class Measurement:
    """One campaign pass: executor, workers, cluster start-up, campaign time, summed solve time, peak memory of
    each worker process (MiB; the bench process itself when serial), objectives by run id."""

    executor: str
    workers: int
    start_s: float | None
    campaign_s: float
    solve_s: float
    peak_mib: tuple[float, ...]
    objectives: dict[int, float | None]

    @property
    def runs_per_s(self) -> float:
        return len(self.objectives) / self.campaign_s

    @property
    def overhead_ms(self) -> float:
        """Time per run beyond the solves, summed over the workers."""
        return 1e3 * (self.workers * self.campaign_s - self.solve_s) / len(self.objectives)


def _peak_mib() -> float:
    """Peak resident memory of this process, MiB: Linux's VmHWM (the high-water mark of this program's memory,
    unlike ru_maxrss, which a spawned process inherits from the one that started it); ru_maxrss elsewhere."""
    try:
        status = Path("/proc/self/status").read_text()
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    kib = next(line.split()[1] for line in status.splitlines() if line.startswith("VmHWM:"))
    return int(kib) / 1024.0


def _noop(i: int) -> dict:
    return {"run_id": i}


def _measure(campaign, runs, workers: int | None, folder: Path, trim_threshold: str | None = None) -> Measurement:
    """Run every run once: in process (``workers`` None) or on a new local cluster of ``workers`` processes
    (started with ``MALLOC_TRIM_THRESHOLD_=trim_threshold`` if given, as Dask's nanny would)."""
    tasks = make_tasks(campaign, runs)
    by_id = {run.run_id: run for run in runs}
    table = ResultsTable.open(folder, campaign, runs)
    outcomes: dict[int, dict] = {}

    def sink(task, outcome) -> None:
        table.append(by_id[task.run_id], outcome)
        outcomes[task.run_id] = outcome

    if workers is None:
        started = time.perf_counter()
        run_serial(tasks, sink)
        elapsed = time.perf_counter() - started
        start_s, used, peaks = None, 1, (_peak_mib(),)
    else:
        started = time.perf_counter()
        with _environment("MALLOC_TRIM_THRESHOLD_", trim_threshold), \
                dask_client(None, workers, 10.0, str(campaign.source)) as client:
            client.run(_import_solver)  # the workers' first imports belong to the start-up
            start_s = time.perf_counter() - started
            started = time.perf_counter()
            run_on_dask(tasks, sink, client)
            elapsed = time.perf_counter() - started
            used = len(client.nthreads())
            peaks = tuple(sorted(client.run(_peak_mib).values()))
    table.compact()
    solve = sum(o["wall_time_s"] for o in outcomes.values())
    return Measurement("in process" if workers is None else "LocalCluster", used, start_s, elapsed, solve, peaks,
                       {i: o["objective"] for i, o in sorted(outcomes.items())})


@contextlib.contextmanager
def _environment(name: str, value: str | None) -> Iterator[None]:
    """``os.environ[name] = value`` for the block (nothing if ``value`` is None); the worker processes inherit it."""
    if value is None:
        yield
        return
    previous = os.environ.get(name)
    os.environ[name] = value
    try:
        yield
    finally:
        if previous is None:
            del os.environ[name]
        else:
            os.environ[name] = previous


def _import_solver() -> None:
    """The imports every planned run makes (the API, the SCP engine and its check-repair loop, SciPy's
    integrators); a family's own modules are small beside them."""
    import convexguid.api  # noqa: F401
    import convexguid.scp.check_repair  # noqa: F401


def _busy_loop(_: int = 0) -> float:
    """Seconds a fixed pure-Python loop takes."""
    started = time.perf_counter()
    total = 0
    for i in range(10_000_000):
        total += i
    return time.perf_counter() - started


def _cores_available(rounds: int = 3) -> float:
    """How many cores two processes got: twice the solo time of a busy loop over the time of two run at once
    (2.0 on an idle 2-core machine, less when others use it), the best of ``rounds`` alternating measurements
    of each."""
    from concurrent.futures import ProcessPoolExecutor

    solo, pair = [], []
    with ProcessPoolExecutor(2) as pool:
        pool.submit(_busy_loop).result()
        for _ in range(rounds):
            solo.append(pool.submit(_busy_loop).result())
            pair.append(max(pool.map(_busy_loop, range(2))))
    return 2 * min(solo) / min(pair)


def _noop_round_trip_ms(tasks: int) -> float:
    """Mean time per task of ``tasks`` tasks that do nothing, on one worker (submit to result back)."""
    with dask_client(None, 1, 10.0, "bench") as client:
        client.submit(_noop, -1, pure=False).result()
        started = time.perf_counter()
        futures = [client.submit(_noop, i, pure=False) for i in range(tasks)]
        client.gather(futures)
        return 1e3 * (time.perf_counter() - started) / tasks


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m convexguid.campaign.bench", description=__doc__.splitlines()[0])
    parser.add_argument("--campaign", type=Path, default=DEFAULT_CAMPAIGN)
    parser.add_argument("--repeat", type=int, default=2, help="passes per executor (the fastest is reported)")
    parser.add_argument("--output", type=Path, help="write the markdown here")
    args = parser.parse_args(argv)
    campaign = load_campaign(args.campaign)
    runs = plan_runs(campaign)
    passes: dict[str, list[Measurement]] = {}
    cores = [_cores_available()]
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(max(1, args.repeat)):
            for label, workers, trim in EXECUTORS:
                folder = Path(tmp) / f"{label}-{len(passes.get(label, []))}"
                m = _measure(campaign, runs, workers, folder, trim)
                passes.setdefault(label, []).append(m)
                print(f"{label:<10} {m.campaign_s:8.2f} s  {m.runs_per_s:6.2f} runs/s  overhead "
                      f"{m.overhead_ms:6.1f} ms/run", file=sys.stderr)
            cores.append(_cores_available())
        noop_ms = _noop_round_trip_ms(NOOP_TASKS)
    reference = passes["serial"][0].objectives
    mismatches = sum(m.objectives != reference for ms in passes.values() for m in ms)
    task_bytes = len(pickle.dumps(make_tasks(campaign, runs[:1])[0]))
    text = _markdown(args, campaign, runs, passes, noop_ms, task_bytes, mismatches, cores)
    if args.output is not None:
        write_text_atomic(args.output, text)
    print(text)
    return 0 if mismatches == 0 else 1


def _markdown(args, campaign, runs, passes, noop_ms: float, task_bytes: int, mismatches: int,
              cores: list[float]) -> str:
    body = []
    for label, ms in passes.items():
        best = min(ms, key=lambda m: m.campaign_s)
        body.append([label, str(best.workers), cell(best.start_s, ".1f"), f"{best.campaign_s:.1f}",
                     ", ".join(f"{m.campaign_s:.1f}" for m in ms), f"{best.runs_per_s:.2f}",
                     f"{1e3 * best.solve_s / len(runs):.0f}", f"{best.overhead_ms:.0f}",
                     ", ".join(f"{p:.0f}" for p in best.peak_mib)])
    serial = min(passes["serial"], key=lambda m: m.campaign_s)
    columns = ["executor", "workers", "start-up s", "campaign s (best)", "all passes s", "runs/s",
               "solve ms/run (mean)", "overhead ms/run", "peak memory MiB per process"]
    per_run = statistics.mean(o for o in serial.objectives.values() if o is not None)
    return "\n".join([
        "# Campaign benchmark: runs per second, Dask's overhead, memory per worker", "",
        f"Campaign `{args.campaign}`: {len(runs)} runs of `{Path(campaign.problem_source).name}` "
        f"({campaign.family.name}) with {len(campaign.spec.dispersions)} dispersed boundary angles; every "
        "executor ran the same runs and appended each row to a results table as a real campaign does.", "",
        f"Command: `OPENBLAS_NUM_THREADS=1 python -m convexguid.campaign.bench --repeat {args.repeat} "
        f"--output {args.output}`", "",
        *environment_lines(PACKAGES),
        f"- Cores two processes got, before and after each round of passes: {', '.join(f'{c:.2f}' for c in cores)}"
        " (two busy loops at once against one alone; 2.00 on an idle 2-core machine: other users share it)", "",
        markdown_grid(columns, [":---"] + ["---:"] * 8, body), "",
        "- start-up: the local cluster (scheduler, nanny and worker processes) until every worker has imported the "
        "solver; paid once per campaign, not per run (in process it is the import, paid by any solve).",
        "- runs/s: runs over campaign time, start-up excluded. solve ms/run: the mean wall time of one solve as "
        "its worker timed it. overhead ms/run: workers x campaign time minus the summed solve times, per run "
        "(scheduling, sending the task and the result, the table's append, and on 2 workers any time a worker "
        "waited for a core: the client and scheduler share the machine's 2 cores with them).",
        f"- A task that does nothing takes {noop_ms:.2f} ms per round trip through the scheduler to one worker "
        f"({NOOP_TASKS} tasks): Dask's own cost per task. A run's task pickles to {task_bytes} bytes (the problem "
        "data travel with every task); its result is a small dictionary (status, objective, figures).",
        "- 2 workers: each solve takes as much longer as the machine has fewer than 2 cores to give (the probe "
        "above); their runs/s is bounded by those cores, not by Dask.",
        f"- Outcomes equal across executors and passes: {'yes' if mismatches == 0 else f'NO ({mismatches})'} "
        f"(mean objective {per_run:.6g}).",
        "- peak memory: the largest resident set each worker process reached (VmHWM); in process, the bench "
        "process itself.",
        "- Last row: workers started as Dask's nanny starts them by default, with MALLOC_TRIM_THRESHOLD_=65536. "
        "A fixed trim threshold also turns off glibc's adaptive mmap threshold, so the solver's mid-sized arrays "
        "are mapped and unmapped afresh each time; convexguid's local cluster leaves the variable unset "
        "(convexguid.campaign.execute.TRIM_THRESHOLD_KEY). On a cluster of your own, set "
        "`distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_: null` in the workers' Dask configuration.",
        ""])


if __name__ == "__main__":
    sys.exit(main())
