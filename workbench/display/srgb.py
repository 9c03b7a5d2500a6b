"""The ideal sRGB display (IEC 61966-2-1): the engine's native space, as in the paper.

DAC values are sRGB-encoded 8-bit values; the white (255, 255, 255) has
``Y = Y_white`` (100 by default) at the D65 chromaticity of sRGB. Transfer
function and primaries are colour-science's (``RGB_COLOURSPACE_sRGB``).
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from workbench.display.base import DisplayModel, as_dac

__all__ = ["SRGBDisplay", "srgb_encode", "srgb_decode"]

_SRGB = colour.models.RGB_COLOURSPACE_sRGB


def srgb_decode(encoded) -> np.ndarray:
    """sRGB-encoded values on 0..1 → linear light on 0..1 (IEC 61966-2-1 EOTF)."""
    return np.asarray(colour.models.eotf_sRGB(np.asarray(encoded, dtype=float)))


def srgb_encode(linear) -> np.ndarray:
    """Linear light on 0..1 → sRGB-encoded values on 0..1 (inverse EOTF)."""
    return np.asarray(colour.models.eotf_inverse_sRGB(np.asarray(linear, dtype=float)))


@dataclass(frozen=True, eq=False)
class SRGBDisplay(DisplayModel):
    """An ideal sRGB monitor whose white has luminance ``Y_white``."""

    Y_white: float = 100.0

    model_id = "srgb"

    @property
    def matrix(self) -> np.ndarray:
        return _SRGB.matrix_RGB_to_XYZ * self.Y_white

    @property
    def white_XYZ(self) -> np.ndarray:
        return self.matrix.sum(axis=1)

    def forward(self, rgb) -> np.ndarray:
        return srgb_decode(as_dac(rgb) / 255.0) @ self.matrix.T

    def linear_drive(self, XYZ) -> np.ndarray:
        return np.asarray(XYZ, dtype=float) @ (_SRGB.matrix_XYZ_to_RGB.T / self.Y_white)

    def dac_from_drive(self, drive) -> np.ndarray:
        return 255.0 * srgb_encode(drive)

    def parameters(self) -> dict:
        return {"Y_white": float(self.Y_white)}

    @classmethod
    def from_parameters(cls, parameters: dict) -> "SRGBDisplay":
        return cls(Y_white=float(parameters.get("Y_white", 100.0)))

    def describe(self) -> str:
        return f"ideal sRGB (white Y = {self.Y_white:g})"
