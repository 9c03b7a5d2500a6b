"""The level-2 texel of design §2 as 256-entry tables per channel, for the per-texel kernels.

The formula is :func:`workbench.colour_management.level2_albedo8`:
``albedo_lin = srgb_decode(DAC_t / 255) ⊘ light_lin``, clipped to [0, 1]
(0 where the light channel is below
:data:`workbench.colour_management.LIGHT_CHANNEL_FLOOR`), then encoded with the
sRGB transfer function to 8 bits. Once the integer ``DAC_t`` of a channel is
known, its texel depends on nothing else, so a 256-entry table per channel
(:func:`level2_texel_table`) is exact; and whether the light can carry it
(albedo ≤ 1, a channel the light has) is a threshold on that DAC
(:func:`level2_unreachable_dac`): the level from which the table saturates.
"""

from __future__ import annotations

import numpy as np

from workbench.colour_management import level2_albedo8

__all__ = ["NO_UNREACHABLE_DAC", "level2_texel_table", "level2_unreachable_dac"]

NO_UNREACHABLE_DAC = 256
""":func:`level2_unreachable_dac` of a channel every DAC level of which the light carries."""


def _per_channel(light_linear) -> tuple[np.ndarray, np.ndarray]:
    """``level2_albedo8`` of each channel alone at DAC 0..255: texels ``(3, 256)`` and
    unreachable ``(3, 256)`` (the other two channels at DAC 0, which is always reachable)."""
    levels = np.zeros((3, 256, 3), dtype=np.int64)
    for channel in range(3):
        levels[channel, :, channel] = np.arange(256)
    texels, unreachable = level2_albedo8(levels, light_linear)
    return texels[np.arange(3), :, np.arange(3)], unreachable


def level2_texel_table(light_linear) -> np.ndarray:
    """``(3, 256)`` uint8: the level-2 texel of each channel for each integer DAC 0..255."""
    texels, _ = _per_channel(light_linear)
    return np.ascontiguousarray(texels.astype(np.uint8))


def level2_unreachable_dac(light_linear) -> np.ndarray:
    """``(3,)`` int32: per channel, the smallest integer ``DAC_t`` the light cannot carry.

    A texel is unreachable (:func:`workbench.colour_management.level2_albedo8`)
    exactly when some channel's ``DAC_t`` is at or above this level;
    :data:`NO_UNREACHABLE_DAC` (256) where the light carries every level of the
    channel. A channel the light does not have gives 1 (only black is carried).
    """
    _, unreachable = _per_channel(light_linear)
    first = np.where(unreachable.any(axis=1), np.argmax(unreachable, axis=1), NO_UNREACHABLE_DAC)
    return first.astype(np.int32)
