"""The light source record every part of the library shares."""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

__all__ = ["Illuminant", "SOURCE_KINDS"]

SOURCE_KINDS = ("cie", "synthesized", "imported", "measured")


@dataclass(frozen=True, eq=False)
class Illuminant:
    """A light source.

    Attributes
    ----------
    id : str
        Stable identifier (``cie-d65``, ``d65-two-peak``, ``file:...``).
    name : str
        Human-readable name.
    kind : str
        One of :data:`SOURCE_KINDS`.
    sd : colour.SpectralDistribution
        Relative spectral power at the working sampling (380–780 nm, 1 nm).
    description : str
        Where it comes from or how it was made.
    native_sd : colour.SpectralDistribution, optional
        The spectrum as defined or imported, before resampling to the working
        range (CCT and Duv are computed from it over 360–830 nm, as CIE 015
        defines them); ``sd`` when not given.
    """

    id: str
    name: str
    kind: str
    sd: colour.SpectralDistribution
    description: str = ""
    native_sd: colour.SpectralDistribution | None = None

    def __post_init__(self):
        if self.native_sd is None:
            object.__setattr__(self, "native_sd", self.sd)

    @property
    def wavelengths(self) -> np.ndarray:
        return self.sd.wavelengths

    @property
    def values(self) -> np.ndarray:
        return self.sd.values
