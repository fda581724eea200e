"""The synth workflow: synthetic measurements of one setup of a study, written to a file.

The request is checked before anything is simulated (the options' ranges, a setup the study
has, the output file, and the memory the shots need); then the study runs once and its
records pass through the rig effects of :mod:`msens.synth` (amplifier gain, offset, trigger
delay, noise) into a waveform file, returned as a :class:`SynthResult` (path-like: it
passes wherever the file's path does).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from msens import preflight
from msens.config import plausible
from msens.config.study import Study
from msens.errors import InputError, shorten
from msens.io.read import write_waveform
from msens.pipeline import run_study
from msens.synth import RigEffects, synthesize
from msens.tables import files_line
from msens.workflows.common import provenance


@dataclass(frozen=True)
class SynthResult(os.PathLike):
    """What ``synth`` produced: a waveform file of synthetic measurements.

    Path-like (``os.fspath``, ``str`` and :func:`msens.read_waveform` give the file), so it
    passes wherever the file's path does, as a column-mapped file does; the file's
    :class:`~pathlib.Path` methods (``read_bytes``, ``exists``...) work on it too.

    Attributes
    ----------
    path : Path
        The waveform file written (CSV, NPZ or TDMS).
    study : str
        The study's name.
    setup : str
        The setup simulated.
    channels : tuple of str
        The file's channels (``mss@13``, ...).
    shots : int
        Repeated shots.
    samples : int
        Samples per record.
    noise : float
        Noise as a fraction of each channel's peak.
    seed : int
        Seed of the rig effects' random numbers.
    provenance : dict
        The msens version and the study's content hash.
    """

    path: Path
    study: str
    setup: str
    channels: tuple[str, ...]
    shots: int
    samples: int
    noise: float
    seed: int
    provenance: dict

    def __fspath__(self) -> str:
        return os.fspath(self.path)

    def __str__(self) -> str:
        return str(self.path)

    def __getattr__(self, name: str):
        """The file's :class:`~pathlib.Path` methods and attributes (``read_bytes``,
        ``suffix``...): code written when ``synth`` returned the path keeps working."""
        if name.startswith("__") or name == "path":  # not during copying or unpickling
            raise AttributeError(name)
        return getattr(self.path, name)

    @property
    def files(self) -> tuple[Path, ...]:
        """The files written (the waveform file)."""
        return (self.path,)

    @property
    def figures(self) -> tuple[Path, ...]:
        """The figures written: none (``msens compare`` draws the records)."""
        return ()

    def to_json(self) -> dict:
        """What was synthesised, as JSON values (synth writes no JSON file of its own)."""
        return {"file": str(self.path), "study": self.study, "setup": self.setup,
                "channels": list(self.channels), "shots": self.shots,
                "samples": self.samples, "noise": self.noise, "seed": self.seed,
                "provenance": dict(self.provenance)}

    def table(self) -> str:
        """What ``msens synth`` prints: the file written."""
        return files_line(self.files)


def synth(study: Study, out: Path, *, setup: str | None = None, shots: int = 1,
          noise: float = 0.01, seed: int = 0, overwrite: bool = False) -> SynthResult:
    """Write synthetic measurements of one setup of ``study`` to ``out`` (never over an
    existing file unless ``overwrite``).

    Parameters
    ----------
    study : Study
    out : Path
        The waveform file (CSV, NPZ or TDMS by its suffix).
    setup : str, optional
        The setup's name; default the study's first.
    shots : int
        Repeated shots, 1 to 10000.
    noise : float
        Noise as a fraction of the peak, 0 to 1.
    seed : int
        Seed of the rig effects' random numbers, 0 to 2**63 - 1.
    overwrite : bool
        Replace ``out`` if it exists.

    Returns
    -------
    SynthResult
        The file ``out`` (path-like) and what was synthesised.

    Raises
    ------
    InputError
        Naming the option and what is allowed, before anything is simulated (also when the
        shots would need more memory than :data:`msens.config.plausible.MEMORY_BUDGET_BYTES`).
    """
    preflight.study(study)
    out = preflight.output_file(out, "--out", overwrite=overwrite)
    shots = preflight.count(shots, "--shots", 1, 10000)
    noise = preflight.number(noise, "--noise", 0.0, 1.0, " (fraction of the peak)")
    seed = preflight.count(seed, "--seed", 0, 2**63 - 1)
    if not 0 <= seed < 2**63:  # numpy's generators take non-negative seeds
        raise InputError(f"--seed must be from 0 to 2**63 - 1, got {seed}")
    names = [s.name for s in study.setups]
    name = names[0] if setup is None else setup  # '' or [] is not "the first setup"
    if not isinstance(name, str) or name not in names:
        raise InputError(f"--setup must be one of {', '.join(names)}, got {shorten(name)}")
    if out.exists() and not overwrite:
        raise InputError(f"refusing to overwrite '{out}' (the command's --overwrite replaces it)")
    chosen_setup = study.setup(name)
    samples = round(study.simulation.t_end_s * study.simulation.sample_rate_hz) + 1
    # the shots' records and the rig effects' working copies (about four) in float64
    need = 4 * 8 * shots * samples * len(chosen_setup.sensors)
    if need > plausible.MEMORY_BUDGET_BYTES:
        raise InputError(f"--shots {shots} of {samples:,} samples x "
                         f"{len(chosen_setup.sensors)} channels need about "
                         f"{need / 2**30:.3g} GiB; the budget is "
                         f"{plausible.MEMORY_BUDGET_BYTES / 2**30:g} GiB: fewer shots, or a "
                         "shorter 'simulation.t_end_s'")
    result = run_study(study)
    chosen = next(s for s in result.setups if s.setup.name == name)
    meta = {"study": study.name}
    if study.striker.drop_height_m is not None:
        meta["drop_height_m"] = repr(study.striker.drop_height_m)
    waveform = synthesize(chosen, RigEffects(shots=shots, noise=noise, seed=seed),
                          metadata=meta)
    write_waveform(waveform, out, overwrite=overwrite)
    return SynthResult(out, study.name, name, tuple(c.name for c in waveform.channels),
                       shots, len(waveform.time), noise, seed, provenance(study))
