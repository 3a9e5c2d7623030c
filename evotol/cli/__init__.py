"""Command line: ``evotol reproduce NAME|all --out DIR``, ``evotol run STUDY.toml``, ...

Further sub-commands are discovered from ``evotol/cli/commands/*.py`` modules that define
``register(subparsers)``; each sets ``func`` on its parser (argparse ``set_defaults``).
"""
from __future__ import annotations

import argparse
import html
import importlib
import logging
import math
import os
import pkgutil
import sys
import time
from pathlib import Path

from evotol.errors import EvotolError, SchedulerLost, WriteFailed

#: progress and notes of the command (standard error, see evotol.cli.logs); results are printed to stdout
log = logging.getLogger(__name__)


def _write_index(out: Path, summaries: dict[str, dict]) -> Path:
    from evotol import studies

    rows = []
    for name, study in studies.available().items():
        present = (out / f"{name}.html").exists()
        secs = summaries.get(name, {}).get("seconds")
        rows.append(
            f"<tr><td>{'<a href=%r>%s</a>' % (name + '.html', html.escape(name)) if present else html.escape(name)}</td>"
            f"<td>{html.escape(study.title)}</td><td>{html.escape(study.seed_paper)}</td>"
            f"<td>{'%.1f s' % secs if secs is not None else ('written earlier' if present else 'not run')}</td>"
            f"<td>{'<a href=%r>JSON</a>' % (name + '.json') if (out / f'{name}.json').exists() else ''}</td></tr>")
    page = ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>evotol studies</title>"
            "<style>body{font-family:system-ui,sans-serif;max-width:1000px;margin:2em auto}"
            "td,th{border:1px solid #ccc;padding:.3em .6em}table{border-collapse:collapse}</style></head>"
            "<body><h1>evotol: reproduced seed studies</h1><table><tr><th>study</th><th>what</th>"
            "<th>seed paper</th><th>run time</th><th>data</th></tr>" + "".join(rows) + "</table></body></html>")
    from evotol._runtime.atomic_files import write_text

    return write_text(out / "index.html", page)


def cmd_reproduce(args) -> int:
    """Run ``evotol reproduce NAME|all``: seed studies into HTML + JSON, and an ``index.html``.

    One study at a time in this process, or with ``--jobs`` > 1 and several studies, each in its
    own process (:func:`evotol.cli.parallel_studies.reproduce_concurrently`). A study that fails with an
    evotol error (or, among several, with a bug) is reported and the others still run; Ctrl-C
    stops after the current study.

    Parameters
    ----------
    args : argparse.Namespace
        ``study`` (a name or ``"all"``), ``out`` (folder), ``seed``, ``quick`` (bool),
        ``scheduler`` (Dask address or None) and ``jobs`` (None: up to 2, by the cores).

    Returns
    -------
    int
        Exit status: 0, 1 when a study failed, 130 after Ctrl-C.

    Raises
    ------
    ValidationError
        An unknown study name, an output folder that cannot be written, or a scheduler that does
        not answer (:func:`evotol.cli.argument_types.check_scheduler_answers`).
    """
    from evotol import studies
    from evotol.cli.argument_types import check_scheduler_answers
    from evotol._runtime.output_paths import output_folder

    names = list(studies.available()) if args.study == "all" else [studies.get(args.study).name]
    out = output_folder(args.out, "--out")          # before any computation (issue 15)
    if args.scheduler:
        check_scheduler_answers(args.scheduler)
    with scheduler_in_environment(args.scheduler):
        return _reproduce(args, names, out)


def scheduler_in_environment(address):
    """``EVOTOL_DASK_SCHEDULER`` set to ``address`` for one command (the grid and design studies and their
    worker processes read it: :func:`evotol._runtime.executor.scheduler_of`), then restored, so that a second
    command in the same process (a script, a test) does not connect to the first one's scheduler.

    Parameters
    ----------
    address : str or None
        The scheduler's address; None or empty: the environment is left as it is.

    Returns
    -------
    contextlib.AbstractContextManager
    """
    import contextlib

    from evotol._runtime.executor.backends import SCHEDULER_ENV

    @contextlib.contextmanager
    def scope():
        previous = os.environ.get(SCHEDULER_ENV)
        os.environ[SCHEDULER_ENV] = address
        try:
            yield
        finally:
            if previous is None:
                os.environ.pop(SCHEDULER_ENV, None)
            else:
                os.environ[SCHEDULER_ENV] = previous
    return scope() if address else contextlib.nullcontext()


