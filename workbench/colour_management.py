"""Level-1 and level-2 colour management (design §2).

The engine model: ``framebuffer_lin = albedo_lin ⊙ light_lin`` (Lambertian,
facing the light), encoded with the sRGB transfer function to 8 bits, and the
HMD receives those 8-bit values as DAC. Light colours and textures are
authored in 8-bit sRGB.

- **Level 1** sets only the light: ``light_rgb8 = display_inverse(XYZ_t(ρ=1))``;
  textures stay as authored.
- **Level 2** also re-authors each texel so that the engine output equals
  ``DAC_t = display_inverse(XYZ_t(ρ))``: ``albedo_lin = srgb_decode(DAC_t) ⊘ light_lin``
  (clipped to [0, 1]; where a light channel is ~0 the texel is flagged).

Scale: DAC and texel values are 8-bit integers (0..255) where the engine sees
them, floats on 0..255 for the theoretical ``DAC_t``; XYZ on the display's scale
(``Y_white`` = the display white luminance).
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from workbench.colorimetry import (
    DEFAULT_K,
    DEFAULT_OBSERVER,
    delta_E2000,
    reflectances_to_XYZ_relative,
    white_XYZ_relative,
)
from workbench.display import (
    DisplayModel,
    SRGBDisplay,
    check_observer,
    quantize_dac,
    srgb_decode,
    srgb_encode,
)
from workbench.errors import InputError

__all__ = [
    "LIGHT_CHANNEL_FLOOR",
    "LightColour",
    "Level2Texture",
    "ErrorTable",
    "light_colour",
    "light_colour_from_XYZ",
    "engine_render",
    "level2_texture",
    "level2_albedo8",
    "target_dac",
    "error_table",
    "authored_srgb8",
]

LIGHT_CHANNEL_FLOOR = 1e-4
"""A light channel with linear value below this cannot carry a level-2 texel."""


@dataclass(frozen=True, eq=False)
class LightColour:
    """The level-1 light for one source on one display.

    Attributes
    ----------
    XYZ : ndarray (3,)
        ``XYZ_t`` of the perfect diffuser (``Y = k · Y_white``).
    dac : ndarray (3,)
        Float DAC (0..255) from the display inverse.
    rgb8 : ndarray (3,) of int
        What the engine's light colour is set to.
    in_gamut : bool
        False where the display cannot show the light's white and it was clipped.
    """

    XYZ: np.ndarray
    dac: np.ndarray
    rgb8: np.ndarray
    in_gamut: bool

    @property
    def linear(self) -> np.ndarray:
        """The light colour as the engine uses it (linear, 0..1)."""
        return srgb_decode(self.rgb8 / 255.0)


def light_colour_from_XYZ(XYZ, display: DisplayModel) -> LightColour:
    """The level-1 light colour whose perfect diffuser has ``XYZ_t = XYZ`` on ``display``.

    ``light_rgb8 = display_inverse(XYZ_t(ρ=1))`` (design §2, level 1), with
    ``in_gamut`` False where the display clips it. ``XYZ`` is on the display's
    scale (``Y = k · Y_white``), e.g. the sum over bands of a source's
    relative-colorimetry weights.
    """
    XYZ = np.asarray(XYZ, dtype=np.float64)
    dac = display.inverse(XYZ)
    return LightColour(XYZ=XYZ, dac=dac, rgb8=quantize_dac(dac),
                       in_gamut=bool(display.in_gamut(XYZ)))


def light_colour(illuminant, display: DisplayModel | None = None, *, k: float = DEFAULT_K,
                 observer: str = DEFAULT_OBSERVER) -> LightColour:
    """Level-1 light colour of ``illuminant`` for ``display`` (default: ideal sRGB)."""
    display = display or SRGBDisplay()
    check_observer(display, observer)
    XYZ = white_XYZ_relative(illuminant, observer, k=k, Y_white=float(display.white_XYZ[1]))
    return light_colour_from_XYZ(XYZ, display)


def _as_rgb8(values, what: str) -> np.ndarray:
    values = np.asarray(values)
    if values.shape[-1:] != (3,):
        raise InputError(f"{what} needs a last axis of 3 (r, g, b); got shape {values.shape}")
    if not np.all(np.isfinite(values)) or np.any(values < 0) or np.any(values > 255):
        raise InputError(f"{what} must be 8-bit values 0..255 without NaN")
    return values


def engine_render(texture_rgb8, light_rgb8) -> np.ndarray:
    """What the engine outputs (8-bit DAC) for sRGB texels under an sRGB light colour."""
    texture = _as_rgb8(texture_rgb8, "texture")
    light = _as_rgb8(light_rgb8, "light colour")
    linear = srgb_decode(texture / 255.0) * srgb_decode(light / 255.0)
    return quantize_dac(255.0 * srgb_encode(linear))



def target_dac(reflectances, illuminant, display: DisplayModel | None = None, *,
               k: float = DEFAULT_K, observer: str = DEFAULT_OBSERVER, wavelengths=None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Theoretical ``DAC_t`` (float, 0..255) and ``XYZ_t`` of surfaces under ``illuminant``."""
    display = display or SRGBDisplay()
    check_observer(display, observer)
    XYZ_t = reflectances_to_XYZ_relative(reflectances, illuminant, observer, k=k,
                                         Y_white=float(display.white_XYZ[1]),
                                         wavelengths=wavelengths)
    return display.inverse(XYZ_t), XYZ_t


