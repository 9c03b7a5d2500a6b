"""What reaches the observer's eye from each dot, for a light source and a way of showing it.

Viewing paths (:data:`VIEWING_PATHS`):

``physical``
    The real plate under the source: radiance ``ρ(λ) · S(λ)``. The reference
    a virtual test should reproduce.
``level-1``
    The HMD at colour-management level 1 (design §2): the engine light is the
    display's rendering of the source's white, the texture stays as authored
    (the exact sRGB of each dot under D65); the engine multiplies them, the
    headset emits its spectrum for the resulting DAC values.
``level-2``
    The HMD at level 2: each texel is re-authored so that the engine output is
    the display inverse of the dot's ``XYZ_t`` under the source.

The headset is :func:`workbench.ishihara.hmd.calibrated_headset`: the simulated
HTC Vive with Table 1's black and a 5 % channel interaction, with the display
model the workbench would use: the paper's model extended with what the
diagnosis of its measured calibration found. Level 2 here uses the full-band
reference path (:func:`~workbench.colour_management.level2_texture`); Table 5
checks the real-time basis path against it.

Scale: radiance in the source's (``physical``) or the headset's
(W·sr⁻¹·m⁻²·nm⁻¹) unit; the observers' chromatic coordinates do not depend on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.colorimetry import DEFAULT_K
from workbench.colour_management import authored_srgb8, engine_render, level2_texture, light_colour
from workbench.errors import InputError
from workbench.illuminants import get_illuminant
from workbench.ishihara.hmd import CalibratedHeadset, calibrated_headset

__all__ = [
    "VIEWING_PATHS",
    "Viewing",
    "parse_level",
    "dot_radiance",
]


def _physical(reflectances, illuminant, hmd: CalibratedHeadset | None, k: float):
    return reflectances * np.asarray(illuminant.sd.values)


def _level1(reflectances, illuminant, hmd: CalibratedHeadset | None, k: float):
    hmd = hmd or calibrated_headset()
    light = light_colour(illuminant.sd, hmd.display, k=k)
    return hmd.radiance(engine_render(authored_srgb8(reflectances), light.rgb8))


def _level2(reflectances, illuminant, hmd: CalibratedHeadset | None, k: float):
    hmd = hmd or calibrated_headset()
    texture = level2_texture(reflectances, illuminant.sd, hmd.display, k=k)
    return hmd.radiance(engine_render(texture.rgb8, texture.light.rgb8))


VIEWING_PATHS = {
    "physical": _physical,
    "level-1": _level1,
    "level-2": _level2,
}
"""Viewing path → ``(reflectances (N, 401), Illuminant, hmd, k) → radiance (N, 401)``."""


def parse_level(text) -> str:
    """A viewing path from ``1``, ``2``, ``"level-1"``, ``"physical"`` …"""
    key = str(text).strip().lower()
    key = {"1": "level-1", "2": "level-2", "real": "physical", "plate": "physical"}.get(key, key)
    if key not in VIEWING_PATHS:
        raise InputError(f"unknown level {text!r}; use 1 or 2 (the HMD at that colour-management "
                         "level) or 'physical' (the real plate under the source)")
    return key


@dataclass(frozen=True)
class Viewing:
    """A light source and a way of showing the plate.

    Attributes
    ----------
    illuminant : str
        Library id or spectrum file (:func:`workbench.illuminants.get_illuminant`).
    path : str
        A key of :data:`VIEWING_PATHS`.
    k : float
        Scene-white factor of relative colorimetry (design §2).
    """

    illuminant: str = "cie-d65"
    path: str = "level-2"
    k: float = DEFAULT_K

    def __post_init__(self):
        object.__setattr__(self, "path", parse_level(self.path))

    def describe(self) -> str:
        where = "the real plate" if self.path == "physical" else f"the HMD at {self.path}"
        return f"{where} under {self.illuminant}"


def dot_radiance(reflectances, viewing: Viewing, hmd: CalibratedHeadset | None = None) -> np.ndarray:
    """Spectral radiance ``(N, 401)`` reaching the eye from dots of ``reflectances`` ``(N, 401)``."""
    illuminant = get_illuminant(viewing.illuminant)
    reflectances = np.asarray(reflectances, dtype=float)
    return VIEWING_PATHS[viewing.path](reflectances, illuminant, hmd, viewing.k)
