"""The ``msens`` command.

Each sub-command is a thin wrapper over the public Python API (:mod:`msens.api`), so a
script or notebook gets the same numbers as the terminal. Bad input ends with one message
on stderr and exit status 2, never a traceback.

Conventions shared by the sub-commands:

- a study is a ``.toml`` file or the name of a built-in study (``paper-mss``, the default,
  and ``paper-table2``);
- ``--set KEY=VALUE`` (repeatable) changes a key of the study as its file would: a dotted
  key (``striker.drop_height_m``; arrays of tables indexed from 1: ``sensor[1].coil.turns``
  or ``sensor.1.coil.turns``) and a TOML value (a bare word is a string); the changed study
  is validated like a file. ``msens study`` prints or saves the result as TOML;
- ``--out`` defaults to ``out/<study>/`` for ``run`` and ``out/<study>-<command>/`` (a
  file ``out/<study>-synth.csv`` for ``synth``) for the others; a folder's own earlier
  outputs are replaced, a file msens did not write never is; an output *file* that exists
  is replaced only with ``--overwrite``;
- cheap checks (options, suffixes, output paths, the study) come before any work.

Feedback: the command prints a first line on stderr before it loads its numerical
libraries; the library logs its stages through :mod:`logging` (loggers ``msens.*``),
with a heartbeat on long ones (:mod:`msens.progress`), and shows tqdm bars only while those
loggers are at INFO; the command sends them to stderr as ``msens: <message>`` lines.
``-q``/``--quiet`` (before or after the sub-command) sets them to WARNING, which also hides
the bars and the first line.
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

_log = logging.getLogger("msens.cli")

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


#: Built-in studies a study argument may name instead of a file.
BUILTIN_STUDIES = ("paper-mss", "paper-table2")

_STUDY_HELP = ("study: a .toml file, or a built-in study name (paper-mss, paper-table2)")
_SET_HELP = ("change a study key as its TOML file would (repeatable): dotted key, TOML "
             "value, e.g. --set striker.drop_height_m=0.01 --set sensor.1.coil.turns=900")

#: Per sub-command: one-line help, a paragraph, and examples (shown by ``msens CMD -h``).
_DOCS: dict[str, tuple[str, str, str]] = {
    "check-waveform": (
        "validate waveform files (CSV, NPZ, TDMS)",
        "Read each waveform file and check it fully: the time axis (uniform, increasing), "
        "the channel names (bead@13, mss@18, ...) and every number. Prints one line per "
        "file: 'ok' and a summary, or what is wrong and where (file, line, column). An "
        "oscilloscope's own export is read through a column map (--columns).",
        "msens check-waveform shot1.csv shot2.npz\n"
        "msens check-waveform scope.csv --columns time=Time:ms,mss@13=CH1:mV"),
    "convert": (
        "convert a waveform file between CSV, NPZ and TDMS",
        "Read a waveform file (or an instrument's text export through --columns) and write "
        "it in the format TARGET's suffix names (.csv, .npz, .tdms). An existing TARGET is "
        "replaced only with --overwrite.",
        "msens convert shot.csv shot.npz\n"
        "msens convert scope.csv shot.csv --columns time=Time:ms,mss@13=CH1:mV"),
    "run": (
        "run a study (default: the built-in paper-mss study)",
        "Simulate every setup of the study: the chain's solitary wave, each sensor's signal "
        "through its read-out, and the pulse features (time of flight, amplitude ratio). "
        "Writes summary.json and figures to --out (default out/<study>/) and prints the "
        "table. The first run after installing msens compiles the chain kernel once "
        "({compile} on an idle 2-core machine, longer on a busy one; a heartbeat line every "
        "few seconds shows it is working).",
        "msens run\n"
        "msens run paper-table2 --set striker.drop_height_m=0.01 --out out/h10mm"),
    "study": (
        "print a study as TOML, or save it (after --set changes)",
        "Read a study, apply the --set changes (validated like the file), and print it as "
        "TOML, or write it to --out (a .toml file; an existing one only with --overwrite). "
        "The file reads back to the same study, so it is how a changed study is kept.",
        "msens study --set sensor.1.coil.turns=900 --set sensor.2.coil.turns=900 "
        "--out my-coil.toml\nmsens run my-coil.toml"),
    "field": (
        "solve the sensor's magnetostatic field model",
        "Solve the field model of the study's MsS sensors (bias magnet, steel beads, coil): "
        "the coils' resistance and inductance, the beads' flux density and the magnetic "
        "compression of the contacts. Writes field.json, field.vtu (ParaView) and figures "
        "to --out (default out/<study>-field/).",
        "msens field paper-mss\nmsens field my-coil.toml --out out/coil-field"),
    "verify": (
        "run the field solver's verification problems",
        "Solve problems with exact answers (analytic fields, convergence orders) with the "
        "field solver and compare. Prints a line per check as it finishes, then the table; "
        "exit status 1 if a check fails.",
        "msens verify"),
    "synth": (
        "synthetic measurements of a study's setup",
        "Simulate one setup of the study and write what an instrument would record: each "
        "sensor's channel with noise, over --shots repeated shots, as a waveform file "
        "(.csv, .npz or .tdms; default out/<study>-synth.csv). The suffix and the file are "
        "checked before the simulation; an existing file is replaced only with --overwrite.",
        "msens synth paper-table2 --setup bead --shots 3 --out shots.csv"),
    "compare": (
        "compare a measured waveform with the model",
        "Simulate the study's setup that has the data's sensors and compare: aligned "
        "waveforms, features (time of flight, amplitude ratio) with their errors. Writes "
        "comparison.json and overlay figures to --out (default out/<study>-compare/).",
        "msens compare paper-mss examples/data/scope-mss.csv "
        "--columns examples/data/scope-columns.toml"),
    "diagnose": (
        "find and name the effect the model misses",
        "Fit candidate effects the model may miss (a soft wall, a different striker speed, "
        "the coil's position, ...) to the measurement and name the one that explains it. "
        "The measurement is DATA, or with --reference SETUP the study's [reference] rows "
        "(features only). The study defaults to paper-mss, as for run. Writes "
        "diagnosis.json and a figure to --out (default out/<study>-diagnose/).",
        "msens diagnose shot.csv --study paper-table2\n"
        "msens diagnose --study paper-table2 --reference bead"),
    "design": (
        "sweep coil and magnet designs of a study's MsS",
        "Evaluate the designs a sweep file lists (coil turns, length, radii, wire; magnet "
        "grade and position) on the study's MsS: signal, noise, SNR. Writes designs.csv, "
        "recommendation.json and a Pareto figure to --out (default out/<study>-design/); "
        "its cache/ folder resumes an interrupted sweep.",
        "msens design paper-mss --sweep studies/sweep-coil.toml"),
    "uq": (
        "prediction bands and Sobol indices over uncertain inputs",
        "Propagate the study's uncertain inputs (an msens.uncertainty/1 file; the built-in "
        "studies have one) through the model: the prediction as bands around the msens run "
        "numbers, and Sobol indices that say which input to measure better. Writes uq.json "
        "and figures to --out.",
        "msens uq --out out/uq\nmsens uq paper-table2 --samples 64 --out out/uq-table2"),
    "calibrate": (
        "Bayesian calibration of uncertain inputs on a measurement",
        "Sample the posterior of chosen uncertain inputs (their distributions in the "
        "uncertainty file are the priors) given a measured waveform file or a setup's "
        "[reference] rows, with the likelihood msens diagnose uses, by emcee. Writes "
        "calibration.json (posterior, convergence, posterior predictive) and figures "
        "(pairs, predictive band, traces) to --out.",
        "msens calibrate data.csv --study paper-mss --out out/cal\n"
        "msens calibrate --study paper-table2 --reference bead --param striker.drop_height_m "
        "--param chain.gamma_contact_kg_per_s --out out/cal-table2"),
}


def _sub(sub, name: str) -> argparse.ArgumentParser:
    """A sub-command parser with its help line, paragraph and examples."""
    import textwrap

    from msens.progress import COMPILE_ESTIMATE_TEXT

    short, paragraph, examples = _DOCS[name]
    description = textwrap.fill(paragraph.format(compile=COMPILE_ESTIMATE_TEXT), 78)
    epilog = "examples:\n" + "\n".join(f"  {line}" for line in examples.splitlines())
    return sub.add_parser(name, help=short, description=description, epilog=epilog,
                          formatter_class=argparse.RawDescriptionHelpFormatter)


def _study_options(command: argparse.ArgumentParser, *, positional: bool = True) -> None:
    """The study argument and ``--set`` of a command that takes a study."""
    if positional:
        command.add_argument("study", nargs="?", default=None,
                             help=f"{_STUDY_HELP}; default paper-mss")
    command.add_argument("--set", dest="sets", action="append", default=[],
                         metavar="KEY=VALUE", help=_SET_HELP)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="msens", description="Magnetostrictive sensors on granular chains. "
                "'msens COMMAND -h' explains a command, with examples.")
    p.add_argument("--version", action="version", version=f"msens {version()}")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress messages or bars on stderr (warnings and errors only)")
    p.add_argument("--debug", action="store_true",
                   help=f"print the traceback of an internal error (also {DEBUG_ENV}=1)")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)

    check = _sub(sub, "check-waveform")
    check.add_argument("files", nargs="+", help="waveform files")
    conv = _sub(sub, "convert")
    conv.add_argument("source", help="waveform file to read")
    conv.add_argument("target", help="file to write (.csv, .npz or .tdms)")
    conv.add_argument("--overwrite", action="store_true", help="replace TARGET if it exists")

    run = _sub(sub, "run")
    _study_options(run)
    run.add_argument("--out", default=None, help="output directory (default: out/<study>/)")
    run.add_argument("--no-figures", action="store_true", help="write summary.json only")
    run.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask distributed scheduler for the eddy-current frequency solves "
                          "(default: here)")

    study = _sub(sub, "study")
    _study_options(study)
    study.add_argument("--out", default=None, metavar="FILE",
                       help="write the study to this .toml file (default: print it)")
    study.add_argument("--overwrite", action="store_true", help="replace FILE if it exists")

    field = _sub(sub, "field")
    _study_options(field)
    field.add_argument("--out", default=None,
                       help="output directory (default: out/<study>-field/)")

    _sub(sub, "verify")

    synth = _sub(sub, "synth")
    _study_options(synth)
    synth.add_argument("--out", default=None,
                       help="waveform file: .csv, .npz or .tdms (default: "
                            "out/<study>-synth.csv)")
    synth.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    synth.add_argument("--setup", default=None, help="setup name (default: the first)")
    synth.add_argument("--shots", type=int, default=1, help="repeated shots (default 1)")
    synth.add_argument("--noise", type=float, default=0.01,
                       help="noise std as a fraction of each channel's peak (default 0.01)")
    synth.add_argument("--seed", type=int, default=0, help="random seed (default 0)")

    comp = _sub(sub, "compare")
    comp.add_argument("study", help=_STUDY_HELP)
    comp.add_argument("data", help="waveform file (.csv, .npz or .tdms)")
    _study_options(comp, positional=False)
    comp.add_argument("--out", default=None,
                      help="output directory (default: out/<study>-compare/)")

    diag = _sub(sub, "diagnose")
    diag.add_argument("data", nargs="?", default=None,
                      help="measured waveform file (.csv, .npz or .tdms)")
    diag.add_argument("--study", default=None,
                      help=f"{_STUDY_HELP}; default paper-mss, as for run")
    _study_options(diag, positional=False)
    diag.add_argument("--out", default=None,
                      help="output directory (default: out/<study>-diagnose/)")
    diag.add_argument("--reference", metavar="SETUP", default=None,
                      help="feature-only mode: the study's [reference] rows of SETUP "
                           "(e.g. the paper's Table 2) are the measurement; no DATA")
    diag.add_argument("--passes", type=int, default=1,
                      help="diagnosis passes, each adding the previous winner (default 1)")
    for reader in (check, conv, comp, diag):  # an instrument's export: README "Instrument exports"
        reader.add_argument("--columns", metavar="MAP", default=None,
                            help="column map of an oscilloscope/DAQ text export, inline "
                                 "('time=Time:ms,mss@13=CH1:mV,...') or a .toml file")
    des = _sub(sub, "design")
    _study_options(des)
    des.add_argument("--sweep", required=True, help="sweep .toml file (schema msens.sweep/1)")
    des.add_argument("--out", default=None, help="output directory (default: "
                     "out/<study>-design/; its cache/ resumes runs)")
    des.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask distributed scheduler address (default: local processes)")
    des.add_argument("--workers", type=int, default=None,
                     help="local worker processes (default: all CPUs)")
    uq = _sub(sub, "uq")
    uq.add_argument("study", nargs="?", help="study .toml file (default: built-in)")
    uq.add_argument("--inputs", default=None, metavar="FILE",
                    help="uncertain inputs (msens.uncertainty/1; default: the built-in "
                         "file of a built-in study)")
    uq.add_argument("--out", required=True, help="output directory")
    uq.add_argument("--samples", type=int, default=256,
                    help="base samples N, a power of two: N (inputs + 2) runs (default 256)")
    uq.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    uq.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask distributed scheduler address (default: local processes)")
    uq.add_argument("--workers", type=int, default=None,
                    help="local worker processes (default: all CPUs)")
    cal = _sub(sub, "calibrate")
    cal.add_argument("data", nargs="?", default=None,
                     help="measured waveform file (.csv, .npz or .tdms)")
    cal.add_argument("--study", default=None, help=f"{_STUDY_HELP}; default paper-mss")
    _study_options(cal, positional=False)
    cal.add_argument("--reference", metavar="SETUP", default=None,
                     help="the study's [reference] rows of SETUP (TOF and AR with their std, "
                          "e.g. the paper's Table 2) are the measurement; no DATA")
    cal.add_argument("--columns", metavar="MAP", default=None,
                     help="column map of an oscilloscope/DAQ text export (as for diagnose)")
    cal.add_argument("--inputs", default=None, metavar="FILE",
                     help="uncertain inputs, the priors (msens.uncertainty/1; default: the "
                          "built-in file of a built-in study)")
    cal.add_argument("--param", dest="params", action="append", default=None, metavar="NAME",
                     help="an input to calibrate (repeat for more; default: drop height, "
                          "contact damping and the magnet's remanence where the file "
                          "samples them); the others are held at their nominal values")
    cal.add_argument("--walkers", type=int, default=None,
                     help="emcee walkers, even, >= 2 x inputs (default max(16, 4 x inputs))")
    cal.add_argument("--steps", type=int, default=1000,
                     help="steps per walker, the first half burn-in (default 1000)")
    cal.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    cal.add_argument("--out", default=None,
                     help="output directory (default: out/<study>-calibrate/)")
    for command in (run, field, comp, diag, des, uq, cal):
        # the same choices as msens.plots.FORMATS (not imported here: matplotlib is slow)
        command.add_argument("--format", dest="fig_format", choices=("png", "pdf", "svg"),
                             default="png", help="figure file format (default png)")
    for command in sub.choices.values():  # also after the sub-command: "msens run -q"
        # SUPPRESS: an absent sub-command flag must not reset "msens -q run" to False
        command.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                             help="no progress messages or bars on stderr")
    return p


def parse_sets(items: Sequence[str]) -> dict[str, object]:
    """``--set KEY=VALUE`` items as :meth:`msens.config.study.Study.replace` takes them.

    A key is dotted; a numeric part indexes the array of tables before it, from 1
    (``sensor.1.coil.turns`` is ``sensor[1].coil.turns``). A value is read as TOML
    (``0.01``, ``true``, ``"AWG36"``, ``[1, 2]``, ``{ grade = "N42" }``); text that is not
    TOML is a string (``--set sensor.1.coil.wire=AWG36``).

    Raises
    ------
    InputError
        For an item without ``=`` or a key, or a key given twice.
    """
    import tomllib

    changes: dict[str, object] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(f"--set {item!r}: expected KEY=VALUE, e.g. "
                             "--set striker.drop_height_m=0.01")
        parts: list[str] = []
        for part in key.split("."):
            if part.isdigit() and parts and not parts[-1].endswith("]"):
                parts[-1] += f"[{part}]"  # sensor.1 -> sensor[1]
            else:
                parts.append(part)
        key = ".".join(parts)
        if key in changes:
            raise InputError(f"--set {key} given twice")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()  # a bare word: a string
        changes[key] = value
    return changes


def _study_path(name: str | None) -> Path:
    """The file of a study argument: a path, or a built-in study's name."""
    from msens.config.study import builtin_study_path, default_study_path

    if name is None:
        return default_study_path()
    path = Path(name)
    if name in BUILTIN_STUDIES and not path.exists():
        return builtin_study_path(name)
    return path


