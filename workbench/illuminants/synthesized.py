"""Synthesized sources, designed by optimisation against CIE D65.

- ``d65-two-peak``: two narrow LED peaks, a fixed blue one and a yellow one
  whose wavelength and power are solved so that the chromaticity equals D65's
  (``|Δxy|`` < 1e-6). Like the paper's Rf 3.2 source: white looks right, reds and
  greens cannot be rendered.
- ``d65-simulator``: six LED channels at common commercial peak wavelengths
  (the paper's lightbooth has six), their powers fitted (non-negative least
  squares in log-power) to the D65 spectrum over 400–720 nm with the D65
  chromaticity as a heavily weighted constraint.

LED peaks use Ohno's (2005) model as colour-science implements it
(:func:`colour.sd_single_led`). Each design runs once per process (~10 ms).

References
----------
Ohno, Y. (2005). Spectral design considerations for white LED color
rendering. Optical Engineering, 44(11), 111302.
"""

from __future__ import annotations

from functools import lru_cache

import colour
import numpy as np
from scipy.optimize import least_squares

from workbench.colorimetry import WORKING_SHAPE, WORKING_WAVELENGTHS, observer_cmfs
from workbench.illuminants.source import Illuminant

__all__ = [
    "TWO_PEAK_BLUE_NM",
    "TWO_PEAK_FWHM_NM",
    "SIMULATOR_CHANNELS",
    "design_d65_two_peak",
    "design_d65_simulator",
    "d65_simulator_channel_powers",
    "SYNTHESIZED_SOURCES",
]

TWO_PEAK_BLUE_NM = 450.0
TWO_PEAK_FWHM_NM = 20.0

SIMULATOR_CHANNELS = ((420.0, 20.0), (450.0, 22.0), (480.0, 28.0),
                      (520.0, 32.0), (570.0, 25.0), (620.0, 22.0))
"""(peak nm, FWHM nm) of the six LED channels of ``d65-simulator``."""


def _led(peak_nm: float, fwhm_nm: float) -> np.ndarray:
    return colour.sd_single_led(peak_nm, half_spectral_width=fwhm_nm, shape=WORKING_SHAPE).values


def _xy(power: np.ndarray) -> np.ndarray:
    XYZ = power @ observer_cmfs("cie1931-2").values
    return XYZ[:2] / XYZ.sum()


def _d65() -> np.ndarray:
    return colour.SDS_ILLUMINANTS["D65"].copy().align(WORKING_SHAPE).values


def _normalize(power: np.ndarray) -> np.ndarray:
    return power / power[WORKING_WAVELENGTHS == 560][0]


@lru_cache(maxsize=1)
def design_d65_two_peak() -> Illuminant:
    """A blue + yellow two-peak source metameric to D65 for the white (Rf ≈ 8)."""
    target = _xy(_d65())
    blue = _led(TWO_PEAK_BLUE_NM, TWO_PEAK_FWHM_NM)

    def build(params):
        yellow_nm, log_ratio = params
        return blue + np.exp(log_ratio) * _led(yellow_nm, TWO_PEAK_FWHM_NM)

    fit = least_squares(lambda p: _xy(build(p)) - target, x0=[575.0, 0.0],
                        bounds=([540.0, -5.0], [620.0, 5.0]), xtol=1e-14, ftol=1e-15)
    yellow_nm = float(fit.x[0])
    sd = colour.SpectralDistribution(_normalize(build(fit.x)), WORKING_WAVELENGTHS,
                                     name="D65 two peaks")
    return Illuminant(
        id="d65-two-peak", name="D65 two peaks", kind="synthesized", sd=sd,
        description=(f"two LED peaks, {TWO_PEAK_BLUE_NM:.0f} nm and {yellow_nm:.1f} nm "
                     f"(FWHM {TWO_PEAK_FWHM_NM:.0f} nm), powers solved for the D65 chromaticity"),
    )


@lru_cache(maxsize=1)
def d65_simulator_channel_powers() -> np.ndarray:
    """Fitted power of each of the :data:`SIMULATOR_CHANNELS` (relative, before normalization)."""
    d65 = _normalize(_d65())
    target = _xy(d65)
    basis = np.stack([_led(peak, fwhm) for peak, fwhm in SIMULATOR_CHANNELS], axis=1)
    band = (WORKING_WAVELENGTHS >= 400) & (WORKING_WAVELENGTHS <= 720)

    def residuals(log_power):
        power = basis @ np.exp(log_power)
        return np.concatenate([(power - d65)[band] / np.sqrt(band.sum()),
                               100.0 * (_xy(power) - target)])

    fit = least_squares(residuals, x0=np.zeros(len(SIMULATOR_CHANNELS)))
    return np.exp(fit.x)


@lru_cache(maxsize=1)
def design_d65_simulator() -> Illuminant:
    """A six-channel LED D65 simulator (CIE Rf ≈ 94, xy within 1e-4 of D65)."""
    basis = np.stack([_led(peak, fwhm) for peak, fwhm in SIMULATOR_CHANNELS], axis=1)
    sd = colour.SpectralDistribution(_normalize(basis @ d65_simulator_channel_powers()),
                                     WORKING_WAVELENGTHS, name="D65 simulator")
    channels = ", ".join(f"{peak:.0f}" for peak, _ in SIMULATOR_CHANNELS)
    return Illuminant(
        id="d65-simulator", name="D65 simulator (6-channel LED)", kind="synthesized", sd=sd,
        description=f"LED channels at {channels} nm, powers fitted to CIE D65",
    )


SYNTHESIZED_SOURCES = {
    "d65-two-peak": design_d65_two_peak,
    "d65-simulator": design_d65_simulator,
}
"""Synthesized source id → designer."""