def _reproduce(args, names, out) -> int:
    """:func:`cmd_reproduce` after its checks (its docstring)."""
    from evotol import studies
    from evotol._runtime.interrupt import CtrlC
    from evotol._runtime.progress import Heartbeat

    summaries, failed, seconds = {}, [], {}
    interrupted = None                     # (study, what happened) after Ctrl-C
    t_all = time.perf_counter()
    jobs = args.jobs if args.jobs is not None else min(2, os.cpu_count() or 1)
    if jobs > 1 and len(names) > 1:        # several studies at once, each its own process (issue 13)
        return _reproduce_jobs(names, out, args, jobs, t_all)
    for name in names:
        study = studies.get(name)
        log.info("reproducing %s: %s", name, study.title)
        t0 = time.perf_counter()
        try:
            extra = {"scheduler": args.scheduler} if args.scheduler and "scheduler" in study.config else {}
            extra.update({"force": True} if args.force else {})    # overwrite a study file's outputs (issue 42)
            with Heartbeat(name, out=out, quick=args.quick), CtrlC() as ctrl_c:   # progress lines in a log file (no terminal, no tqdm)
                summaries[name] = study.run(out, quick=args.quick, seed=args.seed, **extra)
        except KeyboardInterrupt:
            interrupted = (name, "stopped before its files were written (files of an earlier run, if any, are untouched)")
            break
        except (WriteFailed, SchedulerLost):   # a full disk, a read-only folder, a lost scheduler stop every study alike
            raise
        except EvotolError as exc:
            failed.append(name)
            print(f"[evotol] {name} failed: {exc}", file=sys.stderr)
            continue
        except Exception:  # a bug in one study must not stop the others: report it and go on
            if len(names) == 1:
                raise
            import traceback

            failed.append(name)
            traceback.print_exc()
            print(f"[evotol] {name} failed (bug, traceback above); continuing with the other studies", file=sys.stderr)
            continue
        finally:
            seconds[name] = time.perf_counter() - t0
        log.info("%s done in %.1f s -> %s", name, time.perf_counter() - t0, out / (name + '.html'))
        if ctrl_c.count:                   # a GA/NSGA-II caught Ctrl-C and returned its best design so far
            interrupted = (name, "written, but a method inside it stopped early at Ctrl-C (best design so far)")
            break
    index = _write_index(out, summaries)
    log.info("index: %s", index)
    if len(names) > 1:
        _print_time_table(seconds, failed, time.perf_counter() - t_all)
    if failed and len(names) > 1:          # one study: its own line said it
        print(f"[evotol] failed: {', '.join(failed)}", file=sys.stderr)
    if interrupted is not None:
        name, what = interrupted
        done = [n for n in summaries if n != name]
        skipped = names[names.index(name) + 1:]
        print(f"evotol: interrupted (Ctrl-C) during {name}: {what}; "
              f"completed and written: {', '.join(done) or 'none'}; not run: {', '.join(skipped) or 'none'}",
              file=sys.stderr)
        return 130
    return 1 if failed else 0


def _reproduce_jobs(names, out: Path, args, jobs: int, t_all: float) -> int:
    """``evotol reproduce all`` with ``jobs`` studies at once (:mod:`evotol.cli.parallel_studies`)."""
    from evotol import studies
    from evotol.cli.parallel_studies import reproduce_concurrently

    titles = {n: studies.get(n).title for n in names}
    res = reproduce_concurrently(names, out, jobs=jobs, seed=args.seed, quick=args.quick, scheduler=args.scheduler,
                                 titles=titles, force=args.force)
    index = _write_index(out, res.summaries)
    log.info("index: %s", index)
    _print_time_table({n: res.seconds[n] for n in names if n in res.seconds}, res.failed,
                      time.perf_counter() - t_all, jobs=jobs)
    if res.failed:
        print(f"[evotol] failed: {', '.join(res.failed)}", file=sys.stderr)
    if res.interrupted:
        done = [n for n in res.summaries if n not in res.stopped]
        written = res.written
        print(f"evotol: interrupted (Ctrl-C) during {', '.join(res.stopped) or 'none'}: "
              + (f"{', '.join(written)} written, but a method inside stopped early at Ctrl-C (best design so far); "
                 if written else "")
              + (f"{', '.join(n for n in res.stopped if n not in written)} stopped before their files were written "
                 "(files of an earlier run, if any, are untouched); " if set(res.stopped) - set(written) else "")
              + f"completed and written: {', '.join(done) or 'none'}; not run: {', '.join(res.not_run) or 'none'}",
              file=sys.stderr)
        return 130
    return 1 if res.failed else 0