def _load_study(name: str | None, sets: Sequence[str] = ()):
    """Read a study (a file or a built-in name) and apply ``--set`` changes."""
    changes = parse_sets(sets)  # checked before the (slower) study import
    from msens.progress import heartbeat

    with heartbeat(_log, "loading the study reader"):  # imports numpy, scipy, numba
        from msens.config.study import load_study

    study = load_study(_study_path(name))
    if changes:
        study = study.replace(changes)
    _log.info("study %s read from %s%s", study.name, _study_path(name),
              f" with {len(changes)} --set change(s)" if changes else "")
    return study


def _output_file(value: object, option: str, suffixes: tuple[str, ...] | None = None, *,
                 overwrite: bool) -> Path:
    """An output file checked before any work (suffix, folder); an existing one is refused
    unless ``overwrite``, naming the option that replaces it."""
    from msens import preflight

    kwargs = {} if suffixes is None else {"suffixes": suffixes}
    path = preflight.output_file(value, option, overwrite=True, **kwargs)
    if not overwrite and (path.exists() or path.is_symlink()):
        raise InputError(f"{option} '{path}': file exists; msens replaces it only with "
                         "--overwrite (or choose another name)")
    return path


def _api():
    """:mod:`msens.api`, imported with a heartbeat (seconds on a busy machine)."""
    from msens.progress import heartbeat

    with heartbeat(_log, "loading the model code"):
        from msens import api
    return api


