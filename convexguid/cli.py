"""Command line: ``convexguid solve|simulate|validate|bench|campaign`` (arguments, outputs, exit codes: docs/cli.md).

Exit codes: 0 success; 1 the solve (simulation) did not converge (reach the command) or its
verification failed (the summary is still written); 2 bad input (one line, no traceback).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from convexguid.errors import ConvexGuidError, OutputError, SpecError
from convexguid.outputs import check_output_file, check_output_folder, describe, rescue_copy, staged_folder
from convexguid.progress import run

# Each command imports the parts of the package it drives when it runs (the solver, the registry of families, the
# report, Dask): ``--help`` and a bad argument load none of them.

if TYPE_CHECKING:
    from convexguid.scp.engine import IterationRecord
    from convexguid.solution import Solution
    from convexguid.spec import ProblemSpec

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="convexguid", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    solve = sub.add_parser("solve", help="plan one problem file, verify it, write results")
    _add_run_arguments(solve, "no iteration table")
    simulate = sub.add_parser("simulate", help="simulate one closed-loop problem file (potential_function), "
                              "check it, write results")
    _add_run_arguments(simulate, "no start line and no per-case sweep table")
    validate = sub.add_parser("validate", help="solve the paper cases and write the validation report")
    validate.add_argument("problems", nargs="*", type=Path)
    validate.add_argument("--report", type=Path, default=Path("validation/REPORT.md"))
    validate.add_argument("--check", action="store_true",
                          help="solve the cases and compare with the committed report (every number within the "
                               "reproduction tolerance); write nothing, exit 1 naming each line that disagrees")
    bench = sub.add_parser("bench", help="time the SCP against IPOPT on the same transcription "
                           "(rendezvous files: lcvx vs scp_arcs vs IPOPT; --nodes and --backends do not apply)")
    bench.add_argument("problem", nargs="?", type=Path, default=Path("problems/cai2018_flat_attitude.yaml"))
    bench.add_argument("--nodes", type=int, nargs="+",
                       help="discretization sizes to time (default: the family's own list)")
    bench.add_argument("--repeat", type=int, default=3, help="timed runs per case (best is reported)")
    bench.add_argument("--backends", nargs="+", default=["auto", "clarabel", "osqp"])
    bench.add_argument("--runs", type=int, default=20,
                       help="lpmpc files: Monte Carlo runs of the correction comparison")
    bench.add_argument("--output", type=Path, help="also write the table (markdown) here")
    campaign = sub.add_parser("campaign", help="run a sweep or Monte Carlo over a problem file on Dask (a local "
                              "cluster by default), tabulate and report it; resumes an interrupted one")
    campaign.add_argument("campaign", type=Path)
    campaign.add_argument("--out", type=Path, help="results folder (default campaigns/<file stem>); one holding "
                          "this campaign's results is resumed")
    where = campaign.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler "
                       "(e.g. tcp://host:8786) instead of a local cluster")
    where.add_argument("--serial", action="store_true", help="run in this process, one run after another (no Dask)")
    campaign.add_argument("--workers", type=int, help="worker processes of the local cluster (default: every core)")
    campaign.add_argument("--quiet", action="store_true", help="no progress line")
    return parser


def _add_run_arguments(parser: argparse.ArgumentParser, quiet_help: str) -> None:
    """Arguments shared by ``solve`` and ``simulate``."""
    parser.add_argument("problem", type=Path)
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                        help="override one YAML value (value parsed as YAML); repeatable")
    parser.add_argument("--out", type=Path, help="folder for CSV trajectories, summary JSON and plots (replaced as "
                        "a whole when the run completes; a non-empty folder needs --overwrite)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace a non-empty --out folder (everything in it is removed)")
    parser.add_argument("--summary-json", type=Path, help="write the summary JSON here (the folder must exist)")
    parser.add_argument("--quiet", action="store_true", help=quiet_help)


def _print_header() -> None:
    print(f"{'iter':>4} {'objective':>14} {'violation':>10} {'step':>10} {'trust':>10} {'ratio':>8} "
          f"{'':>3} {'qp it':>5} {'time s':>8}")


def _print_row(r: IterationRecord) -> None:
    print(f"{r.iteration:>4} {r.objective:>14.8g} {r.violation:>10.2e} {r.step:>10.2e} {r.trust_radius:>10.2e} "
          f"{r.ratio:>8.3f} {'' if r.accepted else 'rej':>3} {r.solver_iterations:>5} {r.time_s:>8.3f}")


def _print_result(sol: Solution) -> None:
    print(f"\n{sol.problem}: {sol.status} ({sol.message})")
    print(f"  objective {sol.objective:.8g}   iterations {sol.iterations}   variables {sol.size.num_variables}"
          f"   wall time {sol.wall_time_s:.3f} s")
    v = sol.verification
    if v is not None:
        for c in v.checks:
            rel = "<=" if c.sense == "max" else ">="
            beyond = f"   beyond by {c.violation:.2g}" if c.violation > 0 else ""
            print(f"  {c.name:<24} worst {c.worst:<12.6g} {rel} {c.bound:g}{beyond}")
        line = ""  # every state's final error: a few to a line
        for entry in (f"{k} {val:.3g}" for k, val in v.final_errors.items()):
            if line and len(line) + len(entry) >= 110:
                print(f"  {line}")
                line = ""
            line = f"{line}   {entry}" if line else entry
        if line:
            print(f"  {line}")
        print(f"  verification ({v.grid_points} points): {'passed' if v.passed else 'FAILED'}")


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse unusable ``--out`` / ``--summary-json`` paths before the work starts (OutputError: exit 2)."""
    if args.out is not None:
        check_output_folder(args.out, overwrite=args.overwrite, keep=[args.problem])
    if args.summary_json is not None:
        check_output_file(args.summary_json, "summary JSON")


