"""Cone fundamentals of the simulated observers and the dichromats' copunctal points.

The observers of :mod:`workbench.ishihara` share one set of cone fundamentals:
Smith & Pokorny's (1975) linear transform of colour-matching functions,
applied here to the CIE 1931 2° observer that every other figure of the
workbench uses. Because ``LMS = T · XYZ`` exactly, two lights with the same
CIE 1931 XYZ excite every simulated observer's cones identically (normal,
anomalous or dichromat; Machado et al.'s shift keeps the fundamentals linear in
XYZ), and a confusion line of a dichromat is a straight line in the CIE 1931
xy diagram through that dichromat's copunctal point.

The copunctal points are *computed* from the transform: the protanope's is the
chromaticity of the light that excites only the L cones (M = S = 0), the
deuteranope's only the M cones, the tritanope's only the S cones. They come
out as the published values
(protan 0.7465, 0.2535; deutan 1.40, −0.40; tritan 0.1748, 0.0), which is
checked by the tests.

Scale: fundamentals on the working wavelengths (380–780 nm, 1 nm), each as the
transform gives it (``L + M = ȳ``); cone excitations are linear in radiance
and carry its unit.

References
----------
Smith, V. C., & Pokorny, J. (1975). Spectral sensitivity of the foveal cone
photopigments between 400 and 500 nm. *Vision Research*, 15(2), 161–171.

Wyszecki, G., & Stiles, W. S. (1982). *Color Science*, 2nd ed., Wiley,
§5.14 (dichromats' confusion lines and copunctal points) and Table 2(8.2.5).

Viénot, F., Brettel, H., & Mollon, J. D. (1999). Digital video colourmaps for
checking the legibility of displays by dichromats. *Color Research &
Application*, 24(4), 243–252 (the same copunctal points, CIE 1931 xy).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from workbench.colorimetry import observer_cmfs

__all__ = [
    "MATRIX_XYZ_TO_LMS_SMITH_POKORNY1975",
    "CONES",
    "COPUNCTAL_DEFICIENCIES",
    "cone_fundamentals_Smith_Pokorny1975",
    "XYZ_to_LMS",
    "LMS_to_XYZ",
    "copunctal_point",
    "confusion_line_residual",
]

MATRIX_XYZ_TO_LMS_SMITH_POKORNY1975 = np.array([
    [0.15514, 0.54312, -0.03286],
    [-0.15514, 0.45684, 0.03286],
    [0.0, 0.0, 0.00801],
])
"""Smith & Pokorny (1975): ``[L, M, S] = T · [X, Y, Z]`` (rows L, M, S)."""

CONES = ("L", "M", "S")

COPUNCTAL_DEFICIENCIES = {"protan": 0, "deutan": 1, "tritan": 2}
"""Deficiency → index of the cone class whose absence defines its confusion lines."""


@lru_cache(maxsize=1)
def _fundamentals() -> np.ndarray:
    cmfs = observer_cmfs("cie1931-2").values  # (401, 3) x̄ ȳ z̄
    fundamentals = cmfs @ MATRIX_XYZ_TO_LMS_SMITH_POKORNY1975.T
    fundamentals.setflags(write=False)
    return fundamentals


def cone_fundamentals_Smith_Pokorny1975() -> np.ndarray:
    """L, M, S cone fundamentals (401, 3) at the working wavelengths.

    Returns
    -------
    ndarray, shape (401, 3)
        ``T · [x̄, ȳ, z̄]`` with the CIE 1931 2° colour-matching functions
        (so ``L + M = ȳ``); a read-only array shared by every caller.

    References
    ----------
    Smith & Pokorny (1975), see the module.
    """
    return _fundamentals()


def XYZ_to_LMS(XYZ) -> np.ndarray:
    """Cone excitations ``(…, 3)`` of tristimulus values ``(…, 3)`` (same scale)."""
    return np.asarray(XYZ, dtype=float) @ MATRIX_XYZ_TO_LMS_SMITH_POKORNY1975.T


def LMS_to_XYZ(LMS) -> np.ndarray:
    """Tristimulus values ``(…, 3)`` of cone excitations ``(…, 3)`` (same scale)."""
    return np.asarray(LMS, dtype=float) @ np.linalg.inv(MATRIX_XYZ_TO_LMS_SMITH_POKORNY1975).T


def copunctal_point(deficiency: str) -> np.ndarray:
    """CIE 1931 xy of the copunctal point of ``"protan"``, ``"deutan"`` or ``"tritan"``.

    The chromaticity of the light that excites only the missing cone class:
    every confusion line of that dichromat passes through it.

    Returns
    -------
    ndarray, shape (2,)
        Protan (0.7465, 0.2535), deutan (1.4000, −0.4000), tritan (0.1748, 0.0000)
        to the four decimals of the transform.
    """
    try:
        cone = COPUNCTAL_DEFICIENCIES[deficiency]
    except KeyError:
        raise ValueError(f"no copunctal point for {deficiency!r}; use one of "
                         f"{sorted(COPUNCTAL_DEFICIENCIES)}") from None
    XYZ = LMS_to_XYZ(np.eye(3)[cone])
    return XYZ[:2] / XYZ.sum()


def confusion_line_residual(xy_a, xy_b, deficiency: str) -> np.ndarray:
    """How far ``xy_b`` is from the confusion line of ``deficiency`` through ``xy_a``.

    Returns the difference (radians) of the directions in which the copunctal
    point sees the two chromaticities: 0 when both lie on one confusion line.
    """
    point = copunctal_point(deficiency)
    a = np.asarray(xy_a, dtype=float) - point
    b = np.asarray(xy_b, dtype=float) - point
    angle = np.arctan2(a[..., 1], a[..., 0]) - np.arctan2(b[..., 1], b[..., 0])
    return np.abs((angle + np.pi) % (2 * np.pi) - np.pi)