def _out(args: argparse.Namespace, study, command: str) -> Path:
    """``--out``, or its default: ``out/<study>/`` for run, else ``out/<study>-<command>/``."""
    if args.out is not None:
        return Path(args.out)
    return Path("out") / (study.name if command == "run" else f"{study.name}-{command}")


def _run(args: argparse.Namespace) -> int:
    from msens import preflight

    if args.out is not None:
        preflight.output_dir(args.out)
    study = _load_study(args.study, args.sets)
    api = _api()

    out = _out(args, study, "run")
    target = api.prepare_outputs(out, figures=not args.no_figures, fig_format=args.fig_format)
    result = api.run(study, scheduler=args.scheduler)
    from msens.progress import heartbeat

    _log.info("run: writing summary.json%s to %s", "" if args.no_figures else " and figures",
              out)
    with heartbeat(_log, "run: writing the outputs"):
        written = api.write_outputs(result, target, figures=not args.no_figures,
                                    fig_format=args.fig_format)
    print(result.table())
    print(f"\nwrote {len(written)} files to {out}/: " + ", ".join(p.name for p in written))
    return 0


def _study(args: argparse.Namespace) -> int:
    if args.out is not None:
        _output_file(args.out, "--out", (".toml",), overwrite=args.overwrite)
    study = _load_study(args.study, args.sets)
    from msens.config.dump import study_toml

    text = study_toml(study)
    if args.out is None:
        print(text, end="")
        return 0
    from msens.io.atomic import atomic_write_bytes

    atomic_write_bytes(Path(args.out), text.encode("utf-8"), overwrite=args.overwrite)
    print(f"wrote {args.out} (study {study.name}; 'msens run {args.out}' runs it)")
    return 0


