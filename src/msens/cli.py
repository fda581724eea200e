"""The ``msens`` command.

Each sub-command is a thin wrapper over the public Python API (:mod:`msens.api`), so a
script or notebook gets the same numbers as the terminal. Bad input ends with one message
on stderr and exit status 2, never a traceback.

Feedback: the library logs its stages through :mod:`logging` (loggers ``msens.*``) and
shows tqdm bars only while those loggers are at INFO; the command sends them to stderr as
``msens: <message>`` lines. ``-q``/``--quiet`` (before or after the sub-command) sets them to
WARNING, which also hides the bars.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from msens.errors import InputError
from msens.version import version

EXIT_INPUT = 2
#: Exit status of an internal error (a bug in msens, not bad input).
EXIT_INTERNAL = 1
#: Environment variable that makes an internal error print its traceback (as ``--debug``).
DEBUG_ENV = "MSENS_DEBUG"


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as InputError (exit 2, one line)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        # "msens: error: run: ..." (the sub-command, not the program name twice)
        command = self.prog.removeprefix("msens").strip()
        raise InputError(f"{command}: {message}" if command else message)


class _StderrHandler(logging.Handler):
    """Log records as ``msens: <message>`` on the current stderr, above any tqdm bar."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            from tqdm import tqdm

            # tqdm.write clears and redraws an active bar instead of breaking it
            tqdm.write(self.format(record), file=sys.stderr)
        except Exception:  # pragma: no cover - logging must never crash the command
            self.handleError(record)


def _configure_logging(quiet: bool) -> tuple[logging.Handler, int]:
    """Send the ``msens`` loggers to stderr (INFO, or WARNING when quiet).

    Returns the handler and the logger's previous level, for :func:`_restore_logging`.
    """
    log = logging.getLogger("msens")
    handler = _StderrHandler()
    handler.setFormatter(logging.Formatter("msens: %(message)s"))
    log.addHandler(handler)
    previous = log.level
    log.setLevel(logging.WARNING if quiet else logging.INFO)
    return handler, previous


