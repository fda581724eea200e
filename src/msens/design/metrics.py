"""Per-design figures of merit, vectorised over designs (coil sweeps evaluate thousands).

Circuit (as :mod:`msens.electronics` with no cable series resistance): coil R, L in series,
the winding, cable and DAQ input capacitances in parallel, C = C_w + C_cable + C_in, across
the DAQ input resistance R_in (G = 1/R_in). H(s) = 1 / (a0 + b s + c s²) with a0 = 1 + R G,
b = R C + L G, c = L C. Then

- self-resonance ω0² = a0/c and Q = ω0 c / b (the poles of H);
- −3 dB bandwidth: |H(jω)|² = |H(0)|²/2 has exactly one root x = ω² > 0 of
  c² x² + (b² − 2 a0 c) x − a0² = 0;
- Johnson noise at the DAQ over all frequencies: every resistor at temperature T and the DAQ
  node is one capacitor C, so equipartition gives v_rms² = k T / C exactly; the DAQ's input
  noise adds e_n² f_s / 2 and its quantisation LSB²/12 (as :func:`msens.electronics.noise_rms`
  with ``bandwidth=None``; both agree in tests/design/test_metrics.py).

Signal: EMF(t) = −Σ_c (∂Λ/∂F_c) dF_c/dt (issue 4) for the study's wave; the SNR is
peak |EMF| |H(0)| / v_rms (the resonance gain inside the band is not counted).
"""

from __future__ import annotations

import numpy as np

from msens.study import ElectronicsSpec
from msens.units import K_B


def circuit_metrics(resistance: np.ndarray, inductance: np.ndarray,
                    winding_capacitance: np.ndarray, electronics: ElectronicsSpec
                    ) -> dict[str, np.ndarray]:
    """Resonance (Hz), Q, bandwidth (Hz), DC gain and noise rms (V) per design.

    Parameters
    ----------
    resistance, inductance, winding_capacitance : ndarray, shape (n,)
        Ω, H, F.
    electronics : ElectronicsSpec
        Cable and DAQ data, temperature and DAQ noise.
    """
    r = np.asarray(resistance, dtype=float)
    ind = np.asarray(inductance, dtype=float)
    cap = np.asarray(winding_capacitance, dtype=float) + electronics.cable_capacitance_f \
        + electronics.input_capacitance_f
    g = 0.0 if np.isinf(electronics.input_resistance_ohm) else \
        1.0 / electronics.input_resistance_ohm
    a0 = 1.0 + r * g
    b = r * cap + ind * g
    c = ind * cap
    omega0 = np.sqrt(a0 / c)
    bb = b**2 - 2.0 * a0 * c
    x = (-bb + np.sqrt(bb**2 + 4.0 * c**2 * a0**2)) / (2.0 * c**2)
    var = K_B * electronics.temperature_k / cap
    fs = electronics.sample_rate_hz
    var = var + electronics.input_noise_v_per_rthz**2 * fs / 2.0
    if electronics.adc_bits is not None and electronics.adc_range_v is not None:
        var = var + (electronics.adc_range_v / 2**electronics.adc_bits) ** 2 / 12.0
    return {"resonance_Hz": omega0 / (2 * np.pi), "quality_factor": omega0 * c / b,
            "bandwidth_Hz": np.sqrt(x) / (2 * np.pi), "dc_gain": 1.0 / a0,
            "noise_rms_V": np.sqrt(var)}


def peak_emf(sensitivity: np.ndarray, force_rate: np.ndarray, chunk: int = 256) -> np.ndarray:
    """max_t |Σ_c S_c dF_c/dt| per design, V.

    Parameters
    ----------
    sensitivity : ndarray, shape (n_designs, n_contacts)
        ∂Λ/∂F_c, Wb/N.
    force_rate : ndarray, shape (n_contacts, nt)
        dF_c/dt of the study's wave, N/s.
    """
    s = np.atleast_2d(sensitivity)
    out = np.empty(s.shape[0])
    for k in range(0, s.shape[0], chunk):
        out[k:k + chunk] = np.max(np.abs(s[k:k + chunk] @ force_rate), axis=1)
    return out


__all__ = ["circuit_metrics", "peak_emf"]
