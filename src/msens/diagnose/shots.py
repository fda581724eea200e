"""Per-shot alignment of a multi-shot file: each shot's impact-to-trigger delay and striker
speed against the baseline model.

A rig does not repeat its striker speed exactly. Shots at different speeds arrive at different
times at each sensor, so their ensemble mean is a blurred pulse that no single model run
reproduces, and a blurring effect (a low-pass) would be named for it. Each shot is therefore
fitted alone with the baseline at a few striker speeds (two shared grids: coarse over +-40 %,
then fine over +-3 % around the best common speed; a parabola through the three grid points
around each shot's own minimum), which gives its delay (to align the shots on their impact)
and its speed. The relative spread of the speeds is the state's ``velocity_spread``: every
model is then averaged over that spread, like the shots are. The mean speed stays a question
for the diagnosis (``striker_velocity``), judged against its floor.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from msens.diagnose.effects.base import ModelState
from msens.diagnose.objective import WaveformObjective
from msens.diagnose.predict import Predictor
from msens.io.waveform import Waveform
from msens.results import SetupResult

#: Exponent of the solitary wave's speed in the striker speed (V_s ~ F_m^(1/6) ~ v^(1/5),
#: design.md §5): a relative speed spread s moves arrivals at time t by ~ t s / 5.
SPEED_EXPONENT = 0.2
#: Relative half-widths and points of the coarse and fine speed grids.
COARSE = (0.4, 9)
FINE = (0.03, 13)


@dataclass(frozen=True)
class ShotFits:
    """What each shot of a file says about its own speed and timing.

    Attributes
    ----------
    repeats : tuple of int
        The shots' repeat numbers.
    speeds : ndarray, shape (shots,)
        Best striker speed of each shot against the baseline, m/s.
    delays : ndarray, shape (shots,)
        Impact-to-trigger delay of each shot at that speed, s.
    spread : float
        Relative std (ddof 1) of the speeds; 0 when it moves no arrival within the record
        by half a sample.
    """

    repeats: tuple[int, ...]
    speeds: np.ndarray
    delays: np.ndarray
    spread: float

    def to_json(self) -> dict:
        """The per-shot section of a report."""
        return {"striker_speed_spread": self.spread,
                "shots": [{"shot": r, "striker_speed_m_per_s": float(v), "delay_s": float(d)}
                          for r, v, d in zip(self.repeats, self.speeds, self.delays,
                                             strict=True)]}


def shot_of(waveform: Waveform, repeat: int) -> Waveform:
    """The channels of one shot as a one-shot waveform."""
    idx = [j for j, c in enumerate(waveform.channels) if c.repeat == repeat]
    return Waveform(time=waveform.time, data=waveform.data[:, idx],
                    channels=tuple(dataclasses.replace(waveform.channels[j], repeat=1)
                                   for j in idx),
                    metadata=dict(waveform.metadata))


def _parabola_min(x: np.ndarray, y: np.ndarray) -> float:
    k = int(np.clip(np.argmin(y), 1, x.size - 2))
    a, b, _ = np.polyfit(x[k - 1:k + 2], y[k - 1:k + 2], 2)
    return float(np.clip(-b / (2 * a), x[k - 1], x[k + 1])) if a > 0 else float(x[k])


def fit_shots(waveform: Waveform, base: ModelState, result: SetupResult,
              predictor: Predictor) -> ShotFits:
    """Fit every shot of ``waveform`` alone: its striker speed and its delay.

    Parameters
    ----------
    waveform : Waveform
        Two or more shots.
    base : ModelState
        The baseline model.
    result : SetupResult
        The baseline's run (the starting delay of each shot).
    predictor : Predictor

    Returns
    -------
    ShotFits
    """
    repeats = tuple(sorted({c.repeat for c in waveform.channels}))
    objs = [WaveformObjective(shot_of(waveform, r), result) for r in repeats]

    def chi2(velocities: np.ndarray) -> np.ndarray:  # (speeds, shots)
        recs = predictor.records([dataclasses.replace(base, velocity=float(v),
                                                      velocity_spread=0.0)
                                  for v in velocities])
        return np.array([[o.rss(r).sum() for o in objs] for r in recs])

    coarse = base.velocity * (1.0 + np.linspace(-COARSE[0], COARSE[0], COARSE[1]))
    common = float(coarse[int(np.argmin(chi2(coarse).sum(axis=1)))])
    fine = common * (1.0 + np.linspace(-FINE[0], FINE[0], FINE[1]))
    table = chi2(fine)
    speeds = np.array([_parabola_min(fine, table[:, k]) for k in range(len(objs))])
    recs = predictor.records([dataclasses.replace(base, velocity=float(v), velocity_spread=0.0)
                              for v in speeds])
    delays = np.array([o.align(o.shots[0], o.signals(r)).delay
                       for o, r in zip(objs, recs, strict=True)])
    spread = float(np.std(speeds, ddof=1) / np.mean(speeds))
    # a spread that moves no arrival within the record by half a sample is no spread (the
    # average over it would triple the model runs for nothing)
    t_end, dt = float(predictor.t[-1]), float(predictor.t[1] - predictor.t[0])
    if SPEED_EXPONENT * spread * t_end < 0.5 * dt:
        spread = 0.0
    return ShotFits(repeats=repeats, speeds=speeds, delays=delays, spread=spread)
