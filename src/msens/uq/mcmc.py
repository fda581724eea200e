"""Sampling a posterior with emcee, and telling whether the chains converged.

Start: the highest posterior density among the nominal point and a batch of prior draws,
refined by a Nelder-Mead search; the walkers start as draws of the Laplace approximation
there (the curvature of ``-2 ln p``, as diagnose's intervals). Then emcee's ensemble sampler
(Foreman-Mackey et al. 2013, doi:10.1086/670067) with differential-evolution moves (80 %
DEMove, 20 % DESnookerMove; ter Braak & Vrugt 2008), which follow the narrow, correlated
ridges a pulse's timing makes of two inputs that both set its speed; vectorised: each
half-step asks the model for all its walkers in one batch.

Convergence (reported, never silently assumed):

- split R-hat of each input over the walkers (Gelman et al., *Bayesian Data Analysis*, 3rd
  ed., 2013, section 11.4): the kept half of every walker's chain cut in two, between- and
  within-chain variance compared; near 1 when the chains agree;
- the integrated autocorrelation time tau of each input (:func:`emcee.autocorr.
  integrated_time`) and the effective sample size (kept samples / tau);
- the mean acceptance fraction (0.2-0.5 is healthy for the stretch move).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

#: Largest split R-hat accepted as converged.
RHAT_LIMIT = 1.05
#: Prior draws among which the start point is chosen, per calibrated input.
START_DRAWS = 8
#: Radius of the walkers' starting ball, in standardised coordinates.
BALL = 1e-2


@dataclass(frozen=True)
class Chains:
    """What :func:`sample` produced.

    Attributes
    ----------
    z : ndarray, shape (steps, walkers, k)
        Every position of every walker, standardised coordinates.
    log_prob : ndarray, shape (steps, walkers)
    burn : int
        Steps discarded as burn-in (the first half).
    start : ndarray, shape (k,)
        The start point (highest posterior density found before sampling).
    acceptance : float
        Mean acceptance fraction over the walkers.
    """

    z: np.ndarray
    log_prob: np.ndarray
    burn: int
    start: np.ndarray
    acceptance: float

    @property
    def kept(self) -> np.ndarray:
        """Kept positions, shape (steps - burn, walkers, k)."""
        return self.z[self.burn:]

    @property
    def flat(self) -> np.ndarray:
        """Kept positions as one sample, shape ((steps - burn) walkers, k)."""
        k = self.kept
        return k.reshape(-1, k.shape[-1])

    def best(self) -> np.ndarray:
        """The highest-density position visited, shape (k,)."""
        i = np.unravel_index(int(np.argmax(self.log_prob)), self.log_prob.shape)
        return self.z[i]


def split_rhat(chains: np.ndarray) -> np.ndarray:
    """Split R-hat of each parameter.

    Parameters
    ----------
    chains : ndarray, shape (steps, walkers, k)

    Returns
    -------
    ndarray, shape (k,)
        ``sqrt(var_plus / W)`` over the 2 x walkers half chains (BDA3 eq. 11.3-11.4); NaN
        for a parameter that does not move.
    """
    n = chains.shape[0] // 2
    halves = np.concatenate([chains[:n], chains[n:2 * n]], axis=1)  # (n, 2 walkers, k)
    means = halves.mean(axis=0)
    b = n * means.var(axis=0, ddof=1)
    w = halves.var(axis=0, ddof=1).mean(axis=0)
    var_plus = (n - 1) / n * w + b / n
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(w > 0, np.sqrt(var_plus / w), np.nan)


def autocorr_time(chains: np.ndarray) -> np.ndarray:
    """Integrated autocorrelation time of each parameter, steps, shape (k,).

    emcee's estimator, averaged over the walkers, without its check that the chain is
    longer than 50 tau (a short chain gives an estimate, and R-hat judges convergence).
    A parameter whose walkers did not move (a few steps with every proposal rejected) has
    no autocorrelation time: NaN (null in the JSON), never a division warning.

    Parameters
    ----------
    chains : ndarray, shape (steps, walkers, k)
    """
    from emcee.autocorr import integrated_time

    tau = np.full(chains.shape[2], np.nan)
    moving = np.ptp(chains, axis=0).max(axis=0) > 0
    if moving.any():
        with np.errstate(divide="ignore", invalid="ignore"):  # a walker that stood still
            tau[moving] = integrated_time(chains[:, :, moving], tol=0)
    return tau


def start_point(log_prob: Callable[[np.ndarray], np.ndarray], prior_draws: np.ndarray,
                *, max_evals: int) -> np.ndarray:
    """Highest posterior density among 0 (the nominal point) and ``prior_draws``, refined
    by Nelder-Mead.

    Parameters
    ----------
    log_prob : callable
        Vectorised log density of coordinates (rows, k).
    prior_draws : ndarray, shape (m, k)
        Coordinates of prior draws.
    max_evals : int
        Evaluations of the refinement.

    Returns
    -------
    ndarray, shape (k,)
    """
    k = prior_draws.shape[1]
    candidates = np.vstack([np.zeros((1, k)), prior_draws])
    lp = log_prob(candidates)
    if not np.isfinite(lp).any():
        return np.zeros(k)
    x0 = candidates[int(np.argmax(lp))]
    res = minimize(lambda z: -float(log_prob(z[None])[0]) if np.all(np.isfinite(z)) else np.inf,
                   x0, method="Nelder-Mead",
                   options={"maxfev": max_evals, "xatol": 1e-3, "fatol": 0.05,
                            "initial_simplex": x0 + 0.3 * np.vstack([np.zeros(k), np.eye(k)])})
    return res.x if np.isfinite(res.fun) and -res.fun >= lp.max() else x0


def laplace_covariance(log_prob: Callable[[np.ndarray], np.ndarray], start: np.ndarray,
                       lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Covariance of the Gaussian (Laplace) approximation of the posterior at ``start``.

    The finite-difference curvature of ``-2 ln p`` (the chi^2 curvature ``msens diagnose``
    gives its intervals with: :func:`msens.diagnose.fit.curvature_covariance`), with the
    standardised coordinates' bounds ``lower``, ``upper`` (the priors' supports).

    Returns
    -------
    ndarray, shape (k, k)
    """
    from msens.diagnose.fit import curvature_covariance

    def crit(points: list[np.ndarray]) -> np.ndarray:
        lp = log_prob(np.array(points))
        return np.where(np.isfinite(lp), -2.0 * lp, 1e300)

    span = np.minimum(upper - lower, 20.0)  # the searched range: at most +-10 prior std
    lo = np.maximum(lower, start - span / 2)
    hi = np.minimum(upper, start + span / 2)
    return curvature_covariance(crit, start, lo, hi)