def _write_outputs(sol: Solution, args: argparse.Namespace) -> list[str]:
    """Write ``--out`` (a staged folder swapped in whole) and ``--summary-json``; one reason per failed output."""
    from convexguid.ocp.plots import plot_ocp
    from convexguid.solution_plots import plot_solution

    failed = []
    if args.out is not None:
        try:
            with staged_folder(args.out, replace=args.overwrite) as folder:
                if sol.dense is not None:
                    sol.dense.write_csv(folder / "trajectory.csv")
                if sol.nodes is not None:
                    sol.nodes.write_csv(folder / "nodes.csv")
                sol.write_summary(folder / "summary.json")
                if sol.family == "ocp":  # a problem stated in Python: its states and controls
                    plot_ocp(sol, folder)
                else:
                    plot_solution(sol, folder)
        except OSError as exc:
            failed.append(str(exc) if isinstance(exc, OutputError) else f"--out {args.out}: {describe(exc)}")
    if args.summary_json is not None:
        try:
            sol.write_summary(args.summary_json)
        except OSError as exc:
            failed.append(f"--summary-json {args.summary_json}: {describe(exc)}")
    return failed


def _report_lost_outputs(sol: Solution, args: argparse.Namespace, failed: list[str]) -> None:
    """One line on stderr: what could not be written and where the summary is (rescued if need be)."""
    if args.summary_json is not None and not any(f.startswith("--summary-json") for f in failed):
        where = f"the summary is in {args.summary_json}"
    else:
        text = json.dumps(sol.summary(), indent=2) + "\n"
        rescued = rescue_copy(text, "summary.json")
        where = f"the summary was written to {rescued}" if rescued else "the summary follows on stdout"
        if rescued is None:
            print(text, end="")
    print(f"convexguid: could not write {'; '.join(failed)}; {where}", file=sys.stderr)


def _runnable_problem(args: argparse.Namespace) -> ProblemSpec:
    """The problem file with ``--set`` applied, the outputs checked, and each input it takes from another case's
    result resolved by solving the problem file named so beside it first, as validate does
    (:mod:`convexguid.validation.links`). Bad input (the file, a link, an output) is refused before anything is
    solved."""
    from convexguid.api import check_runnable
    from convexguid.families import get_family
    from convexguid.problem_files import load_problem
    from convexguid.validation.links import linked_cases

    spec = load_problem(args.problem, args.overrides)
    linked = linked_cases(spec)
    for case in (*linked, spec):
        get_family(case.family).check_size(case)
    _check_outputs(args)
    if linked:
        spec = _resolved(spec, linked, args.command, args.quiet)
    check_runnable(spec)
    return spec


def _resolved(spec: ProblemSpec, linked: list[ProblemSpec], command: str, quiet: bool) -> ProblemSpec:
    """``spec`` with its input links resolved by solving ``linked`` first (a status line names them; without
    ``quiet`` a line before each and one with the values taken)."""
    from convexguid.validation.links import resolve_links

    names = ", ".join(case.name for case in linked)
    return run(lambda: resolve_links(spec, linked, None if quiet else print), f"{command} {spec.name}: solve {names}")


def _cmd_solve(args: argparse.Namespace) -> int:
    from convexguid.api import solve

    if args.problem.suffix == ".py":
        return _solve_module(args)
    spec = _runnable_problem(args)
    if not args.quiet:
        _print_header()
    sol = run(lambda: solve(spec, log=None if args.quiet else _print_row), f"solve {spec.name}")
    return _finish(sol, args)


def _solve_module(args: argparse.Namespace) -> int:
    """``convexguid solve my_problem.py``: a problem stated in Python (:mod:`convexguid.ocp.module`)."""
    from convexguid.ocp.module import load_module_problem

    problem = load_module_problem(args.problem, args.overrides)
    _check_outputs(args)
    if not args.quiet:
        _print_header()
    sol = run(lambda: problem.solve(log=None if args.quiet else _print_row), f"solve {problem.name}")
    return _finish(sol, args)