def _restore_logging(handler: logging.Handler, level: int) -> None:
    """Undo :func:`_configure_logging` (main() may run many times in one process)."""
    log = logging.getLogger("msens")
    log.removeHandler(handler)
    log.setLevel(level)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="msens", description="Magnetostrictive sensors on granular chains.")
    p.add_argument("--version", action="version", version=f"msens {version()}")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress messages or bars on stderr (warnings and errors only)")
    p.add_argument("--debug", action="store_true",
                   help=f"print the traceback of an internal error (also {DEBUG_ENV}=1)")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)

    check = sub.add_parser("check-waveform", help="validate waveform files (CSV, NPZ, TDMS)")
    check.add_argument("files", nargs="+", help="waveform files")
    conv = sub.add_parser("convert", help="convert a waveform file between CSV, NPZ and TDMS")
    conv.add_argument("source", help="waveform file to read")
    conv.add_argument("target", help="file to write (.csv, .npz or .tdms; never overwritten)")

    run = sub.add_parser("run", help="run a study (default: the built-in default study)")
    run.add_argument("study", nargs="?", help="study .toml file (default: built-in)")
    run.add_argument("--out", default=None, help="output directory (default: out/<name>)")
    run.add_argument("--no-figures", action="store_true", help="write summary.json only")
    run.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask distributed scheduler for the eddy-current frequency solves "
                          "(default: here)")

    field = sub.add_parser("field", help="solve the sensor's magnetostatic field model")
    field.add_argument("study", help="study .toml file with an mss sensor")
    field.add_argument("--out", required=True, help="output directory")

    sub.add_parser("verify", help="run the field solver's verification problems")

    synth = sub.add_parser("synth", help="synthetic measurements of a study's setup")
    synth.add_argument("study", help="study .toml file")
    synth.add_argument("--out", required=True, help="waveform file (.csv, .npz or .tdms)")
    synth.add_argument("--setup", default=None, help="setup name (default: the first)")
    synth.add_argument("--shots", type=int, default=1, help="repeated shots (default 1)")
    synth.add_argument("--noise", type=float, default=0.01,
                       help="noise std as a fraction of each channel's peak (default 0.01)")
    synth.add_argument("--seed", type=int, default=0, help="random seed (default 0)")

    comp = sub.add_parser("compare", help="compare a measured waveform with the model")
    comp.add_argument("study", help="study .toml file")
    comp.add_argument("data", help="waveform file (.csv, .npz or .tdms)")
    comp.add_argument("--out", required=True, help="output directory")

    diag = sub.add_parser("diagnose", help="find and name the effect the model misses")
    diag.add_argument("data", nargs="?", default=None,
                      help="measured waveform file (.csv, .npz or .tdms)")
    diag.add_argument("--study", default=None,
                      help="study .toml file (default: the built-in paper study)")
    diag.add_argument("--out", required=True, help="output directory")
    diag.add_argument("--reference", metavar="SETUP", default=None,
                      help="feature-only mode: the study's [reference] rows of SETUP "
                           "(e.g. the paper's Table 2) are the measurement; no DATA")
    diag.add_argument("--passes", type=int, default=1,
                      help="diagnosis passes, each adding the previous winner (default 1)")
    for reader in (check, conv, comp, diag):  # an instrument's export: README "Instrument exports"
        reader.add_argument("--columns", metavar="MAP", default=None,
                            help="column map of an oscilloscope/DAQ text export, inline "
                                 "('time=Time:ms,mss@13=CH1:mV,...') or a .toml file")
    des = sub.add_parser("design", help="sweep coil and magnet designs of a study's MsS")
    des.add_argument("study", help="study .toml file with an mss sensor")
    des.add_argument("--sweep", required=True, help="sweep .toml file (schema msens.sweep/1)")
    des.add_argument("--out", required=True, help="output directory (its cache/ resumes runs)")
    des.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask distributed scheduler address (default: local processes)")
    des.add_argument("--workers", type=int, default=None,
                     help="local worker processes (default: all CPUs)")
    uq = sub.add_parser("uq", help="prediction bands and Sobol indices over uncertain inputs")
    uq.add_argument("study", nargs="?", help="study .toml file (default: built-in)")
    uq.add_argument("--inputs", default=None, metavar="FILE",
                    help="uncertain inputs (msens.uncertainty/1; default: the built-in "
                         "file of a built-in study)")
    uq.add_argument("--out", required=True, help="output directory")
    uq.add_argument("--samples", type=int, default=128,
                    help="base samples N, a power of two: N (inputs + 2) runs (default 128)")
    uq.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    uq.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask distributed scheduler address (default: local processes)")
    uq.add_argument("--workers", type=int, default=None,
                    help="local worker processes (default: all CPUs)")
    for command in (run, field, comp, diag, des, uq):
        # the same choices as msens.plots.FORMATS (not imported here: matplotlib is slow)
        command.add_argument("--format", dest="fig_format", choices=("png", "pdf", "svg"),
                             default="png", help="figure file format (default png)")
    for command in sub.choices.values():  # also after the sub-command: "msens run -q"
        # SUPPRESS: an absent sub-command flag must not reset "msens -q run" to False
        command.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                             help="no progress messages or bars on stderr")
    return p


def _run(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study) if args.study else api.load_default()
    out = Path(args.out) if args.out else Path("out") / study.name
    target = api.prepare_outputs(out, figures=not args.no_figures, fig_format=args.fig_format)
    result = api.run(study, scheduler=args.scheduler)
    written = api.write_outputs(result, target, figures=not args.no_figures,
                                fig_format=args.fig_format)
    print(api.format_summary(result))
    print(f"\nwrote {len(written)} files to {out}/: " + ", ".join(p.name for p in written))
    return 0