def sample(log_prob: Callable[[np.ndarray], np.ndarray], start: np.ndarray, *, walkers: int,
           steps: int, seed: int, cov: np.ndarray | None = None,
           progress: Callable[[int, int], None] | None = None) -> Chains:
    """Run emcee's ensemble sampler from a Gaussian cloud around ``start``.

    Parameters
    ----------
    log_prob : callable
        Vectorised log density of coordinates (walkers, k) -> (walkers,).
    start : ndarray, shape (k,)
    cov : ndarray, shape (k, k), optional
        Covariance of the starting cloud (:func:`laplace_covariance`); default a ball of
        radius :data:`BALL`. Starting from the posterior's own scale and orientation spares
        the walkers the long burn-in of spreading out of a tiny ball along a narrow ridge.
    walkers : int
        An even number, at least 2 k.
    steps : int
        Steps of every walker; the first half is burn-in.
    seed : int
        Seed of the starting ball and of the sampler's moves.
    progress : callable, optional
        ``progress(done_steps, steps)`` after every step.

    Returns
    -------
    Chains
    """
    import emcee

    k = start.size
    rng = np.random.default_rng(seed)
    root = BALL * np.eye(k) if cov is None else np.linalg.cholesky(
        cov + 1e-12 * np.trace(cov) / k * np.eye(k))

    def cloud(m: int) -> np.ndarray:
        return start + rng.standard_normal((m, k)) @ root.T

    p0 = cloud(walkers)
    lp0 = log_prob(p0)
    for _ in range(20):  # walkers must start where the density is positive
        bad = ~np.isfinite(lp0)
        if not bad.any():
            break
        p0[bad] = cloud(int(bad.sum()))
        lp0[bad] = log_prob(p0[bad])
    if not np.all(np.isfinite(lp0)):  # e.g. a start on a support's edge: a tiny ball
        bad = ~np.isfinite(lp0)
        p0[bad] = start + 1e-6 * rng.standard_normal((int(bad.sum()), k))
        lp0[bad] = log_prob(p0[bad])
    moves = [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    sampler = emcee.EnsembleSampler(walkers, k, log_prob, vectorize=True, moves=moves)
    sampler.random_state = np.random.RandomState(seed).get_state()
    state = emcee.State(p0, log_prob=lp0)
    for i, _ in enumerate(sampler.sample(state, iterations=steps), 1):
        if progress is not None:
            progress(i, steps)
    return Chains(z=sampler.get_chain(), log_prob=sampler.get_log_prob(), burn=steps // 2,
                  start=np.asarray(start, dtype=float),
                  acceptance=float(np.mean(sampler.acceptance_fraction)))


__all__ = [
    "BALL",
    "RHAT_LIMIT",
    "START_DRAWS",
    "Chains",
    "autocorr_time",
    "laplace_covariance",
    "sample",
    "split_rhat",
    "start_point",
]