def _field(args: argparse.Namespace) -> int:
    from msens import preflight

    if args.out is not None:
        preflight.output_dir(args.out)
    study = _load_study(args.study, args.sets)
    api = _api()

    result = api.field(study, _out(args, study, "field"), fig_format=args.fig_format)
    print(result.table())
    return 0


def _verify(args: argparse.Namespace) -> int:
    from msens.field.verify import format_table, run_all

    rows = run_all(progress=lambda row: _log.info(
        "verify: %s %s", row.name, "passed" if row.passed else "FAILED"))
    print(format_table(rows))
    return 0 if all(r.passed for r in rows) else 1


def _synth(args: argparse.Namespace) -> int:
    if args.out is not None:  # the suffix and the file, before any work
        _output_file(args.out, "--out", overwrite=args.overwrite)
    study = _load_study(args.study, args.sets)
    api = _api()

    out = Path(args.out) if args.out else Path("out") / f"{study.name}-synth.csv"
    _output_file(out, "--out", overwrite=args.overwrite)
    if args.out is None:
        out.parent.mkdir(parents=True, exist_ok=True)
    result = api.synth(study, out, setup=args.setup, shots=args.shots, noise=args.noise,
                       seed=args.seed, overwrite=args.overwrite)
    print(result.table())
    return 0


