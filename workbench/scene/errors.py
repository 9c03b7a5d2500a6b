"""The per-patch error table beside the scene: the paper's Table 4, patch by patch, for any source and profile.

For each ColorChecker patch and each level: the engine output (DAC) against
the theoretical ``round(DAC_t)`` (``|ΔR|``, ``|ΔG|``, ``|ΔB|`` in counts) and the CIEDE2000
between what the headset shows and ``XYZ_t`` (CIELAB white: ``XYZ_t`` of the
perfect diffuser under the source). The summary rows are
:func:`workbench.colour_management.error_table`, computed exactly as
:func:`workbench.reproduction.table4` computes the paper's Table 4 (on the
ideal sRGB display these are its numbers), and carry the paper's own figures
for its four sources.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.colorimetry import DEFAULT_K, delta_E2000
from workbench.colour_management import (
    ErrorTable,
    engine_render,
    error_table,
    level2_texture,
    light_colour,
    target_dac,
)
from workbench.display import DisplayModel, quantize_dac
from workbench.reproduction import PAPER_TABLE4
from workbench.samples import COLORCHECKER_SRGB_REFERENCE, colorchecker

__all__ = ["PatchError", "SourceErrors", "patch_errors"]


@dataclass(frozen=True)
class PatchError:
    """One ColorChecker patch under one source at one level."""

    patch: int
    name: str
    level: int
    target_dac: tuple[int, int, int]
    engine_dac: tuple[int, int, int]
    abs_dac: tuple[int, int, int]
    dE00: float


@dataclass(frozen=True)
class SourceErrors:
    """Per-patch errors at both levels and their Table-4 summaries.

    Attributes
    ----------
    source : str
    display : str
        The display model's description.
    patches : tuple of PatchError
        24 rows at level 1, then 24 at level 2.
    summary : dict
        ``{level: ErrorTable}``.
    paper : dict
        ``{level: (mean_abs, sd)}`` from the paper's Table 4 where it has the
        source (measured on an sRGB engine pipeline), else empty.
    """

    source: str
    display: str
    patches: tuple[PatchError, ...]
    summary: dict
    paper: dict

    def level(self, level: int) -> tuple[PatchError, ...]:
        return tuple(p for p in self.patches if p.level == level)


def patch_errors(illuminant, display: DisplayModel, *, k: float = DEFAULT_K) -> SourceErrors:
    """Per-patch level-1 and level-2 errors of the ColorChecker under ``illuminant`` on ``display``."""
    patches = colorchecker()
    sd = illuminant.sd
    observer = display.observer
    light = light_colour(sd, display, k=k, observer=observer)
    dac_t, XYZ_t = target_dac(patches.reflectances, sd, display, k=k, observer=observer)
    level2 = level2_texture(patches.reflectances, sd, display, k=k, observer=observer)
    textures = {1: np.asarray(COLORCHECKER_SRGB_REFERENCE), 2: level2.rgb8}
    rows: list[PatchError] = []
    summary: dict[int, ErrorTable] = {}
    target = quantize_dac(dac_t)
    for level, texture in textures.items():
        engine = engine_render(texture, light.rgb8)
        summary[level] = error_table(engine, dac_t, XYZ_t, light.XYZ, display)
        dE = delta_E2000(display.forward(engine), XYZ_t, light.XYZ)
        for i, name in enumerate(patches.names):
            rows.append(PatchError(
                patch=i + 1, name=name, level=level,
                target_dac=tuple(int(v) for v in target[i]),
                engine_dac=tuple(int(v) for v in engine[i]),
                abs_dac=tuple(int(v) for v in np.abs(engine[i] - target[i])),
                dE00=float(dE[i])))
    paper = {level: PAPER_TABLE4[(illuminant.id, level)] for level in textures
             if (illuminant.id, level) in PAPER_TABLE4}
    return SourceErrors(source=illuminant.id, display=display.describe(), patches=tuple(rows),
                        summary=summary, paper=paper)
