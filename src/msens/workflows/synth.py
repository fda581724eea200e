"""The synth workflow: synthetic measurements of one setup of a study, written to a file.

The request is checked before anything is simulated (the options' ranges, a setup the study
has, the output file, and the memory the shots need); then the study runs once and its
records pass through the rig effects of :mod:`msens.synth` (amplifier gain, offset, trigger
delay, noise) into a waveform file.
"""

from __future__ import annotations

from pathlib import Path

from msens import preflight
from msens.config import plausible
from msens.config.study import Study
from msens.errors import InputError
from msens.io.read import write_waveform
from msens.pipeline import run_study
from msens.synth import RigEffects, synthesize


def synth(study: Study, out: Path, *, setup: str | None = None, shots: int = 1,
          noise: float = 0.01, seed: int = 0, overwrite: bool = False) -> Path:
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
    Path
        ``out``.

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
    name = setup or names[0]
    if name not in names:
        raise InputError(f"--setup must be one of {', '.join(names)}, got {name!r}")
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
    return out