def _data(path: str, columns: str | None):
    """A data file as the readers take it: with its column map (checked now) if given."""
    from msens.io.mapped import mapped

    return mapped(path, columns)


def _compare(args: argparse.Namespace) -> int:
    from msens import preflight

    if args.out is not None:
        preflight.output_dir(args.out)
    data = _data(args.data, args.columns)
    study = _load_study(args.study, args.sets)
    api = _api()

    result = api.compare(study, data, _out(args, study, "compare"), fig_format=args.fig_format)
    print(result.table())
    return 0


def _diagnose(args: argparse.Namespace) -> int:
    from msens import preflight

    if args.columns is not None and args.data is None:
        raise InputError("diagnose: --columns maps the columns of DATA; give DATA")
    if args.out is not None:
        preflight.output_dir(args.out)
    data = _data(args.data, args.columns) if args.data else None
    study = _load_study(args.study, args.sets)
    api = _api()

    result = api.diagnose(study, data, _out(args, study, "diagnose"), reference=args.reference,
                          passes=args.passes, fig_format=args.fig_format)
    print(result.table())
    return 0


def _design(args: argparse.Namespace) -> int:
    from msens import preflight

    if args.out is not None:
        preflight.output_dir(args.out)
    study = _load_study(args.study, args.sets)
    api = _api()

    result = api.design(study, Path(args.sweep), _out(args, study, "design"),
                        scheduler=args.scheduler, workers=args.workers,
                        progress=not args.quiet, fig_format=args.fig_format)
    print(result.table())
    return 0


