"""From the field model to the coil's voltage: the one transducer core every workflow calls.

- :mod:`.potentials` — the factorised tangent operator at the bias point, source potentials,
  coil flux linkage by mesh quadrature and by summed-area table.
- :mod:`.villari` — the Villari source of each bead (bead stress × magnetoelastic law).
- :mod:`.approach` — the contact-approach source of each contact (morphed-mesh residual);
  :mod:`.contact_map` — its nonlinear map from the open gap to peak approach.
- :mod:`.magnetoelastic`, :mod:`.steel_law` — the JAS magnetoelastic law and its fit to the
  field model's B–H table.
- :mod:`.mechanisms` — incremental potentials of both mechanisms' sources, coil linkage.
- :mod:`.transducer` — per-coil sensitivities of both mechanisms, the magnets' pull on the
  beads, coil R and L; :mod:`.transducer_cache` — their stored artifacts;
  :mod:`.coil_read` — a changed coil read from another coil's field model (tables of the
  coil's window); :mod:`.variants` — transducers as a function of the magnets' remanence.
- :mod:`.dynamic`, :mod:`.frequency_response`, :mod:`.eddy_readout` — eddy currents:
  sensitivities and impedance per frequency, and the EMF spectra through them;
  :mod:`.dynamic_cache` — their stored models; :mod:`.eddy_coil_read` — a changed coil
  read from another coil's eddy-current model; :mod:`.harmonic_tables` — the sources'
  harmonic potentials tabulated over a coil window.
- :mod:`.emf` — a transducer's EMF from the chain's contact states and its parts (rigid
  translation, open contacts). The physics MsS's read-out, EMF to DAQ record, is
  :mod:`msens.readout.mss`.

The names below load with their module on first use. The functions named like their modules
(``emf``, ``contact_map``, ``harmonic_tables``) are not listed here: an attribute of the
package cannot be both; import them from their modules.
"""

from msens._lazy import attribute, names

_HOMES = {
    "transducer": ("Transducer", "TransducerReport", "bias_solution", "compute_transducers",
                   "magnetic_precompression", "particle_forces"),
    "transducer_cache": ("solved_for", "transducer_report", "transducers_for"),
    "coil_read": ("CoilTables", "InductanceGrid", "coil_window", "scaled_inductance"),
    "variants": ("RemanenceFamily", "remanence_family"),
    "emf": ("open_contact_emf", "open_contact_rates", "rigid_translation_emf",
            "rigid_translation_rates"),
    "dynamic": ("DynamicReport", "frequency_responses"),
    "dynamic_cache": ("dynamic_report",),
    "frequency_response": ("FrequencyResponse", "coil_impedance"),
    "eddy_readout": ("emf_spectra", "mechanism_emfs"),
    "magnetoelastic": ("PiezomagneticCoefficient", "anhysteretic_magnetisation",
                       "differential_susceptibility", "magnetostriction",
                       "piezomagnetic_coefficient", "stress_sensitivity"),
    "steel_law": ("fit_anhysteretic", "law_for_steel"),
    "potentials": ("LinkageTable", "TangentOperator", "linkage_table"),
    "mechanisms": ("MechanismPotentials", "coil_linkage", "mechanism_potentials"),
    "villari": ("contact_sensitivity", "villari_sources"),
    "approach": ("approach_flux_change",),
    "contact_map": ("ApproachMap", "ContactMap", "approach_maps", "contact_maps",
                    "mapped_contacts"),
    "harmonic_tables": ("HarmonicTables",),
}

__all__ = names(_HOMES)


def __getattr__(name: str):
    return attribute(__name__, _HOMES, name)