@dataclass(frozen=True, eq=False)
class Level2Texture:
    """A level-2 texture for one source.

    Attributes
    ----------
    rgb8 : ndarray (N, 3) of int
        The sRGB texels to upload.
    target_dac : ndarray (N, 3)
        Theoretical ``DAC_t`` (float) the engine output should equal.
    XYZ_t : ndarray (N, 3)
        Target tristimulus values.
    light : LightColour
    unreachable : ndarray (N,) of bool
        Texels needing more than the light gives (albedo clipped at 1) or a
        channel the light does not have.
    """

    rgb8: np.ndarray
    target_dac: np.ndarray
    XYZ_t: np.ndarray
    light: LightColour
    unreachable: np.ndarray


def level2_texture(reflectances, illuminant, display: DisplayModel | None = None, *,
                   k: float = DEFAULT_K, observer: str = DEFAULT_OBSERVER, wavelengths=None
                   ) -> Level2Texture:
    """Level-2 texels: ``albedo_lin = srgb_decode(DAC_t) ⊘ light_lin``, 8-bit sRGB encoded."""
    display = display or SRGBDisplay()
    light = light_colour(illuminant, display, k=k, observer=observer)
    dac, XYZ_t = target_dac(reflectances, illuminant, display, k=k, observer=observer,
                            wavelengths=wavelengths)
    rgb8, unreachable = level2_albedo8(quantize_dac(dac), light.linear)
    return Level2Texture(rgb8=rgb8, target_dac=dac, XYZ_t=XYZ_t, light=light,
                         unreachable=unreachable)


def level2_albedo8(dac_rgb8, light_linear) -> tuple[np.ndarray, np.ndarray]:
    """The level-2 texel of design §2 for integer target DAC values under a light.

    ``albedo_lin = srgb_decode(DAC_t / 255) ⊘ light_lin``, clipped to [0, 1]
    (0 where the light channel is below :data:`LIGHT_CHANNEL_FLOOR`), then
    encoded with the sRGB transfer function to 8 bits.

    Parameters
    ----------
    dac_rgb8 : array_like (..., 3) of int
        ``round(DAC_t)`` on 0..255 (:func:`workbench.display.quantize_dac`).
    light_linear : array_like (3,)
        The engine light colour, linear 0..1 (:attr:`LightColour.linear`).

    Returns
    -------
    texels : ndarray (..., 3), int64
        Texels 0..255 to upload.
    unreachable : ndarray (...), bool
        Texels the light cannot carry: an albedo above 1 (clipped) or a target
        in a channel the light does not have. Per channel this depends only on
        that channel's DAC and is non-decreasing in it.
    """
    light = np.asarray(light_linear, dtype=np.float64)
    wanted = srgb_decode(np.asarray(dac_rgb8, dtype=np.float64) / 255.0)
    dark = light < LIGHT_CHANNEL_FLOOR
    with np.errstate(divide="ignore", invalid="ignore"):
        albedo = np.where(dark, 0.0, wanted / np.where(dark, 1.0, light))
    unreachable = np.any(albedo > 1.0 + 1e-9, axis=-1) | np.any(dark & (wanted > 0), axis=-1)
    texels = quantize_dac(255.0 * srgb_encode(np.clip(albedo, 0.0, 1.0)))
    return texels, unreachable


def authored_srgb8(reflectances, *, wavelengths=None) -> np.ndarray:
    """'Perfectly authored' 8-bit sRGB texels: the exact sRGB of each surface under D65.

    ``XYZ`` under CIE D65 with the perfect diffuser at Y = 100 (k = 1), encoded
    for the ideal sRGB display, clipped to its gamut.
    """
    d65 = colour.SDS_ILLUMINANTS["D65"]
    display = SRGBDisplay()
    XYZ = reflectances_to_XYZ_relative(reflectances, d65, k=1.0, Y_white=100.0,
                                       wavelengths=wavelengths)
    return display.inverse_rgb8(XYZ)


@dataclass(frozen=True)
class ErrorTable:
    """Engine output vs theory for one source and level (the paper's Table 4, plus ΔE00).

    ``mean_abs``/``sd`` are per channel (R, G, B) of ``|engine − round(DAC_t)|``
    in DAC counts; ``dE00`` figures compare what the HMD shows with ``XYZ_t``
    in CIELAB relative to ``XYZ_t`` of the perfect diffuser under the source.
    """

    mean_abs: tuple[float, float, float]
    sd: tuple[float, float, float]
    mean_dE00: float
    max_dE00: float


def error_table(engine_rgb8, target, XYZ_t, XYZ_white, display: DisplayModel) -> ErrorTable:
    """Compare engine output with the theoretical ``DAC_t`` and score it in CIEDE2000."""
    engine_rgb8 = _as_rgb8(engine_rgb8, "engine output")
    difference = np.abs(engine_rgb8 - quantize_dac(target)).astype(float)
    dE = delta_E2000(display.forward(engine_rgb8), XYZ_t, XYZ_white)
    return ErrorTable(
        mean_abs=tuple(float(v) for v in difference.mean(axis=0)),
        sd=tuple(float(v) for v in difference.std(axis=0, ddof=1)) if len(difference) > 1
        else (0.0, 0.0, 0.0),
        mean_dE00=float(np.mean(dE)),
        max_dE00=float(np.max(dE)),
    )
