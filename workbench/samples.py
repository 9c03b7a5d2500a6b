"""Reflectance sample sets: the ColorChecker and the 99 CIE 2017 colour evaluation samples.

Reflectances are returned at the working sampling (380–780 nm, 1 nm) as
``(N, 401)`` arrays on 0..1, with their names.

References
----------
- ColorChecker: BabelColor average spectral data (Pascale, D., 2006, "RGB
  coordinates of the Macbeth ColorChecker"), as shipped by colour-science
  (``SDS_COLOURCHECKERS["BabelColor Average"]``).
- CES: CIE 224:2017, "CIE 2017 Colour Fidelity Index for accurate scientific
  use", its 99 colour evaluation samples, as shipped by colour-science.
- Manufacturer sRGB of the ColorChecker: X-Rite's published values, as listed
  in the "Reference" column of Table 2 of Díaz-Barrancas et al. (2020).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import colour
import numpy as np

from workbench.colorimetry import WORKING_SHAPE, as_reflectances

__all__ = [
    "ReflectanceSet",
    "COLORCHECKER_SRGB_REFERENCE",
    "colorchecker",
    "ces99",
    "SAMPLE_SETS",
    "sample_set",
]

COLORCHECKER_SRGB_REFERENCE = np.array([
    [115, 82, 68], [194, 150, 130], [98, 122, 157], [87, 108, 67], [133, 128, 177],
    [103, 189, 170], [214, 126, 44], [80, 91, 166], [193, 90, 99], [94, 60, 108],
    [157, 188, 64], [224, 163, 46], [56, 61, 150], [70, 148, 73], [175, 54, 60],
    [231, 199, 31], [187, 86, 149], [8, 133, 161], [243, 243, 242], [200, 200, 200],
    [160, 160, 160], [122, 122, 121], [85, 85, 85], [52, 52, 52],
])
"""Manufacturer (X-Rite) 8-bit sRGB of the 24 ColorChecker patches under D65."""


@dataclass(frozen=True, eq=False)
class ReflectanceSet:
    """Named reflectances at the working sampling."""

    id: str
    names: tuple[str, ...]
    reflectances: np.ndarray  # (N, 401)

    def __len__(self) -> int:
        return len(self.names)


@lru_cache(maxsize=1)
def colorchecker() -> ReflectanceSet:
    """The 24 ColorChecker patches (BabelColor average spectra)."""
    sds = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    names = tuple(sds.keys())
    values = np.vstack([as_reflectances(sds[name]) for name in names])
    values.setflags(write=False)
    return ReflectanceSet("colorchecker", names, values)


@lru_cache(maxsize=1)
def ces99() -> ReflectanceSet:
    """The 99 colour evaluation samples of CIE 224:2017."""
    from colour.quality.cfi2017 import load_TCS_CIE2017

    msds = load_TCS_CIE2017(WORKING_SHAPE)
    values = as_reflectances(msds)
    values.setflags(write=False)
    return ReflectanceSet("ces99", tuple(msds.labels), values)


SAMPLE_SETS = {"colorchecker": colorchecker, "ces99": ces99}


def sample_set(name: str) -> ReflectanceSet:
    """One of :data:`SAMPLE_SETS` by id."""
    try:
        return SAMPLE_SETS[name]()
    except KeyError:
        raise ValueError(f"unknown sample set {name!r}; use one of {sorted(SAMPLE_SETS)}") from None
