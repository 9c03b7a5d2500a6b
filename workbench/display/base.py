"""What every display model is: forward (DAC → XYZ) and inverse (XYZ → DAC).

Scale: DAC values are floats on 0..255 (8-bit panels; :func:`quantize_dac`
rounds to the integer the panel receives); XYZ on the scale the model was
fitted on (absolute cd/m², or relative with the white at Y = 100).

Out-of-gamut policy (every model): the inverse returns the DAC triplet of the
nearest colour it can show by clipping each channel's linear drive to [0, 1]
(per-channel clipping in the model's linear space, then the tone curve),
never NaN; :meth:`DisplayModel.in_gamut` says which inputs were clipped.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np

from workbench.errors import InputError

__all__ = ["DisplayModel", "quantize_dac", "as_dac", "as_XYZ", "GAMUT_TOLERANCE",
           "check_observer"]

GAMUT_TOLERANCE = 1e-6
"""Linear drive beyond [0, 1] by more than this counts as out of gamut."""


def as_dac(rgb) -> np.ndarray:
    """Validated DAC values (..., 3) on 0..255."""
    rgb = np.asarray(rgb, dtype=float)
    if rgb.shape[-1:] != (3,):
        raise InputError(f"DAC values need a last axis of 3 (r, g, b); got shape {rgb.shape}")
    if not np.all(np.isfinite(rgb)):
        raise InputError("DAC values hold NaN or infinity")
    if np.any(rgb < 0) or np.any(rgb > 255):
        raise InputError(f"DAC values must lie in 0..255; got {rgb.min():g}..{rgb.max():g}")
    return rgb


def as_XYZ(XYZ) -> np.ndarray:
    """Validated tristimulus values (..., 3)."""
    XYZ = np.asarray(XYZ, dtype=float)
    if XYZ.shape[-1:] != (3,):
        raise InputError(f"XYZ needs a last axis of 3; got shape {XYZ.shape}")
    if not np.all(np.isfinite(XYZ)):
        raise InputError("XYZ holds NaN or infinity")
    return XYZ


def check_observer(display: "DisplayModel", observer: str) -> None:
    """Raise if ``observer`` is not the one the display model's XYZ are expressed for."""
    if observer != display.observer:
        raise InputError(
            f"the display model ({display.describe()}) is characterized for the {display.observer} "
            f"observer; XYZ for {observer} cannot drive it. Use --observer {display.observer} for "
            "light colours and textures (other observers are fine for XYZ and xy alone)")


def quantize_dac(dac) -> np.ndarray:
    """The integer DAC values (0..255) a panel receives for float DAC values."""
    return np.clip(np.round(np.asarray(dac, dtype=float)), 0, 255).astype(np.int64)


@dataclass(frozen=True, eq=False)
class DisplayModel(abc.ABC):
    """A colorimetric display model. Subclasses are frozen dataclasses."""

    #: registry id, e.g. ``"gamma-matrix"``
    model_id = ""

    #: observer the model's XYZ are expressed for: a CS-2000 reports CIE 1931 2°,
    #: and sRGB is defined for it. Colour management refuses to mix observers.
    observer = "cie1931-2"

    @property
    @abc.abstractmethod
    def white_XYZ(self) -> np.ndarray:
        """XYZ of the display white (the scale ``Y_white`` of relative colorimetry)."""

    @property
    def black_XYZ(self) -> np.ndarray:
        """XYZ measured at DAC 0 (zeros when the model has no black term)."""
        return np.zeros(3)

    @abc.abstractmethod
    def forward(self, rgb) -> np.ndarray:
        """XYZ shown for DAC values ``rgb`` (..., 3) on 0..255."""

    @abc.abstractmethod
    def linear_drive(self, XYZ) -> np.ndarray:
        """Unclipped linear drive (..., 3) that would produce ``XYZ``."""

    @abc.abstractmethod
    def dac_from_drive(self, drive) -> np.ndarray:
        """DAC values (float, 0..255) for linear drive clipped to [0, 1]."""

    def inverse(self, XYZ) -> np.ndarray:
        """Float DAC values (..., 3) that show ``XYZ``; out of gamut: clipped (module doc)."""
        drive = self.linear_drive(as_XYZ(XYZ))
        return self.dac_from_drive(np.clip(drive, 0.0, 1.0))

    def inverse_rgb8(self, XYZ) -> np.ndarray:
        """Integer DAC values the panel receives for ``XYZ``."""
        return quantize_dac(self.inverse(XYZ))

    def in_gamut(self, XYZ) -> np.ndarray:
        """True where ``XYZ`` is reachable without clipping."""
        drive = self.linear_drive(as_XYZ(XYZ))
        return np.all((drive >= -GAMUT_TOLERANCE) & (drive <= 1 + GAMUT_TOLERANCE), axis=-1)

    @abc.abstractmethod
    def parameters(self) -> dict:
        """JSON-ready parameters; ``from_parameters`` rebuilds the model from them."""

    @classmethod
    @abc.abstractmethod
    def from_parameters(cls, parameters: dict) -> "DisplayModel":
        """Rebuild a model from :meth:`parameters`."""

    def describe(self) -> str:
        return self.model_id