def _print_time_table(seconds: dict, failed: list, total: float, jobs: int = 1) -> None:
    """Per-study wall-clock times (s) at the end of ``evotol reproduce all`` (issue 13), with the
    machine load: the 2-core machine is often shared, so absolute times are noisy."""
    import os

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    w = max(len(n) for n in seconds) if seconds else 5
    print(f"[evotol] run times (load average {load:.1f}, {os.cpu_count()} cores"
          + (f"; {jobs} studies at a time, so their times overlap" if jobs > 1 else "") + "):")
    for name, sec in seconds.items():
        print(f"  {name:{w}s} {sec:8.1f} s{'  (failed)' if name in failed else ''}")
    print(f"  {'total':{w}s} {total:8.1f} s", flush=True)


def cmd_run(args) -> int:
    """Run ``evotol run STUDY.toml`` (:func:`evotol.studyfile.run_study_file`) and print a line
    per method; plausibility warnings are printed one line each.

    Parameters
    ----------
    args : argparse.Namespace
        ``study_file``, ``out`` (folder, or None: beside the study file), ``seed`` (or None: the
        file's), ``keep_going`` and ``force`` (bool).

    Returns
    -------
    int
        Exit status: 0, or 130 when Ctrl-C stopped a method (0 with ``--keep-going``).

    Raises
    ------
    ValidationError
        An unreadable study file, an unwritable output folder, or a bad study file.
    evotol.errors.InfeasibleError
        No allowed design meets the requirement.
    """
    from evotol._runtime.output_paths import input_file, output_folder
    from evotol.core.plausibility import reported
    from evotol.studyfile import run_study_file

    study_file = input_file(args.study_file, "study file", "a study TOML file")
    out = output_folder(args.out if args.out is not None else study_file.parent, "--out")
    with reported():                    # unit slips, an inactive requirement: one line each (issue 27)
        summary = run_study_file(study_file, out=out, seed=args.seed, keep_going=args.keep_going, force=args.force)
    _print_results(summary)
    log.info("wrote %s and %s", summary['html'], summary['json'])
    if summary.get("interrupted"):
        what = summary["interruption"]
        print(f"evotol: interrupted (Ctrl-C): stopped {', '.join(what['stopped'])}"
              + (f", skipped {', '.join(what['skipped'])}" if what["skipped"] else "")
              + f"; the results computed until then are in {summary['json']}", file=sys.stderr)
        return 0 if args.keep_going else 130
    return 0