def _finish(sol: Solution, args: argparse.Namespace) -> int:
    """Print the result block, write the outputs and return the exit code (shared by solve and simulate)."""
    _print_result(sol)
    failed = _write_outputs(sol, args)
    if failed:
        _report_lost_outputs(sol, args, failed)
    if not sol.ok:
        reason = sol.message if sol.status != "converged" else "dense verification failed"
        print(f"convexguid: {args.problem}: {sol.status}: {reason}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_FAILED if failed else EXIT_OK


def _cmd_simulate(args: argparse.Namespace) -> int:
    from convexguid.api import simulate
    from convexguid.families import get_family

    spec = _runnable_problem(args)
    family = get_family(spec.family)
    if not args.quiet and family.console_header is not None:
        print(family.console_header(spec))
    sol = run(lambda: simulate(spec), f"simulate {spec.name}")
    if not args.quiet and family.console_details is not None:
        for line in family.console_details(sol):
            print(line)
    return _finish(sol, args)


def _cmd_validate(args: argparse.Namespace) -> int:
    from convexguid.validation.run import check, check_report_outputs, validate
    from convexguid.validation.timings import timings_path

    if args.check:
        results, differences = run(lambda: check(args.problems, args.report), "validate --check")
        _print_verdicts(results)
        for difference in differences:
            print(f"{args.report}: {difference.describe()}")
        if differences:
            print(f"{len(differences)} line(s) of {args.report} not reproduced (within the reproduction tolerance)")
        else:
            print(f"{args.report} reproduced: every line agrees within the reproduction tolerance")
        return EXIT_OK if not differences and all(r.ok for r in results) else EXIT_FAILED
    check_report_outputs(args.report)  # before anything is solved: OutputError, exit 2
    try:
        results = run(lambda: validate(args.problems, args.report), "validate")
    except OSError as exc:  # after the solves: the report or a figure could not be written
        reason = exc if isinstance(exc, ConvexGuidError) else f"{exc.filename or args.report}: {describe(exc)}"
        print(f"convexguid: could not write the validation outputs: {reason}", file=sys.stderr)
        return EXIT_FAILED
    _print_verdicts(results)
    print(f"report written to {args.report}; compute times in {timings_path(args.report)}")
    return EXIT_OK if all(r.ok for r in results) else EXIT_FAILED


def _print_verdicts(results) -> None:
    for r in results:
        verdict = ("matches paper" if r.ok else "MISMATCH") if r.compared else \
            ("verified, nothing to compare (no reference)" if r.ok else "NOT verified (no reference)")
        print(f"{r.spec.name:<32} {r.solution.status:<12} {verdict}")


def _cmd_bench(args: argparse.Namespace) -> int:
    from convexguid.api import PLANNER
    from convexguid.backends import check_backend_name
    from convexguid.families import FAMILIES, get_family
    from convexguid.problem_files import load_problem
    from convexguid.threads import single_threaded
    from convexguid.validation.links import linked_cases

    counts = [("--repeat", args.repeat), ("--runs", args.runs), *(("--nodes", n) for n in args.nodes or ())]
    for option, value in counts:
        if value < 1:
            raise SpecError(f"{option}: must be at least 1 (got {value})")
    for name in args.backends:
        try:
            check_backend_name(name)
        except ConvexGuidError as exc:
            raise SpecError(f"--backends: {exc}") from None
    spec = load_problem(args.problem)
    family = get_family(spec.family)
    if family.bench is None:
        benched = ", ".join(name for name, f in FAMILIES.items() if f.bench is not None)
        raise SpecError(f"{args.problem}: family {family.name!r} has no benchmark; "
                        f"convexguid bench handles: {benched}")
    linked = linked_cases(spec)
    if linked:
        spec = _resolved(spec, linked, args.command, quiet=False)
    with single_threaded():
        return run(lambda: family.bench(spec, args, PLANNER), f"bench {args.problem}")


def _cmd_campaign(args: argparse.Namespace) -> int:
    from convexguid.campaign import run_campaign
    from convexguid.campaign.progress import ProgressLine

    progress = None if args.quiet else ProgressLine(args.campaign.stem)
    try:
        result = run_campaign(args.campaign, args.out, scheduler=args.scheduler, workers=args.workers,
                              serial=args.serial, progress=progress)
    except KeyboardInterrupt:
        print(f"convexguid: {args.campaign}: the runs that finished are in the results table; the same command "
              "resumes the campaign", file=sys.stderr)
        raise
    finally:
        if progress is not None:
            progress.close()
    print(result.describe())
    return EXIT_OK if result.ok else EXIT_FAILED


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    handlers = {"solve": _cmd_solve, "simulate": _cmd_simulate, "validate": _cmd_validate, "bench": _cmd_bench,
                "campaign": _cmd_campaign}
    try:
        return handlers[args.command](args)
    except ConvexGuidError as exc:
        print(f"convexguid: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("convexguid: interrupted", file=sys.stderr)
        return 130
    except MemoryError:  # a backstop: each family's size limit should refuse such a problem before it starts
        print("convexguid: out of memory: the problem is too large for this machine; give a smaller problem "
              "(e.g. fewer nodes or steps)", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
