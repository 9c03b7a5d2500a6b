"""Two-peak metamers of any source: a blue and a yellow LED whose white matches the source's.

The generalization of ``d65-two-peak``
(:func:`workbench.illuminants.synthesized.design_d65_two_peak`): a fixed blue
peak and a yellow peak whose wavelength and relative power are solved (least
squares) so that the CIE 1931 chromaticity of the mix equals the source's.
Level 1 cannot tell the two apart (the light colour is the same); level 2
and every coloured surface can. If no yellow peak on 520–640 nm reaches the
source's chromaticity with the default blue peak, the blue peak is moved
(430–480 nm) until one does.
"""

from __future__ import annotations

import colour
import numpy as np
from scipy.optimize import least_squares

from workbench.colorimetry import WORKING_WAVELENGTHS
from workbench.errors import WorkbenchError
from workbench.illuminants.source import Illuminant
# the LED shape and the chromaticity the d65-two-peak design solves with
from workbench.illuminants.synthesized import TWO_PEAK_BLUE_NM, TWO_PEAK_FWHM_NM, _led, _xy

__all__ = ["METAMER_XY_TOLERANCE", "two_peak_metamer"]

METAMER_XY_TOLERANCE = 1e-6
"""Largest ``|Δx|``, ``|Δy|`` between a metamer and its source."""

_BLUE_CANDIDATES_NM = (TWO_PEAK_BLUE_NM, 440.0, 460.0, 430.0, 470.0, 480.0)


def two_peak_metamer(illuminant: Illuminant, fwhm_nm: float = TWO_PEAK_FWHM_NM) -> Illuminant:
    """A two-peak LED source with the chromaticity of ``illuminant`` (``|Δxy|`` ≤ 1e-6).

    Raises
    ------
    WorkbenchError
        No blue + yellow pair reaches the source's chromaticity (a strongly
        coloured source far from the blue–yellow line, e.g. a saturated green).
    """
    target = _xy(np.asarray(illuminant.sd.values, dtype=float))
    best = None
    for blue_nm in _BLUE_CANDIDATES_NM:
        blue = _led(blue_nm, fwhm_nm)

        def build(params, blue=blue):
            yellow_nm, log_ratio = params
            return blue + np.exp(log_ratio) * _led(yellow_nm, fwhm_nm)

        fit = least_squares(lambda p, build=build: _xy(build(p)) - target, x0=[575.0, 0.0],
                            bounds=([520.0, -8.0], [640.0, 8.0]), xtol=1e-14, ftol=1e-15)
        error = float(np.max(np.abs(fit.fun)))
        if best is None or error < best[0]:
            best = (error, blue_nm, fit.x, build(fit.x))
        if error <= METAMER_XY_TOLERANCE:
            break
    error, blue_nm, (yellow_nm, _), power = best
    if error > METAMER_XY_TOLERANCE:
        raise WorkbenchError(
            f"no two-peak (blue + yellow LED) mix reaches the chromaticity of {illuminant.name} "
            f"(x, y = {target[0]:.4f}, {target[1]:.4f}; closest |Δxy| {error:.2g}); choose a "
            "whitish source near the blue–yellow line")
    power = power / power[WORKING_WAVELENGTHS == 560][0]
    name = f"{illuminant.name} two peaks"
    sd = colour.SpectralDistribution(power, WORKING_WAVELENGTHS, name=name)
    return Illuminant(
        id=f"{illuminant.id}-two-peak", name=name, kind="synthesized", sd=sd,
        description=(f"two LED peaks, {blue_nm:.0f} nm and {yellow_nm:.1f} nm (FWHM "
                     f"{fwhm_nm:.0f} nm), powers solved for the chromaticity of {illuminant.name}"))