def _print_results(summary: dict) -> None:
    """One line per method of ``evotol run`` (and, for NSGA-II, its cheapest feasible point and
    knee): cost, largest errors in the study's display units, status and the Monte Carlo exceed
    rate, so the terminal answers "what did I get" without opening the JSON; then one line per source
    with each method's tolerance zone and cost share, the page's cells (issue 34). A stack
    (``[stack]``) prints its gap figures, Cp, Cpk and fractions outside, the page's cells."""
    from evotol.reporting import stack_report
    from evotol.reporting.callout_drawing import terminal_lines
    from evotol.reporting.drawing import terminal_tolerance_rows
    from evotol.reporting.calibration import terminal_lines as calibration_lines
    from evotol.reporting.iso9283 import terminal_lines as iso_lines
    from evotol.reporting.shop_floors import floor_lines
    from evotol.reporting.user_study import model_line, terminal_rows

    if summary.get("kind") == "analysis":      # every tolerance given: their analysis (issue 33)
        from evotol.studyfile.given_tolerances import analysis_lines
        print("\n".join(analysis_lines(summary)))
        return None
    if "stack" in summary:
        rows, header = stack_report.terminal_rows(summary)
        print(f"[evotol] gap '{summary['stack']['gap']}' ({summary['display']['unit']})")
    else:
        rows, header = terminal_rows(summary)
    if not rows:
        return
    if "stack" not in summary:
        print("[evotol] results (cost in the cost models' unit; errors: largest over the allocation poses)")
    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    for line in [header, *rows]:
        print("  " + "  ".join(f"{x:<{w}s}" if i in (0, len(line) - 1) else f"{x:>{w}s}"
                               for i, (x, w) in enumerate(zip(line, widths))).rstrip())
    for name, r in summary.get("results", {}).items():
        if r.get("verdict"):
            print(f"  {name}: {r['verdict']}")
    line = model_line(summary) if "stack" not in summary and "sources" in summary else ""
    if line:
        print(f"  {line}")             # the model the Monte Carlo sampled (the page's line)
    over = summary.get("nsga2", {}).get("cheapest_feasible_over_optimum")
    if over is not None:
        print(f"  nsga2: the front's cheapest feasible point is {100 * over:.3g} % above the certified optimum")
    if "stack" in summary and summary.get("allocation"):      # the drawn zones of each allocation, as on the page
        rows, header = stack_report.allocation_rows(summary)
        _print_table(rows[:len(summary["stack"]["dimensions"])], header,
                     title="[evotol] allocated zones as drawn (+upper / lower from the nominal), (cost share)")
    elif "stack" not in summary and "display_units" in summary and summary.get("results"):
        _print_table(*terminal_tolerance_rows(summary),
                     title="[evotol] tolerances: the zone a drawing states (display units; ±t, or +upper / −lower "
                           "from the nominal; as on the page and in the CSV), (cost share)")
    for line in terminal_lines(summary):     # drawing callouts and exact zones vs boxes (issue 35)
        print(line)
    for line in floor_lines(summary):        # sources held at the [shop] floors, as on the page (issue 41)
        print(f"  {line}")
    for line in calibration_lines(summary):  # a calibrated study: the page's calibration section (issue 41)
        print(line)
    for line in iso_lines(summary):          # ISO 9283 figures: the page's section (issue 44)
        print(line)


def _print_table(rows: list, header: list, title: str) -> None:
    """Print ``title`` and a left-aligned table (two spaces of indent)."""
    print(title)
    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    for line in [header, *rows]:
        print("  " + "  ".join(f"{x:<{w}s}" for x, w in zip(line, widths)).rstrip())