def _field(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    report = api.field(study, Path(args.out), fig_format=args.fig_format)
    print(report)
    return 0


def _verify(args: argparse.Namespace) -> int:
    from msens.field.verify import format_table, run_all

    rows = run_all()
    print(format_table(rows))
    return 0 if all(r.passed for r in rows) else 1


def _synth(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    path = api.synth(study, args.out, setup=args.setup, shots=args.shots,
                     noise=args.noise, seed=args.seed)
    print(f"wrote {path}")
    return 0


def _data(path: str, columns: str | None):
    """A data file as the readers take it: with its column map (checked now) if given."""
    from msens.io.mapped import mapped

    return mapped(path, columns)


def _compare(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    report, written = api.compare(study, _data(args.data, args.columns), Path(args.out),
                                  fig_format=args.fig_format)
    print(api.format_comparison(report))
    print(f"\nwrote {', '.join(str(p) for p in written)}")
    return 0


def _diagnose(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study) if args.study else api.load_paper_table2()
    if args.columns is not None and args.data is None:
        raise InputError("diagnose: --columns maps the columns of DATA; give DATA")
    data = _data(args.data, args.columns) if args.data else None
    report, written = api.diagnose(study, data, Path(args.out), reference=args.reference,
                                   passes=args.passes, fig_format=args.fig_format)
    print(api.format_diagnosis(report))
    print(f"\nwrote {', '.join(str(p) for p in written)}")
    return 0


def _design(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    result = api.design(study, Path(args.sweep), Path(args.out), scheduler=args.scheduler,
                        workers=args.workers, progress=not args.quiet,
                        fig_format=args.fig_format)
    print(api.format_design(result))
    return 0


def _uq(args: argparse.Namespace) -> int:
    from msens import api
    from msens.uq import run_uq
    from msens.uq.report import format_table

    study = api.load(args.study) if args.study else api.load_default()
    result = run_uq(study, Path(args.out), inputs=args.inputs, samples=args.samples,
                    seed=args.seed, scheduler=args.scheduler, workers=args.workers,
                    fig_format=args.fig_format, progress=not args.quiet)
    print(format_table(result.report))
    print(f"\nwrote {', '.join(str(p) for p in result.written)}")
    return 0


def _check_waveform(args: argparse.Namespace) -> int:
    from msens.io.columns import column_map
    from msens.io.read import main_check

    return main_check(args.files, None if args.columns is None else column_map(args.columns))


def _convert(args: argparse.Namespace) -> int:
    from msens.io.read import describe, read_waveform, write_waveform

    waveform = read_waveform(_data(args.source, args.columns))
    path = write_waveform(waveform, args.target)
    print(f"wrote {path}: {describe(waveform)}")
    return 0


def _internal_error(exc: BaseException, *, debug: bool) -> int:
    """Report an internal error in one line (the traceback with ``--debug`` or
    ``MSENS_DEBUG=1``); returns :data:`EXIT_INTERNAL`."""
    if debug or os.environ.get(DEBUG_ENV, "") not in ("", "0"):
        import traceback

        traceback.print_exception(exc, file=sys.stderr)
    text = " ".join(str(exc).split())[:300]  # bounded: an exception may carry raw data
    print(f"msens: internal error ({type(exc).__name__}: {text}); this is a bug in msens, not "
          f"in your input: please report it to the msens maintainers with the command line (run "
          f"again with --debug or {DEBUG_ENV}=1 for the traceback)", file=sys.stderr)
    return EXIT_INTERNAL


_COMMANDS = {"check-waveform": _check_waveform, "convert": _convert, "run": _run,
             "field": _field, "verify": _verify, "synth": _synth, "compare": _compare,
             "diagnose": _diagnose, "design": _design, "uq": _uq}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``msens`` console script; returns the exit status."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    logging_state = None
    try:
        parser = _parser()
        args = parser.parse_args(argv)
        if args.command is None:  # bare "msens": say what it can do
            parser.print_help()
            return 0
        logging_state = _configure_logging(args.quiet)
        from msens.parallel import allow_pools

        # the console command may start local pools; a script calling main() may lack the
        # __main__ guard their workers need
        with allow_pools(argv is None):
            return _COMMANDS[args.command](args)
    except InputError as exc:
        print(f"msens: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("msens: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: say so, never dressed up as bad input
        return _internal_error(exc, debug="--debug" in (sys.argv if argv is None else argv))
    finally:
        from msens.io import dirlock

        dirlock.release_all()  # main() may run many times in one process (tests, scripts)
        if logging_state is not None:
            _restore_logging(*logging_state)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
