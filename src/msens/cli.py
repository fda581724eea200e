"""The ``msens`` command.

Each sub-command is a thin wrapper over the public Python API (:mod:`msens.api`), so a
script or notebook gets the same numbers as the terminal. Bad input ends with one message
on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from msens.errors import InputError

EXIT_INPUT = 2


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as InputError (exit 2, one line)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        # "msens: error: run: ..." (the sub-command, not the program name twice)
        command = self.prog.removeprefix("msens").strip()
        raise InputError(f"{command}: {message}" if command else message)


def version() -> str:
    """The installed msens version (from the package metadata)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _version

    try:
        return _version("msens")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "unknown"


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="msens", description="Magnetostrictive sensors on granular chains.")
    p.add_argument("--version", action="version", version=f"msens {version()}")
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
    des = sub.add_parser("design", help="sweep coil and magnet designs of a study's MsS")
    des.add_argument("study", help="study .toml file with an mss sensor")
    des.add_argument("--sweep", required=True, help="sweep .toml file (schema msens.sweep/1)")
    des.add_argument("--out", required=True, help="output directory (its cache/ resumes runs)")
    des.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask distributed scheduler address (default: local processes)")
    des.add_argument("--workers", type=int, default=None,
                     help="local worker processes (default: all CPUs)")
    return p


def _run(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study) if args.study else api.load_default()
    out = Path(args.out) if args.out else Path("out") / study.name
    target = api.prepare_outputs(out, figures=not args.no_figures)
    result = api.run(study)
    written = api.write_outputs(result, target, figures=not args.no_figures)
    print(api.format_summary(result))
    print(f"\nwrote {len(written)} files to {out}/: " + ", ".join(p.name for p in written))
    return 0


def _field(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    report = api.field(study, Path(args.out))
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
    path = api.synth(study, Path(args.out), setup=args.setup, shots=args.shots,
                     noise=args.noise, seed=args.seed)
    print(f"wrote {path}")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    report, written = api.compare(study, Path(args.data), Path(args.out))
    print(api.format_comparison(report))
    print(f"\nwrote {', '.join(str(p) for p in written)}")
    return 0


def _diagnose(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study) if args.study else api.load_paper_table2()
    data = Path(args.data) if args.data else None
    report, written = api.diagnose(study, data, Path(args.out), reference=args.reference,
                                   passes=args.passes)
    print(api.format_diagnosis(report))
    print(f"\nwrote {', '.join(str(p) for p in written)}")
    return 0


def _design(args: argparse.Namespace) -> int:
    from msens import api

    study = api.load(args.study)
    result = api.design(study, Path(args.sweep), Path(args.out), scheduler=args.scheduler,
                        workers=args.workers)
    print(api.format_design(result))
    return 0


def _check_waveform(args: argparse.Namespace) -> int:
    from msens.io.read import main_check

    return main_check(args.files)


def _convert(args: argparse.Namespace) -> int:
    from msens.io.read import describe, read_waveform, write_waveform

    waveform = read_waveform(args.source)
    path = write_waveform(waveform, args.target)
    print(f"wrote {path}: {describe(waveform)}")
    return 0


_COMMANDS = {"check-waveform": _check_waveform, "convert": _convert, "run": _run,
             "field": _field, "verify": _verify, "synth": _synth, "compare": _compare,
             "diagnose": _diagnose, "design": _design}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``msens`` console script; returns the exit status."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        parser = _parser()
        args = parser.parse_args(argv)
        if args.command is None:  # bare "msens": say what it can do
            parser.print_help()
            return 0
        return _COMMANDS[args.command](args)
    except InputError as exc:
        print(f"msens: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("msens: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
