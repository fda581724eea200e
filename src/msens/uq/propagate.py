"""Forward propagation: Saltelli samples of the inputs through the model, bands and indices.

The unit-cube samples come from SALib's Saltelli scheme on a scrambled Sobol' sequence
(:func:`SALib.sample.sobol.sample`, first-order and total indices: N (p + 2) rows for p
inputs), seeded; :meth:`msens.uq.inputs.InputSet.values` maps them through each input's
inverse CDF. The rows are evaluated in chunks (:func:`msens.uq.model.evaluate`) on local
worker processes or a Dask cluster (:func:`msens.parallel.run_tasks`); the result does not
depend on where a chunk ran. Then:

- bands: the 5, 50 and 95 % quantiles of every feature over all rows (each row is a draw
  from the joint distribution), and of every waveform sample over the N "A" and N "B" rows
  of the scheme (2N independent draws);
- Sobol indices: first-order S1 and total ST with their bootstrap confidence intervals from
  :func:`SALib.analyze.sobol.analyze`, per feature.
"""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass

import numpy as np

from msens.config.study import Study
from msens.errors import InputError
from msens.parallel import run_tasks
from msens.progress import heartbeat
from msens.uq.inputs import InputSet
from msens.uq.model import Evaluation, Task, evaluate

_log = logging.getLogger(__name__)

#: Quantiles of the reported bands.
QUANTILES = (0.05, 0.5, 0.95)
#: Confidence level of the indices' intervals, and the bootstrap resamples behind them.
CONFIDENCE = 0.95
RESAMPLES = 200
#: Rows per worker task.
CHUNK = 48


@dataclass(frozen=True)
class Indices:
    """Sobol indices of one output over the propagated inputs.

    Attributes
    ----------
    first, total : ndarray, shape (p,)
        First-order S1 and total ST index of each input.
    first_conf, total_conf : ndarray, shape (p,)
        Half-widths of their :data:`CONFIDENCE` bootstrap intervals.
    note : str
        Why there are none (a constant output, missing features), else "".
    """

    first: np.ndarray
    total: np.ndarray
    first_conf: np.ndarray
    total_conf: np.ndarray
    note: str = ""


@dataclass(frozen=True)
class Propagation:
    """What :func:`propagate` produced.

    Attributes
    ----------
    inputs : InputSet
    base_samples : int
        N of the Saltelli scheme (rows = N (p + 2)).
    seed : int
    unit : ndarray, shape (rows, p)
        Unit-cube samples.
    values : ndarray, shape (rows, p)
        Input values, SI.
    features : dict of str -> ndarray, shape (rows,)
    t : ndarray, shape (nt,)
        Waveform times, s.
    waveforms : dict of str -> ndarray, shape (2N, nt)
        The A and B rows' records.
    indices : dict of str -> Indices
    runs : int
        Chain runs.
    seconds : float
        Wall time of the evaluations, s.
    workers : str
        Where they ran.
    """

    inputs: InputSet
    base_samples: int
    seed: int
    unit: np.ndarray
    values: np.ndarray
    features: dict[str, np.ndarray]
    t: np.ndarray
    waveforms: dict[str, np.ndarray]
    indices: dict[str, Indices]
    runs: int
    seconds: float
    workers: str

    def band(self, name: str) -> np.ndarray:
        """The :data:`QUANTILES` of an output over its finite values (NaN if none)."""
        y = self.features[name]
        y = y[np.isfinite(y)]
        return np.quantile(y, QUANTILES) if y.size else np.full(len(QUANTILES), np.nan)

    def waveform_band(self, name: str) -> np.ndarray:
        """The :data:`QUANTILES` of a waveform at every time, shape (3, nt)."""
        return np.quantile(self.waveforms[name], QUANTILES, axis=0)


def check_samples(samples: int) -> int:
    """N of the Saltelli scheme: a power of two from 4 to 2**16 (Sobol' balance)."""
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 4 or \
            samples > 2**16 or samples & (samples - 1):
        raise InputError(f"--samples must be a power of two from 4 to 65536 (the Sobol' "
                         f"sequence is balanced only then), got {samples!r}")
    return samples


def problem(inputs: InputSet) -> dict:
    """The SALib problem over the unit cube of the propagated inputs."""
    names = [p.name for p in inputs.propagated]
    return {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names)}


def unit_samples(inputs: InputSet, samples: int, seed: int) -> np.ndarray:
    """Saltelli unit-cube samples, shape (N (p + 2), p) (first-order and total indices)."""
    from SALib.sample import sobol

    return sobol.sample(problem(inputs), check_samples(samples), calc_second_order=False,
                        seed=seed)


