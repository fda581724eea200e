"""``msens calibrate``: what a measurement says about a study's uncertain inputs.

Order of work: every check of the user's input first (output folder, figure format, sampler
settings, the uncertainty file against the study, the inputs to calibrate, the measured
file against the study's setups), so that bad input ends in one
:class:`~msens.errors.InputError` before any simulation; then the study's Eq. 10 dissipation
fit if it asks for one (its values become the nominal ones); the likelihood
(:mod:`msens.uq.posterior`); a start point and the ensemble sampler (:mod:`msens.uq.mcmc`);
the posterior predictive (model runs at posterior draws: every setup's features, and the
measured channels' band); and the files (:mod:`msens.uq.calibration_report`).

The sampler evaluates its walkers in batches in this process (a half-step of 8 walkers is
one batch of chain runs); the predictive runs are few.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from msens.config.study import Study
from msens.errors import InputError
from msens.io.output import DPI, OutputDir
from msens.parallel import one_blas_thread
from msens.progress import heartbeat, refreshing
from msens.results import JsonReport
from msens.uq.inputs import InputSet, load_inputs
from msens.uq.mcmc import (
    RHAT_LIMIT,
    START_DRAWS,
    Chains,
    autocorr_time,
    laplace_covariance,
    sample,
    split_rhat,
    start_point,
)
from msens.uq.posterior import Coordinates, Likelihood, Posterior, select

_log = logging.getLogger(__name__)

FILES = ("calibration.json", "calibration_pairs.png", "calibration_predictive.png",
         "calibration_trace.png")
#: Default steps of every walker (the first half is burn-in).
DEFAULT_STEPS = 1000
#: Posterior draws run again for the posterior predictive.
PREDICTIVE_DRAWS = 64
#: Bounds of the sampler settings.
MAX_STEPS, MAX_WALKERS = 100_000, 1_000


@dataclass(frozen=True)
class Calibration:
    """What :func:`run_calibrate` found.

    Attributes
    ----------
    mode : {"waveform", "features"}
    setup : str
        The setup the measurement belongs to.
    measurement : str
        The file, or ``[reference] rows of <setup>``.
    coords : Coordinates
    chains : Chains
    samples : ndarray, shape (draws, k)
        Kept posterior samples of the calibrated inputs, SI.
    rhat, tau, ess : ndarray, shape (k,)
        Split R-hat, autocorrelation time (steps) and effective sample size of each input.
    chi2_best, n_obs : float
        chi^2 at the best sample visited and the number of observations it sums over.
    predictive : dict of str -> ndarray, shape (draws,)
        Every setup's features at the predictive draws (``setup/sensor/feature``).
    reference : list of dict
        The study's ``[reference]`` rows with the predictive band of their features.
    band : dict or None
        Waveform mode: the measured channels (``data``, shape (sensors, n), on ``t_us``:
        time since impact with the draws' median impact-to-trigger offset ``delay_us``),
        their noise std and the 5/50/95 % quantiles of the calibrated model on them
        (``model``, shape (3, sensors, n)).
    variance : dict
        The likelihood's variance split (noise, model uncertainty).
    runs : int
        Model runs made.
    seconds : float
        Wall time, s.
    """

    mode: str
    setup: str
    measurement: str
    coords: Coordinates
    chains: Chains
    samples: np.ndarray
    rhat: np.ndarray
    tau: np.ndarray
    ess: np.ndarray
    chi2_best: float
    n_obs: float
    predictive: dict[str, np.ndarray]
    reference: list[dict]
    band: dict | None
    variance: dict
    runs: int
    seconds: float

    @property
    def converged(self) -> bool:
        """Whether every input's split R-hat is at most :data:`~msens.uq.mcmc.RHAT_LIMIT`."""
        return bool(np.all(np.isfinite(self.rhat)) and np.all(self.rhat <= RHAT_LIMIT))


@dataclass(frozen=True)
class CalibrateResult(JsonReport):
    """What :func:`run_calibrate` returns: the calibration, ``calibration.json``'s content
    and the files written."""

    calibration: Calibration
    report: dict
    written: tuple[Path, ...]

    def table(self) -> str:
        """What ``msens calibrate`` prints: the table
        (:func:`msens.uq.calibration_report.format_table`) and the files written."""
        from msens.tables import files_line
        from msens.uq.calibration_report import format_table

        return f"{format_table(self.report)}\n\n{files_line(self.written)}"


def check_sampler(walkers: int | None, steps: int, k: int) -> int:
    """The number of walkers (default max(16, 4 k), even), after checking both settings.

    Raises
    ------
    InputError
        Walkers odd, fewer than 2 k or more than :data:`MAX_WALKERS`; steps not a whole
        number from 20 to :data:`MAX_STEPS`.
    """
    if isinstance(steps, bool) or not isinstance(steps, int) or not 20 <= steps <= MAX_STEPS:
        raise InputError(f"--steps must be a whole number from 20 to {MAX_STEPS}, got {steps!r}")
    if walkers is None:
        walkers = max(16, 4 * k)
        walkers += walkers % 2
    if isinstance(walkers, bool) or not isinstance(walkers, int) or walkers % 2 or \
            not 2 * k <= walkers <= MAX_WALKERS:
        raise InputError(f"--walkers must be an even whole number from {max(2 * k, 2)} (twice "
                         f"the {k} calibrated inputs) to {MAX_WALKERS}, got {walkers!r}")
    return walkers


def _objective(study: Study, data, reference: str | None):
    # the measurement's likelihood (the one diagnose uses) and its setup; a measured file is
    # matched to a setup and its channels checked before anything is simulated
    from msens.diagnose.objective import FeatureObjective
    from msens.diagnose.predict import positions
    from msens.diagnose.workflow import waveform_baseline
    from msens.pipeline import output_times

    if reference is None:
        b = waveform_baseline(data, study)
        return b.objective, b.ctx.setup, str(getattr(data, "path", "the measured file"))
    setup = study.setup(reference)
    rows = {r.position: r for r in study.reference if r.setup == reference}
    where = positions([s.particle for s in setup.sensors])
    return (FeatureObjective(setup, rows, where, output_times(study)), setup,
            f"[reference] rows of {reference}")


def _check_reference(study: Study, reference: str) -> None:
    names = [s.name for s in study.setups]
    if reference not in names:
        raise InputError(f"--reference must be one of the study's setups {', '.join(names)}, "
                         f"got {reference!r}")
    if not any(r.setup == reference for r in study.reference):
        with_rows = sorted({r.setup for r in study.reference})
        raise InputError(f"the study {study.name!r} has no [reference] rows for setup "
                         f"{reference!r}" + (f"; it has rows for {', '.join(with_rows)}"
                                             if with_rows else ""))


def predictive(study: Study, inputs: InputSet, coords: Coordinates, theta: np.ndarray,
               objective, setup_name: str, rng: np.random.Generator
               ) -> tuple[dict, list[dict], dict | None]:
    """The model at posterior draws: every setup's features, the reference rows' band, and
    (waveform mode) the band of the calibrated model over the measured channels.

    Parameters
    ----------
    study : Study
    inputs : InputSet
    coords : Coordinates
    theta : ndarray, shape (draws, k)
        Posterior draws of the calibrated inputs, SI.
    objective : WaveformObjective or FeatureObjective
        The measurement's objective (its setup is ``setup_name``).
    setup_name : str
    rng : numpy.random.Generator
        Draws of the measurement scatter.

    Returns
    -------
    features : dict of str -> ndarray, shape (draws,)
    reference : list of dict
        Per ``[reference]`` row: measured TOF and AR with std, the model's 5/50/95 %
        quantiles, the 5-95 % band of a measurement (the model at the draws plus the
        row's std as Gaussian scatter), and whether the measured value lies inside it.
    band : dict or None
    """
    from msens.diagnose.objective import FeatureObjective, WaveformObjective
    from msens.diagnose.predict import positions
    from msens.pipeline import output_times
    from msens.uq.model import Task, evaluate

    rows = coords.rows(theta)
    ev = evaluate(Task(study, inputs, rows, np.ones(rows.shape[0], bool), precise=True))
    t = output_times(study)
    reference = []
    for setup in study.setups:
        refs = {r.position: r for r in study.reference if r.setup == setup.name}
        if not refs:
            continue
        where = positions([s.particle for s in setup.sensors])
        fo = FeatureObjective(setup, refs, where, t)
        keys = [f"{setup.name}/{s.kind.value}@{s.particle}" for s in setup.sensors]
        recs = np.stack([ev.waveforms[k] for k in keys], axis=1)
        f = np.array([fo.features(r) for r in recs])  # (draws, sensors, 2)
        for j, pos in enumerate(where):
            r = refs.get(pos)
            if r is None:
                continue
            entry = {"setup": setup.name, "position": pos, "sensor": keys[j].split("/")[1],
                     "calibrated_on": setup.name == setup_name}
            for i, (name, meas, std) in enumerate((("tof_us", r.tof_us, r.tof_std_us),
                                                   ("ar", r.ar, r.ar_std))):
                v = f[:, j, i]
                v = v[np.isfinite(v)]
                q = np.quantile(v, (0.05, 0.5, 0.95)) if v.size else np.full(3, np.nan)
                # what a measurement would show: the model plus the measurement's own scatter
                m = v + std * rng.standard_normal(v.size) if v.size else v
                qm = np.quantile(m, (0.05, 0.95)) if m.size else np.full(2, np.nan)
                entry[name] = {"measured": meas, "measured_std": std,
                               "model_5_50_95": [float(x) for x in q],
                               "measurement_5_95": [float(x) for x in qm],
                               "inside_90": bool(qm[0] <= meas <= qm[1])}
            reference.append(entry)
    band = None
    if isinstance(objective, WaveformObjective):
        setup = study.setup(setup_name)
        keys = [f"{setup.name}/{s.kind.value}@{s.particle}" for s in setup.sensors]
        recs = np.stack([ev.waveforms[k] for k in keys], axis=1)
        shot = objective.shots[0]
        aligned = [objective.aligned(r)[0] for r in recs]
        models = np.array([m for _, _, m in aligned])  # (draws, sensors, n)
        delay = float(np.median([a.delay for a, _, _ in aligned]))  # impact to trigger
        band = {"channels": [k.split("/")[1] for k in keys], "t_us": (shot.tau + delay) * 1e6,
                "delay_us": delay * 1e6,
                "data": shot.y, "noise_std": np.sqrt(1.0 / shot.w),
                "model": np.quantile(models, (0.05, 0.5, 0.95), axis=0)}
    return ev.features, reference, band


@one_blas_thread()
def run_calibrate(study: Study, out: str | Path, *, data=None, reference: str | None = None,
                  inputs: str | Path | None = None, params: Sequence[str] | None = None,
                  walkers: int | None = None, steps: int = DEFAULT_STEPS, seed: int = 0,
                  fig_format: str = "png", progress: bool = True) -> CalibrateResult:
    """Calibrate uncertain inputs of ``study`` on a measurement; write ``calibration.json``
    and three figures.

    Parameters
    ----------
    study : Study
    out : str or Path
        Output directory.
    data : Waveform, optional
        A measured waveform file, read (one or more shots of one setup's channels).
    reference : str, optional
        Instead of ``data``: a setup whose ``[reference]`` rows (TOF and AR with std) are
        the measurement.
    inputs : str or Path, optional
        Uncertainty file (``msens.uncertainty/1``); default the built-in one of a built-in
        study. Its distributions are the priors.
    params : sequence of str, optional
        Inputs to calibrate (default :data:`msens.uq.posterior.DEFAULT_CALIBRATED` where
        sampled); all others are held at their nominal values.
    walkers : int, optional
        emcee walkers (default max(16, 4 k), even).
    steps : int
        Steps per walker (half burn-in).
    seed : int
        Seed of the start search, the sampler and the predictive draws.
    fig_format : {"png", "pdf", "svg"}
    progress : bool
        A progress bar on stderr.

    Returns
    -------
    CalibrateResult

    Raises
    ------
    InputError
        Before any simulation, for any bad input (see the module docstring).
    """
    from msens import budget, plots
    from msens.uq import calibration_report as rep
    from msens.uq.workflow import _calibrated
    from msens.workflows.common import check_format, figure_names, provenance

    start_time = time.perf_counter()
    if (data is None) == (reference is None):
        raise InputError("calibrate needs either DATA (a waveform file) or --reference SETUP, "
                         "not both")
    names = figure_names(FILES, check_format(fig_format))
    target = OutputDir(out)
    target.check(names)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
        raise InputError(f"--seed must be a whole number from 0 to 2**32 - 1, got {seed!r}")
    columns = select(load_inputs(inputs, study), params)
    walkers = check_sampler(walkers, steps, len(columns))
    if reference is not None:
        _check_reference(study, reference)
    else:
        from msens.diagnose.noise import shot_matrix
        from msens.diagnose.objective import check_channels
        from msens.diagnose.workflow import match_setup_spec
        from msens.workflows.compare import check_measurement

        _log.info("calibrate: checking the measurement against the model's record")
        with heartbeat(_log, "calibrate: checking the measurement"):
            check_measurement(study, data, str(getattr(data, "path", data)))
            setup = match_setup_spec(study, data)
            check_channels(data)
            shot_matrix(data, [(s.kind.value, s.particle) for s in setup.sensors])
    budget.check(study)

    _log.info("calibrate: the model's baseline and the likelihood")
    with heartbeat(_log, "calibrate: the model's baseline"):
        study = _calibrated(study)
        checked = load_inputs(inputs, study)
        coords = Coordinates.of(checked, columns)
        objective, setup, measurement = _objective(study, data, reference)
        likelihood = Likelihood(study, checked, setup, objective)
    posterior = Posterior(coords, likelihood)
    k = len(columns)
    _log.info("calibrate %s on %s: %d inputs (%s), %d walkers x %d steps", study.name,
              measurement, k, ", ".join(coords.names), walkers, steps)

    _log.info("calibrate: start point from the nominal values and %d prior draws, then "
              "Nelder-Mead (up to %d runs) and the posterior's curvature there",
              START_DRAWS * k, 30 * k)
    rng = np.random.default_rng(seed)
    draws = np.column_stack([p.distribution.values(rng.random(START_DRAWS * k))
                             for p in coords.inputs])
    with heartbeat(_log, "calibrate: start point"):
        z0 = start_point(posterior, coords.coordinates(draws), max_evals=30 * k)
        support = np.array([p.distribution.support for p in coords.inputs])
        lower = coords.coordinates(support[:, 0])[0]
        upper = coords.coordinates(support[:, 1])[0]
        cov = laplace_covariance(posterior, z0, lower, upper)
    bar = None
    if progress and _log.isEnabledFor(logging.INFO):
        from tqdm import tqdm

        bar = tqdm(desc="calibrate steps", total=steps, unit=" steps", leave=False)

    def tick(done: int, total: int) -> None:
        if bar is not None:
            bar.n = done
            bar.refresh()

    try:
        with refreshing(bar):
            chains = sample(posterior, z0, walkers=walkers, steps=steps, seed=seed, cov=cov,
                            progress=tick)
    finally:
        if bar is not None:
            bar.close()
    kept = chains.kept
    theta = coords.values(chains.flat)
    tau = autocorr_time(kept)
    ess = kept.shape[0] * kept.shape[1] / np.maximum(tau, 1.0)
    best = coords.values(chains.best()[None])
    chi2_best = float(likelihood.chi2(coords.rows(best))[0])
    pick = rng.choice(theta.shape[0], size=min(PREDICTIVE_DRAWS, theta.shape[0]), replace=False)
    _log.info("calibrate: posterior predictive from %d draws", pick.size)
    with heartbeat(_log, "calibrate: posterior predictive"):
        features, refs, band = predictive(study, checked, coords, theta[pick], objective,
                                          setup.name, rng)
    variance = objective.variance_split() if hasattr(objective, "variance_split") else \
        {"noise_share": 1.0, "model_uncertainty_share": 0.0}
    cal = Calibration(mode="features" if reference else "waveform", setup=setup.name,
                      measurement=measurement, coords=coords, chains=chains, samples=theta,
                      rhat=split_rhat(kept), tau=tau, ess=ess, chi2_best=chi2_best,
                      n_obs=float(np.sum(objective.n_obs)), predictive=features,
                      reference=refs, band=band, variance=variance,
                      runs=likelihood.runs + len(study.setups) * pick.size,
                      seconds=time.perf_counter() - start_time)
    _log.info("calibrate: writing %s and the figures to %s", names[0], target.path)
    with heartbeat(_log, "calibrate: writing the files and figures"):
        report = rep.to_json(cal, checked, provenance=provenance(study))
        written = [target.write_json(names[0], report)]
        for name, make in ((names[1], lambda: rep.pairs_figure(cal)),
                           (names[2], lambda: rep.predictive_figure(cal)),
                           (names[3], lambda: rep.trace_figure(cal))):
            fig = make()
            written.append(target.savefig(name, fig, fmt=fig_format, dpi=DPI))
            plots.close(fig)
    return CalibrateResult(calibration=cal, report=report, written=tuple(written))


__all__ = ["DEFAULT_STEPS", "FILES", "PREDICTIVE_DRAWS", "CalibrateResult", "Calibration",
           "check_sampler", "predictive", "run_calibrate"]
