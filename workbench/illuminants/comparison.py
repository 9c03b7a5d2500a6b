"""What the Illuminants page compares: one table row per source, and the ColorChecker under it.

- :func:`source_row`: id, name, kind, CCT, Duv, Rf, Rg, xy and the level-1
  light colour for a headset profile and for the ideal sRGB display (the
  library's own metric functions; Rf/Rg are cached per spectrum, so a second
  pass over the library is fast).
- :func:`colorchecker_comparison`: the 24 patches as the headset shows them
  at level 1 and level 2 under the source, beside the colour they should have
  (``XYZ_t``, shown the same way), with CIEDE2000 per patch
  (:func:`workbench.scene.patch_errors`).

Swatch colours are 8-bit sRGB of this monitor with the headset white mapped
to the monitor white (:func:`workbench.scene.images.headset_to_monitor_rgb8`).
"""

from __future__ import annotations

from dataclasses import dataclass

import colour
import numpy as np

from workbench.colorimetry import DEFAULT_K, white_XYZ_relative
from workbench.colour_management import light_colour
from workbench.display import DisplayModel, SRGBDisplay
from workbench.illuminants.metrics import CCT_Duv, fidelity_Rf_Rg
from workbench.illuminants.source import Illuminant

__all__ = ["SourceRow", "PatchComparison", "source_row", "colorchecker_comparison"]


@dataclass(frozen=True)
class SourceRow:
    """One source in the Illuminants table."""

    id: str
    name: str
    kind: str
    CCT: float
    Duv: float
    Rf: float
    Rg: float
    xy: tuple[float, float]
    rgb8_profile: tuple[int, int, int]
    rgb8_srgb: tuple[int, int, int]
    light_in_gamut: bool


@dataclass(frozen=True, eq=False)
class PatchComparison:
    """The ColorChecker under one source on one headset.

    Attributes
    ----------
    source : str
    names : tuple of str
    target_rgb8 : ndarray (24, 3) uint8
        ``XYZ_t`` (the patch under the source) as the headset would show it exactly.
    level1_rgb8, level2_rgb8 : ndarray (24, 3) uint8
        What the headset shows at each level.
    level1_dE00, level2_dE00 : ndarray (24,)
    """

    source: str
    names: tuple
    target_rgb8: np.ndarray
    level1_rgb8: np.ndarray
    level2_rgb8: np.ndarray
    level1_dE00: np.ndarray
    level2_dE00: np.ndarray


def source_row(illuminant: Illuminant, display: DisplayModel, *, k: float = DEFAULT_K) -> SourceRow:
    """The table row of ``illuminant`` with the light colour for ``display`` and for sRGB."""
    Rf, Rg = fidelity_Rf_Rg(illuminant)
    CCT, Duv = CCT_Duv(illuminant)
    light = light_colour(illuminant.sd, display, k=k, observer=display.observer)
    srgb = light_colour(illuminant.sd, SRGBDisplay(), k=k)
    xy = colour.XYZ_to_xy(white_XYZ_relative(illuminant.sd, "cie1931-2", k=k, Y_white=100.0))
    return SourceRow(id=illuminant.id, name=illuminant.name, kind=illuminant.kind, CCT=CCT,
                     Duv=Duv, Rf=Rf, Rg=Rg, xy=(float(xy[0]), float(xy[1])),
                     rgb8_profile=tuple(int(v) for v in light.rgb8),
                     rgb8_srgb=tuple(int(v) for v in srgb.rgb8),
                     light_in_gamut=bool(light.in_gamut))


def colorchecker_comparison(illuminant: Illuminant, display: DisplayModel, *,
                            k: float = DEFAULT_K) -> PatchComparison:
    """The ColorChecker under ``illuminant`` at both levels on ``display``, with ΔE00 per patch."""
    from workbench.scene.errors import patch_errors
    from workbench.scene.images import headset_to_monitor_rgb8

    errors = patch_errors(illuminant, display, k=k)
    level1, level2 = errors.level(1), errors.level(2)
    return PatchComparison(
        source=illuminant.id, names=tuple(p.name for p in level1),
        target_rgb8=headset_to_monitor_rgb8(np.array([p.target_dac for p in level1]), display),
        level1_rgb8=headset_to_monitor_rgb8(np.array([p.engine_dac for p in level1]), display),
        level2_rgb8=headset_to_monitor_rgb8(np.array([p.engine_dac for p in level2]), display),
        level1_dE00=np.array([p.dE00 for p in level1]),
        level2_dE00=np.array([p.dE00 for p in level2]),
    )