def _uq(args: argparse.Namespace) -> int:
    api = _api()
    from msens.uq import run_uq

    study = api.load(args.study) if args.study else api.load_default()
    result = run_uq(study, Path(args.out), inputs=args.inputs, samples=args.samples,
                    seed=args.seed, scheduler=args.scheduler, workers=args.workers,
                    fig_format=args.fig_format, progress=not args.quiet)
    print(result.table())
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    from msens import preflight

    if args.columns is not None and args.data is None:
        raise InputError("calibrate: --columns maps the columns of DATA; give DATA")
    if args.out is not None:
        preflight.output_dir(args.out)
    study = _load_study(args.study, args.sets)
    waveform = None
    if args.data is not None:
        from msens.io.read import read_waveform

        waveform = read_waveform(_data(args.data, args.columns))
    from msens.uq.calibration import run_calibrate

    result = run_calibrate(study, _out(args, study, "calibrate"), data=waveform,
                           reference=args.reference, inputs=args.inputs, params=args.params,
                           walkers=args.walkers, steps=args.steps, seed=args.seed,
                           fig_format=args.fig_format, progress=not args.quiet)
    print(result.table())
    return 0


def _check_waveform(args: argparse.Namespace) -> int:
    from msens.io.columns import column_map
    from msens.io.read import main_check

    return main_check(args.files, None if args.columns is None else column_map(args.columns))


def _convert(args: argparse.Namespace) -> int:
    # the target first: a bad suffix or an existing file is refused before reading
    _output_file(args.target, "TARGET", overwrite=args.overwrite)
    from msens.io.read import describe, read_waveform, write_waveform

    waveform = read_waveform(_data(args.source, args.columns))
    path = write_waveform(waveform, args.target, overwrite=args.overwrite)
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
             "study": _study, "field": _field, "verify": _verify, "synth": _synth,
             "compare": _compare, "diagnose": _diagnose, "design": _design, "uq": _uq,
             "calibrate": _calibrate}

#: What the first line says each command does first (before its libraries load).
_FIRST = {"check-waveform": "reading {n} file(s)", "convert": "reading {source}",
          "verify": "loading the field solver", "study": "reading the study"}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``msens`` console script; returns the exit status."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    from msens.numba_cache import use_user_cache

    use_user_cache()  # compiled code in the user cache folder: it survives reinstalling
    logging_state = None
    try:
        parser = _parser()
        args = parser.parse_args(argv)
        if args.command is None:  # bare "msens": say what it can do
            parser.print_help()
            return 0
        logging_state = _configure_logging(args.quiet)
        # the first line, before the numerical libraries load (seconds on a busy machine)
        first = _FIRST.get(args.command, "loading study {study} and the model code")
        _log.info("%s: %s", args.command, first.format(
            n=len(getattr(args, "files", ())), source=getattr(args, "source", ""),
            study=getattr(args, "study", None) or "paper-mss (built-in)"))
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
        if argv is None:
            # the console command ends here: the interpreter's last garbage collection over
            # the model's millions of objects took 2-6 s after the output (nothing to free
            # that exit does not); frozen objects are skipped by it
            import gc

            gc.freeze()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