def ab_rows(p: int, samples: int) -> np.ndarray:
    """Row indices of the A and B matrices in SALib's Saltelli layout (blocks of p + 2 rows:
    A, the p mixed rows, B)."""
    block = np.arange(samples) * (p + 2)
    return np.sort(np.concatenate([block, block + p + 1]))


def sobol_indices(inputs: InputSet, y: np.ndarray, seed: int) -> Indices:
    """First-order and total indices of one output (SALib), or NaN with a note."""
    from SALib.analyze import sobol

    p = len(inputs.propagated)
    nan = np.full(p, np.nan)
    bad = int(np.sum(~np.isfinite(y)))
    if bad:
        return Indices(nan, nan, nan, nan, f"not found in {bad} of {y.size} runs")
    if not np.ptp(y) > 1e-12 * max(float(np.max(np.abs(y))), 1e-300):
        zero = np.zeros(p)
        return Indices(zero, zero, zero, zero, "does not vary with the inputs")
    with warnings.catch_warnings(), np.errstate(divide="ignore", invalid="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        # SALib seeds its bootstrap only for a truthy seed (seed 0 would draw from numpy's
        # global generator: intervals that change from run to run), hence seed + 1
        s = sobol.analyze(problem(inputs), y, calc_second_order=False,
                          num_resamples=RESAMPLES, conf_level=CONFIDENCE, seed=seed + 1)
    return Indices(np.asarray(s["S1"]), np.asarray(s["ST"]), np.asarray(s["S1_conf"]),
                   np.asarray(s["ST_conf"]))


def propagate(study: Study, inputs: InputSet, *, samples: int = 64, seed: int = 0,
              scheduler: str | None = None, workers: int | None = None,
              progress=None) -> Propagation:
    """Propagate ``inputs`` through the model of ``study``.

    Parameters
    ----------
    study : Study
    inputs : InputSet
        From :func:`msens.uq.inputs.load_inputs` for this study.
    samples : int
        N of the Saltelli scheme (a power of two): N (p + 2) model runs per setup.
    seed : int
        Seed of the scrambled Sobol' sequence and of the indices' bootstrap.
    scheduler : str, optional
        Dask scheduler address; default local worker processes.
    workers : int, optional
        Local worker processes (default: all CPUs).
    progress : callable, optional
        Called with (rows done, rows) as chunks finish.

    Returns
    -------
    Propagation
    """
    from msens.pipeline import output_times

    unit = unit_samples(inputs, samples, seed)
    values = inputs.values(unit)
    p = len(inputs.propagated)
    keep = np.zeros(unit.shape[0], dtype=bool)
    keep[ab_rows(p, samples)] = True
    starts = range(0, unit.shape[0], CHUNK)
    tasks = [Task(study, inputs, values[s:s + CHUNK], keep[s:s + CHUNK]) for s in starts]
    _log.info("uq: %d inputs propagated (%d held at nominal), N = %d: %d model runs per "
              "setup in %d tasks", p, len(inputs.held), samples, unit.shape[0], len(tasks))
    start = time.perf_counter()
    parts: list[Evaluation | None] = [None] * len(tasks)
    done = 0
    for i, ev in run_tasks(evaluate, tasks, scheduler=scheduler, workers=workers):
        parts[i] = ev
        done += tasks[i].values.shape[0]
        if progress is not None:
            progress(done, unit.shape[0])
    seconds = time.perf_counter() - start
    names = list(parts[0].features)
    features = {k: np.concatenate([e.features[k] for e in parts]) for k in names}
    waveforms = {k: np.concatenate([e.waveforms[k] for e in parts if k in e.waveforms])
                 for k in parts[0].waveforms}
    _log.info("uq: Sobol indices of %d outputs (SALib, %d bootstrap resamples each)",
              len(features), RESAMPLES)
    with heartbeat(_log, "uq: Sobol indices"):
        indices = {k: sobol_indices(inputs, y, seed) for k, y in features.items()}
    where = f"Dask scheduler {scheduler}" if scheduler else \
        f"local processes ({workers or 'all CPUs'})"
    return Propagation(inputs=inputs, base_samples=samples, seed=seed, unit=unit,
                       values=values, features=features, t=output_times(study),
                       waveforms=waveforms, indices=indices,
                       runs=sum(e.runs for e in parts), seconds=seconds, workers=where)


__all__ = ["CHUNK", "CONFIDENCE", "QUANTILES", "RESAMPLES", "Indices", "Propagation",
           "ab_rows", "check_samples", "problem", "propagate", "sobol_indices", "unit_samples"]