def cmd_list(args) -> int:
    """Run ``evotol list``: the seed studies, each with its expected full-run time and title.

    Parameters
    ----------
    args : argparse.Namespace
        No options are read.

    Returns
    -------
    int
        Exit status 0.
    """
    from evotol import studies

    from evotol._runtime.progress import expected

    for name, s in studies.available().items():
        print(f"{name:28s} {expected(name) or 'not measured':>12s}  {s.title}")
    print("(times: a full run on the project's 2-core machine, 2026-11-23; a slower machine took 2-3 times as long; "
          "`evotol reproduce` quotes your last run in the output folder; --quick is much shorter)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``evotol`` argument parser: ``reproduce``, ``run``, ``list`` and the sub-commands of
    every :mod:`evotol.cli.commands` module with a ``register`` function.

    Returns
    -------
    argparse.ArgumentParser
        The parser; each sub-command sets ``func``, the function to call with the parsed
        arguments.
    """
    from evotol.cli import argument_types as arguments
    from evotol.cli.plain_help import plain_parser
    from evotol import __version__

    p = argparse.ArgumentParser(prog="evotol", description="Cost-optimal tolerance allocation for robots.",
                                epilog="Results go to standard output; progress and messages to standard error.")
    p.add_argument("--version", action="version", version=f"evotol {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("reproduce", help="reproduce a seed study (or 'all') into HTML + JSON")
    r.add_argument("study", help="study name (see 'evotol list') or 'all'")
    r.add_argument("--out", default="reports", help="output folder (default: reports)")
    r.add_argument("--seed", type=arguments.seed, default=0, help="random seed, a non-negative integer (default 0)")
    r.add_argument("--quick", action="store_true", help="smaller run for a fast look")
    r.add_argument("--scheduler", type=arguments.scheduler, default=None,
                   help="Dask scheduler address (tcp://host:port) for the large grid/design studies; default: local cores")
    r.add_argument("--jobs", type=arguments.jobs, default=None,
                   help="studies run at the same time for 'all', each in its own process with its output in "
                        "OUT/logs/NAME.log (default: 2 on a machine with 2 or more cores; 1 runs them one by one "
                        "in this process). A study's grids use every core either way.")
    r.add_argument("--force", action="store_true",
                   help="overwrite the files of a study file's study with the same name in the output folder (default: refuse)")
    r.set_defaults(func=cmd_reproduce)

    u = sub.add_parser("run", help="run a user study described in a TOML file")
    u.add_argument("study_file")
    u.add_argument("--out", default=None, help="output folder (default: next to the TOML file)")
    u.add_argument("--seed", type=arguments.seed, default=None, help="override the study's seed (non-negative integer)")
    u.add_argument("--keep-going", action="store_true",
                   help="Ctrl-C stops only the running method (a GA keeps its best design so far); the "
                        "remaining methods still run and the exit code is 0 (default: stop, exit code 130)")
    u.add_argument("--force", action="store_true",
                   help="overwrite the files of another study with the same name in the output folder (default: refuse)")
    u.set_defaults(func=cmd_run)

    ls = sub.add_parser("list", help="list the reproducible studies")
    ls.set_defaults(func=cmd_list)

    import evotol.cli.commands as commands
    for info in pkgutil.iter_modules(commands.__path__):
        mod = importlib.import_module(f"evotol.cli.commands.{info.name}")
        if hasattr(mod, "register"):
            mod.register(sub)
    for parser in (p, *sub.choices.values()):      # before or after the sub-command: evotol -q run ..., evotol run ... -q
        _verbosity_options(parser, default=0 if parser is p else argparse.SUPPRESS)
    plain_parser(p)                                  # help in plain words: no markup, no issue numbers
    return p


def _verbosity_options(parser: argparse.ArgumentParser, default) -> None:
    """``-q`` (warnings and errors only) and ``-v`` (debug lines too) on ``parser``."""
    parser.add_argument("-q", "--quiet", action="count", default=default,
                        help="show only warnings and errors on standard error (no progress)")
    parser.add_argument("-v", "--verbose", action="count", default=default,
                        help="show debug messages too")


def main(argv=None) -> int:
    """The ``evotol`` command: parse the arguments and run the sub-command.

    Sets ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 unless
    already set. An evotol error is printed as one line ``evotol: error: ...``.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: the sub-command's; 2 after an evotol error; 3 after a fault (a write the
        system refused, a lost Dask scheduler); 130 after Ctrl-C; 0 on a broken pipe.

    Raises
    ------
    SystemExit
        From argparse: status 2 on a usage error, 0 after ``--help``.
    """
    import os

    # small matrices: one BLAS thread per process (see evotol._runtime.blas_threads); override with the usual variables
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    for stream in (sys.stdout, sys.stderr):     # an ASCII locale: '±', 'µ' printed as escapes, not a traceback
        try:
            "±µ".encode(stream.encoding or "ascii")
        except (UnicodeEncodeError, LookupError):
            if hasattr(stream, "reconfigure"):
                stream.reconfigure(errors="backslashreplace")
        except AttributeError:
            pass
    from evotol.cli.logs import configure, level_for

    args = build_parser().parse_args(argv)
    configure(level_for(args.quiet, args.verbose))
    try:
        return int(args.func(args) or 0)
    except (WriteFailed, SchedulerLost) as exc:   # disk full, read-only folder, lost scheduler (issue 42)
        print(f"evotol: error: {exc}", file=sys.stderr)
        return 3
    except EvotolError as exc:
        print(f"evotol: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:                # a refused write outside evotol's writers (e.g. a library's cache)
        from evotol._runtime.atomic_files import refused

        failed = refused(exc, exc.filename or "a file")
        if failed is None:
            raise
        print(f"evotol: error: {failed}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("evotol: interrupted; results saved so far are kept", file=sys.stderr)
        return 130
    except BrokenPipeError:               # `evotol describe ucr3 | head`: the reader left, not an error
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
