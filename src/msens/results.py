"""What a study run produced: typed result records and the summaries written from them.

:class:`StudyResult` holds every setup's chain history and sensor records
(:class:`SetupResult`, :class:`SensorResult`); :func:`summary` is the content of
``summary.json`` (with :func:`provenance`: :meth:`StudyResult.to_json`) and
:func:`physics_summary` its physics-MsS part (per coil: voltages, each
mechanism's share of the signal, the frequency response with eddy currents). The workflows
(:mod:`msens.pipeline`, :mod:`msens.compare`, :mod:`msens.synth`, :mod:`msens.diagnose`)
produce and read these records; nothing here runs a model.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from msens.calibrate import DissipationFit
from msens.chain.integrate import ChainResult
from msens.chain.model import Chain
from msens.chain.published import GAMMA_CONTACT, GAMMA_WALL
from msens.config.schema import ReferenceRow, SensorSpec, SetupSpec
from msens.config.study import Study
from msens.signals.features import PulseFeatures


class JsonReport:
    """What the results of the workflows that write one JSON report and its figures share.

    The subclass, a frozen dataclass, has ``report`` (dict: the JSON file's content) and
    ``written`` (tuple of Path: the JSON file, then the figures) and defines ``table()``
    (what its command prints).
    """

    report: dict
    written: tuple[Path, ...]

    @property
    def files(self) -> tuple[Path, ...]:
        """The files written: the JSON report, then the figures."""
        return tuple(self.written)

    @property
    def figures(self) -> tuple[Path, ...]:
        """The figures written."""
        return tuple(p for p in self.written if Path(p).suffix != ".json")

    def to_json(self) -> dict:
        """The content of the JSON report (a copy, as JSON values)."""
        import json

        from msens.io.output import to_json

        return json.loads(to_json(self.report))

@dataclass(frozen=True)
class SensorResult:
    """One sensor's modelled record and features.

    Attributes
    ----------
    sensor : SensorSpec
    position : {"top", "bottom", "single"}
        Order along the chain among the setup's sensors.
    force : ndarray, shape (nt,)
        Dynamic force the sensor reads, N (for the four-contact MsS: mean of its contacts).
    voltage_shape : ndarray, shape (nt,) or None
        For a four-contact MsS, d(force)/dt, N/s — the paper's model of the coil voltage
        (Eq. 5), up to its unknown conversion factor. For a physics MsS, the predicted DAQ
        voltage, V, on the chain's time grid.
    features : PulseFeatures
        Scalar features of ``force``; for a physics MsS, of what the DAQ records (its
        integrated voltage in newtons, :attr:`msens.readout.mss.MssRecord.daq_force`), by the
        one feature pipeline (:func:`msens.signals.features.model_features`).
    mss : MssRecord or None
        For a physics MsS: flux change, EMF and DAQ voltage (:mod:`msens.readout.mss`).
    note : str or None
        Why the record's TOF and AR are missing (NaN), when they are: e.g. the record ends
        before the wall's reflection can arrive (:func:`msens.budget.flag_unresolved`).
    """

    sensor: SensorSpec
    position: str
    force: np.ndarray
    voltage_shape: np.ndarray | None
    features: PulseFeatures
    mss: object | None = None
    note: str | None = None

    def __repr__(self) -> str:
        # the arrays' full reprs (thousands of samples) bury what a notebook user looks for
        model = f" {self.sensor.model.value}" if self.sensor.model is not None else ""
        return (f"SensorResult({_label(self.sensor)}{model} {self.position}: "
                f"{_features_text(self.features)}; force {_shape(self.force)}, "
                f"voltage_shape {_shape(self.voltage_shape)}"
                + (", mss record" if self.mss is not None else "") + ")")


@dataclass(frozen=True)
class SetupResult:
    """A simulated setup.

    Attributes
    ----------
    setup : SetupSpec
    chain : Chain
    history : ChainResult
        Contact forces of every contact, shape (nt, n).
    static_force : ndarray, shape (n,)
        Static contact forces at rest (gravity + precompression), N.
    sensors : tuple of SensorResult
    speed_incident, speed_reflected : float
        Pulse speed between the top and bottom sensor, m/s (NaN with one sensor).
    transducers : dict or None
        Physics MsS transducers by coil particle (:class:`msens.magnetics.transducer.Transducer`).
    responses : dict or None
        With eddy currents: each coil's frequency response by particle
        (:class:`msens.magnetics.frequency_response.FrequencyResponse`).
    magnetostatic : dict or None
        With eddy currents, as ``msens run`` asks for it: each physics coil's record
        without them (:class:`msens.readout.mss.MssRecord` by particle; the same chain,
        transducer and circuit), the faster, less exact model to compare with.
    """

    setup: SetupSpec
    chain: Chain
    history: ChainResult
    static_force: np.ndarray
    sensors: tuple[SensorResult, ...]
    speed_incident: float
    speed_reflected: float
    transducers: dict | None = None
    responses: dict | None = None
    magnetostatic: dict | None = None

    def __repr__(self) -> str:
        coils = (f", transducers at {', '.join(map(str, sorted(self.transducers)))}"
                 if self.transducers else "")
        return (f"SetupResult({self.setup.name!r}, {self.chain.n_particles} particles, "
                f"sensors {', '.join(f'{_label(s.sensor)} {s.position}' for s in self.sensors)}"
                f", speed {self.speed_incident:.1f} m/s, history force "
                f"{_shape(self.history.force)}{coils})")


@dataclass(frozen=True)
class StudyResult:
    """Everything a study run produced.

    Attributes
    ----------
    study : Study
    gamma_contact, gamma_wall : float
        Damping coefficients used (fitted when the study asks for the Eq. 10 fit).
    fit : DissipationFit or None
    setups : tuple of SetupResult

    Notes
    -----
    :meth:`to_json` is the content of ``summary.json`` and :meth:`table` the table
    ``msens run`` prints; a run writes no file itself: its files and figures are written by
    :func:`msens.workflows.run.write_outputs`, which returns their paths.
    """

    study: Study
    gamma_contact: float
    gamma_wall: float
    fit: DissipationFit | None
    setups: tuple[SetupResult, ...]

    def __repr__(self) -> str:
        how = "Eq. 10 fit" if self.fit is not None else "from the study"
        lines = [f"StudyResult({self.study.name!r}, gamma_c = {self.gamma_contact:.3g} kg/s, "
                 f"gamma_w = {self.gamma_wall:.3g} kg/s ({how}), {len(self.setups)} setup(s):"]
        for s in self.setups:
            sensors = "; ".join(f"{_label(r.sensor)} {r.position} {_features_text(r.features)}"
                                for r in s.sensors)
            lines.append(f"  {s.setup.name}: {sensors}; speed {s.speed_incident:.1f} m/s")
        lines.append("  .rows(), .rows_frame(), .records_frame(), .setups[i].sensors[j])")
        return "\n".join(lines)

    def to_json(self) -> dict:
        """The content of ``summary.json``: :func:`summary` with this run's
        :func:`provenance`, as plain JSON values (non-finite numbers are None)."""
        import json

        from msens.io.output import to_json

        return json.loads(to_json(summary(self, provenance(self.study))))

    def table(self) -> str:
        """The table ``msens run`` prints: per sensor TOF (µs), AR, incident peak (N) and
        speed (m/s), with the paper's values where the study has them
        (:func:`msens.tables.format_summary`)."""
        from msens.tables import format_summary

        return format_summary(self)

    def rows_frame(self):
        """The Table-2 rows (:meth:`rows`) as a pandas DataFrame, one row per sensor.

        The published comparison of a row (``reference``) is spread into columns of its own
        (``experiment_tof_us``, ``tof_error_pct``, ...; NaN where a row has none).

        Returns
        -------
        pandas.DataFrame
            Times in µs, forces in N, speeds in m/s (the units are in the column names).

        Raises
        ------
        ImportError
            If pandas is not installed (``pip install "msens[notebook]"``).
        """
        pd = _pandas()
        flat = [{**{k: v for k, v in row.items() if k != "reference"},
                 **row.get("reference", {})} for row in self.rows()]
        return pd.DataFrame(flat)

    def records_frame(self):
        """Every sensor's modelled records as one long-format pandas DataFrame.

        Columns ``time_s``, ``setup``, ``sensor`` (``kind@particle``), ``quantity`` and
        ``value``. Quantities carry their unit in the name: ``force_N`` for every sensor
        (for a physics MsS the sensitivity-weighted force), ``dforce_dt_N_per_s`` for a
        four-contact MsS, and ``voltage_V`` (DAQ voltage), ``emf_V`` and ``flux_Wb`` (flux
        change) for a physics MsS. Select with, e.g.,
        ``df[df.quantity == "voltage_V"].pivot(index="time_s", columns="sensor",
        values="value")``.

        Returns
        -------
        pandas.DataFrame
            One row per sample; ``setup``, ``sensor`` and ``quantity`` are categorical.

        Raises
        ------
        ImportError
            If pandas is not installed (``pip install "msens[notebook]"``).
        """
        pd = _pandas()
        parts = []
        for s in self.setups:
            t = s.history.t
            for r in s.sensors:
                for quantity, values in _records(r):
                    parts.append((s.setup.name, _label(r.sensor), quantity, t, values))
        n = [p[3].size for p in parts]
        cat = [pd.Categorical(np.repeat([p[i] for p in parts], n)) for i in range(3)]
        return pd.DataFrame({
            "time_s": np.concatenate([p[3] for p in parts]),
            "setup": cat[0], "sensor": cat[1], "quantity": cat[2],
            "value": np.concatenate([np.asarray(p[4], dtype=float) for p in parts]),
        })

    def rows(self) -> list[dict]:
        """Table-2 rows, one per sensor: model features and, where the study has them,
        the published experiment and model with the errors of both."""
        refs = {(r.setup, r.position): r for r in self.study.reference}
        out = []
        for s in self.setups:
            for sr in s.sensors:
                f = sr.features
                row = {
                    "setup": s.setup.name,
                    "sensor": sr.sensor.kind.value,
                    "position": sr.position,
                    "particle": sr.sensor.particle,
                    "tof_us": float(f.tof) * 1e6,
                    "ar": float(f.ar),
                    "incident_peak_N": float(f.f_incident),
                    "reflected_peak_N": float(f.f_reflected),
                    "width_us": float(f.width) * 1e6,
                    "speed_m_per_s": s.speed_incident,
                    "speed_reflected_m_per_s": s.speed_reflected,
                }
                if sr.note is not None:  # features missing: say why (null in JSON)
                    row["note"] = sr.note
                ref = refs.get((s.setup.name, sr.position))
                if ref is not None:
                    row["reference"] = _compare(row, ref)
                out.append(row)
        return out


def _label(sensor: SensorSpec) -> str:
    """A sensor as a waveform channel names it, ``kind@particle``."""
    return f"{sensor.kind.value}@{sensor.particle}"


def _shape(array: np.ndarray | None) -> str:
    return "None" if array is None else f"array{tuple(np.shape(array))}"


def _features_text(f: PulseFeatures) -> str:
    return (f"TOF {float(f.tof) * 1e6:.1f} us, AR {float(f.ar):.3f}, "
            f"peak {float(f.f_incident):.3g} N")


def _records(r: SensorResult) -> list[tuple[str, np.ndarray]]:
    """A sensor's records on the chain's time grid, named with their units."""
    out = [("force_N", r.force)]
    if r.mss is not None:
        out += [("voltage_V", r.voltage_shape), ("emf_V", r.mss.emf), ("flux_Wb", r.mss.flux)]
    elif r.voltage_shape is not None:
        out.append(("dforce_dt_N_per_s", r.voltage_shape))
    return out


def _pandas():
    """pandas, imported on first use: an optional dependency (the ``notebook`` extra)."""
    try:
        import pandas
    except ImportError:
        raise ImportError('DataFrames need pandas, an optional dependency of msens: '
                          'pip install "msens[notebook]" (or pip install "pandas>=2")') from None
    return pandas


def _compare(row: dict, ref: ReferenceRow) -> dict:
    """Model against the published experiment, and the published model's own errors."""
    cmp = {
        "experiment_tof_us": ref.tof_us, "experiment_tof_std_us": ref.tof_std_us,
        "experiment_ar": ref.ar, "experiment_ar_std": ref.ar_std,
        "tof_error_pct": 100.0 * (row["tof_us"] - ref.tof_us) / ref.tof_us,
        "ar_error_pct": 100.0 * (row["ar"] - ref.ar) / ref.ar,
    }
    if ref.model_tof_us is not None:
        cmp["paper_model_tof_us"] = ref.model_tof_us
        cmp["paper_model_tof_error_pct"] = 100.0 * (ref.model_tof_us - ref.tof_us) / ref.tof_us
        cmp["tof_vs_paper_model_pct"] = 100.0 * (row["tof_us"] - ref.model_tof_us) \
            / ref.model_tof_us
    if ref.model_ar is not None:
        cmp["paper_model_ar"] = ref.model_ar
        cmp["paper_model_ar_error_pct"] = 100.0 * (ref.model_ar - ref.ar) / ref.ar
        cmp["ar_vs_paper_model"] = row["ar"] - ref.model_ar
    return cmp


def provenance(study: Study) -> dict:
    """What made a result file: the msens version and the study's content hash (SHA-256 of
    its canonical JSON form, so the same study gives the same hash wherever its file is)."""
    import dataclasses

    from msens.io.hashing import content_hash
    from msens.version import version

    return {"msens_version": version(),
            "study_sha256": content_hash(dataclasses.replace(study, source=""))}


def summary(result: StudyResult, provenance: dict) -> dict:
    """The content of ``summary.json``: study, calibrated parameters, Table-2 rows and, for
    physics MsS, :func:`physics_summary`; ``provenance`` says what made it."""
    fit = result.fit
    calibration = {
        "gamma_contact_kg_per_s": result.gamma_contact,
        "gamma_wall_kg_per_s": result.gamma_wall,
        "fitted": fit is not None,
    }
    if fit is not None:
        calibration.update({
            "objective_eq10": fit.objective,
            "ar_top_model": fit.ar_top_model,
            "ar_bottom_model": fit.ar_bottom_model,
            "simulations": fit.n_simulations,
            "paper_gamma_contact_kg_per_s": GAMMA_CONTACT,
            "paper_gamma_wall_kg_per_s": GAMMA_WALL,
        })
    static = {
        s.setup.name: {
            "precompression": [{"contacts": [p.first, p.last], "force_N": p.force_n}
                               for p in s.setup.precompression],
        }
        for s in result.setups
    }
    out = {
        "study": result.study.name,
        "source": result.study.source,
        "provenance": provenance,
        "striker_velocity_m_per_s": result.study.striker.velocity_m_per_s,
        "calibration": calibration,
        "setups": static,
        "rows": result.rows(),
    }
    out.update(physics_summary(result))
    return out


def _trough(record) -> dict:
    """Is there a dip of the integrated signal before its main (incident) peak?"""
    f = record.weighted_force
    i_peak = int(np.argmax(f))
    before = f[:i_peak + 1]
    depth = float(-before.min()) if before.size else 0.0
    peak = float(f[i_peak])
    return {"present": bool(depth > 0.01 * peak), "depth_fraction_of_peak": depth / peak,
            "time_us": float(record.t[int(np.argmin(before))] * 1e6)}


def _peaks(record) -> dict:
    """Largest |DAQ voltage| (V) and its time (µs from the impact), largest |EMF| (V)."""
    k = int(np.argmax(np.abs(record.voltage)))
    return {"peak_voltage_V": float(abs(record.voltage[k])),
            "peak_voltage_time_us": float(record.t_daq[k] * 1e6),
            "peak_emf_V": float(np.max(np.abs(record.emf)))}


def _readout_peak(circuit, response) -> dict:
    """The read-out's resonance as the record sees it: the largest |V_daq / EMF| and its
    frequency, with the eddy-current impedance Z(f) when there is a ``response``."""
    from msens.readout.electronics import peak_gain

    f, gain = peak_gain(circuit, None if response is None else response.impedance_at)
    return {"frequency_Hz": f, "gain": gain}


def physics_summary(result: StudyResult) -> dict:
    """Physics-MsS part of ``summary.json``: per-coil voltage, each mechanism's share of the
    signal and sensitivity profile, the magnet's precompression per contact and the
    dominant transduction mechanism."""
    coils, villari, approach = [], 0.0, 0.0
    precompression = []
    for s in result.setups:
        if not s.transducers:
            continue
        from msens.magnetics.transducer import magnetic_precompression
        from msens.readout.electronics import resonance

        magnetic = magnetic_precompression(s.transducers)
        for c, f in enumerate(np.cumsum(magnetic)[:-1], start=1):
            if abs(f) > 1e-3:
                precompression.append({"setup": s.setup.name, "contact": c, "upper": c,
                                       "lower": c + 1, "force_N": float(f)})
        for r in s.sensors:
            if r.mss is None:
                continue
            tr = s.transducers[r.sensor.particle]
            villari += float(np.sum(np.abs(tr.sensitivity_villari)))
            approach += float(np.sum(np.abs(tr.sensitivity_approach)))
            f0, q = resonance(r.mss.circuit)
            response = s.responses[r.sensor.particle] if s.responses else None
            static_rec = (s.magnetostatic or {}).get(r.sensor.particle)
            coils.append({
                "setup": s.setup.name, "particle": r.sensor.particle,
                **_peaks(r.mss),
                "resistance_ohm": tr.resistance_ohm, "inductance_H": tr.inductance_H,
                "resonance_Hz": f0, "quality_factor": q,
                "readout_peak": _readout_peak(r.mss.circuit, response),
                **({} if static_rec is None else {"magnetostatic": {
                    **_peaks(static_rec),
                    "readout_peak": _readout_peak(static_rec.circuit, None)}}),
                "pre_peak_trough": _trough(r.mss),
                "mechanism_share": mechanism_share(tr, s.history, response),
                **({"frequency_response": frequency_summary(response, tr)}
                   if response is not None else {}),
                "sensitivity_profile": [
                    {"contact": int(c), "dLambda_dF_Wb_per_N": float(v + g),
                     "villari_Wb_per_N": float(v), "approach_Wb_per_N": float(g)}
                    for c, v, g in zip(tr.contacts, tr.sensitivity_villari,
                                       tr.sensitivity_approach, strict=True)],
            })
    if not coils:
        return {}
    return {"coils": coils, "magnetic_precompression_N": precompression,
            "dominant_mechanism": "villari" if villari >= approach else "contact approach",
            "mechanism_magnitude_Wb_per_N": {"villari": villari, "approach": approach}}


def frequency_summary(response, tr) -> dict:
    """A coil's eddy-current frequency response for ``summary.json``: at each solved
    frequency, the contact-approach and Villari sensitivities of the two contacts beside the
    coil's bead relative to their static values (magnitude, phase in degrees), the coil
    impedance as R (Ω) and L (H), and (``screening_by_part``) how much of the screening the
    equivalent magnet's pole pieces cause and how much the beads."""
    freqs = np.asarray(response.frequencies, dtype=float)
    own = [int(np.flatnonzero(np.asarray(response.contacts) == c)[0])
           for c in (tr.particle - 1, tr.particle)]
    out = {"frequencies_Hz": freqs.tolist(), "contacts": [tr.particle - 1, tr.particle]}
    for name, values in (("approach", response.approach), ("villari", response.villari)):
        ratio = np.asarray(values)[:, own] / np.asarray(values)[0, own]
        out[f"{name}_ratio_magnitude"] = np.abs(ratio).tolist()
        out[f"{name}_ratio_phase_deg"] = np.degrees(np.angle(ratio)).tolist()
    z = np.asarray(response.impedance)
    out["resistance_ohm"] = z.real.tolist()
    out["inductance_H"] = np.asarray(response.inductance).real.tolist()
    if response.screening is not None:
        # what rests on the equivalent magnet: the screening with its pole pieces (and magnet)
        # conducting or not (msens.magnetics.dynamic.screening_split)
        out["screening_by_part"] = response.screening
    return out


def mechanism_share(tr, history, response=None) -> dict:
    """Each mechanism's open-circuit EMF alone: its peak (V) and its share of the summed
    signal energy ∫EMF_m² dt / Σ_m ∫EMF_m² dt (the two are not orthogonal: their cross term
    is left out, so the shares add to 1). The contact-approach entry also carries the
    beads' rigid translation (contained in it, see
    :func:`msens.magnetics.emf.rigid_translation_emf`): its sensitivity, peak EMF and
    fraction of the contact-approach peak, and the part of it from contacts while they are open
    (extrapolated linearly: :func:`msens.magnetics.emf.open_contact_emf`), its peak and
    share of the contact-approach energy. With an eddy-current ``response`` the two mechanisms'
    EMFs are the frequency-domain ones (:func:`msens.magnetics.eddy_readout.mechanism_emfs`), and
    so are the rigid-translation and open-contact parts (their rates through the same
    response)."""
    from msens.magnetics.emf import (
        contact_columns,
        contact_rates,
        emf_from_rates,
        open_contact_rates,
        rigid_translation_rates,
    )

    rates = contact_rates(history.t, history.force, tr.contacts, tr.contact_stiffness,
                          approach=history.approach, equivalent=tr.equivalent_approach)
    if response is None:
        def approach_emf(r):
            return emf_from_rates(r, tr.sensitivity_villari, tr.dlambda_dapproach, "approach")

        emfs = {m: emf_from_rates(rates, tr.sensitivity_villari, tr.dlambda_dapproach, m)
                for m in ("villari", "approach")}
    else:
        from msens.magnetics.eddy_readout import mechanism_emfs

        def approach_emf(r):
            return mechanism_emfs(response, r)["approach"]

        emfs = mechanism_emfs(response, rates)
    energy = {m: float(np.trapezoid(e**2, history.t)) for m, e in emfs.items()}
    total = sum(energy.values()) or 1.0
    out = {m: {"peak_emf_V": float(np.max(np.abs(e))), "energy_share": energy[m] / total}
           for m, e in emfs.items()}
    opened = approach_emf(open_contact_rates(rates,
                                             contact_columns(history.approach, tr.contacts)))
    out["approach"]["open_contacts"] = {
        "peak_emf_V": float(np.max(np.abs(opened))),
        "energy_share": float(np.trapezoid(opened**2, history.t)) / (energy["approach"] or 1.0)}
    rigid = approach_emf(rigid_translation_rates(tr, rates))
    out["approach"]["rigid_translation"] = {
        "sensitivity_Wb_per_m": float(tr.dlambda_dapproach[-1]),
        "peak_emf_V": float(np.max(np.abs(rigid))),
        "fraction_of_peak": float(np.max(np.abs(rigid))
                                  / max(out["approach"]["peak_emf_V"], 1e-300))}
    return out
