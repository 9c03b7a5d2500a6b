"""The level-2 texel of design §2 as a function of the target DAC, per channel.

``albedo_lin = srgb_decode(DAC_t / 255) ⊘ light_lin``, clipped to [0, 1]
(0 where the light channel is below
:data:`workbench.colour_management.LIGHT_CHANNEL_FLOOR`), then encoded with the
sRGB transfer function to 8 bits. Once the integer ``DAC_t`` of a channel is
known, its texel depends on nothing else: a 256-entry table per channel
(:func:`level2_texel_table`) is exact. This is the same arithmetic as
:func:`workbench.colour_management.level2_texture`, applied to integer DAC.
"""

from __future__ import annotations

import numpy as np

from workbench.colour_management import LIGHT_CHANNEL_FLOOR
from workbench.display import quantize_dac, srgb_decode, srgb_encode

__all__ = ["level2_texels_from_dac", "level2_texel_table"]


def level2_texels_from_dac(dac, light_linear) -> np.ndarray:
    """8-bit level-2 texels for integer target DAC values ``(..., 3)`` under a light.

    Parameters
    ----------
    dac : array_like (..., 3) of int
        ``round(DAC_t)`` on 0..255.
    light_linear : array_like (3,)
        The engine light colour, linear 0..1 (:attr:`LightColour.linear`).

    Returns
    -------
    ndarray (..., 3), int64
        Texels 0..255 to upload.
    """
    light = np.asarray(light_linear, dtype=np.float64)
    wanted = srgb_decode(np.asarray(dac, dtype=np.float64) / 255.0)
    dark = light < LIGHT_CHANNEL_FLOOR
    with np.errstate(divide="ignore", invalid="ignore"):
        albedo = np.where(dark, 0.0, wanted / np.where(dark, 1.0, light))
    return quantize_dac(255.0 * srgb_encode(np.clip(albedo, 0.0, 1.0)))


def level2_texel_table(light_linear) -> np.ndarray:
    """``(3, 256)`` uint8: the level-2 texel of each channel for each integer DAC 0..255."""
    levels = np.repeat(np.arange(256)[:, None], 3, axis=1)
    return np.ascontiguousarray(level2_texels_from_dac(levels, light_linear).T.astype(np.uint8))
