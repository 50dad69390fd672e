"""Run the robustness benchmark and write its report (``python -m convexguid.robustness --help``).

The trials run on a local Dask cluster of single-threaded worker processes (``--serial``: in this process),
through the campaign's executors. Round-off trials of a file whose input is another case's result
(``boundary.tf_from``) wait for that case's nominal run and take its figure, as ``convexguid validate`` does.
Ctrl-C cancels what is pending and writes nothing.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from convexguid.bench_common import environment_lines
from convexguid.campaign.execute import dask_client, run_on_dask, run_serial
from convexguid.outputs import write_text_atomic
from convexguid.problem_files import load_problem
from convexguid.robustness.instances import DEFAULT_SAMPLES, GENERATORS, roundoff_trials
from convexguid.robustness.report import render
from convexguid.robustness.trial import Trial, judged, run_trial

DEFAULT_OUTPUT = Path("validation/ROBUSTNESS.md")
PACKAGES = ("numpy", "scipy", "clarabel", "piqp", "daqp", "osqp", "casadi", "dask")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m convexguid.robustness", description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=Path, default=Path("problems"), help="folder of the problem files")
    parser.add_argument("--perturbations", type=int, default=2, help="round-off perturbations per problem file")
    parser.add_argument("--sections", nargs="+", default=["roundoff", *GENERATORS],
                        choices=["roundoff", *GENERATORS], help="what to run (default: everything)")
    parser.add_argument("--samples", type=int, help="random instances per family (default: "
                        + ", ".join(f"{k} {v}" for k, v in DEFAULT_SAMPLES.items()) + ")")
    parser.add_argument("--seed", type=int, default=19, help="seed of the random instances")
    parser.add_argument("--workers", type=int, help="Dask worker processes (default: every core)")
    parser.add_argument("--serial", action="store_true", help="run in this process (no Dask)")
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT, help="report file (markdown)")
    return parser


class Runner:
    """Runs batches of trials on one executor, numbering them and printing progress on stderr."""

    def __init__(self, client, total: int) -> None:
        self.client, self.total, self.done, self.failures = client, total, 0, 0
        self.started = time.perf_counter()
        self.results: list[tuple[Trial, dict[str, Any]]] = []

    def run(self, trials: Sequence[Trial]) -> None:
        trials = [replace(t, run_id=len(self.results) + i) for i, t in enumerate(trials)]

        def sink(trial: Trial, outcome: dict[str, Any]) -> None:
            self.results.append((trial, outcome))
            self.done += 1
            self.failures += trial.section != "round-off" and judged(outcome) != "success"
            print(f"\rrobustness: {self.done}/{self.total} trials, {self.failures} not successes, "
                  f"{time.perf_counter() - self.started:.0f} s", end="", file=sys.stderr, flush=True)

        if self.client is None:
            run_serial(trials, sink, run_trial)
        else:
            run_on_dask(trials, sink, self.client, run_trial)


def _run_roundoff(runner: Runner, files: list[Path], perturbations: int) -> None:
    """Files without input links first, then each file whose linked cases have run (their nominal figures)."""
    pending = {p.name: p for p in files}
    specs = {p.name: load_problem(p) for p in files}
    by_case = {spec.name: name for name, spec in specs.items()}
    nominal: dict[str, dict[str, Any]] = {}
    while pending:
        links, ready = {}, []
        for name in list(pending):
            needs = [(key, link_key, by_case.get(link.problem), link.figure)
                     for key, link_key, link in specs[name].input_links()]
            if all(linked in nominal for _, _, linked, _ in needs):
                value = {linked: nominal[linked]["figures"].get(figure) for _, _, linked, figure in needs}
                links[name] = [o for key, link_key, linked, _ in needs
                               for o in (f"{link_key}=null", f"{key}={value[linked]!r}")]
                ready.append(pending.pop(name))
        if not ready:
            raise SystemExit(f"robustness: input links cannot be resolved among {', '.join(pending)}")
        before = len(runner.results)
        runner.run(list(roundoff_trials(ready, perturbations, links)))
        for trial, outcome in runner.results[before:]:
            if trial.label == "nominal":
                nominal[trial.group] = outcome


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    files = sorted(args.problems.glob("*.yaml")) if "roundoff" in args.sections else []
    randoms = [list(GENERATORS[name](args.problems, args.samples or DEFAULT_SAMPLES[name], args.seed))
               for name in GENERATORS if name in args.sections]
    total = len(files) * (1 + args.perturbations) + sum(map(len, randoms))
    command = "python -m convexguid.robustness " + " ".join(argv if argv is not None else sys.argv[1:])
    started = time.perf_counter()
    try:
        if args.serial:
            runner = Runner(None, total)
            _run_all(runner, files, args.perturbations, randoms)
        else:
            with dask_client(None, args.workers, 10.0, "robustness") as client:
                runner = Runner(client, total)
                workers = len(client.scheduler_info()["workers"])
                _run_all(runner, files, args.perturbations, randoms)
    except KeyboardInterrupt:
        print("\nrobustness: interrupted; nothing written", file=sys.stderr)
        return 130
    print(file=sys.stderr)
    elapsed = time.perf_counter() - started
    executor = "in process" if args.serial else f"{workers} Dask worker processes, one thread each"
    text = render(runner.results, command.strip(), elapsed, executor, environment_lines(PACKAGES))
    write_text_atomic(args.output, text)
    print(f"report written to {args.output}")
    return 0


def _run_all(runner: Runner, files: list[Path], perturbations: int, randoms: list[list[Trial]]) -> None:
    if files:
        _run_roundoff(runner, files, perturbations)
    for trials in randoms:
        runner.run(trials)
