"""Level-2 relighting from basis coefficients in NumPy, through the display model's own inverse.

For every display model, separable or not: per block of texels, float16 →
float32 coefficients, ``XYZ = offset + c @ M`` (float32 BLAS), then
:meth:`DisplayModel.inverse` (float64), rounding to the integer ``DAC_t`` and
the per-channel level-2 texel table; a texel is counted unreachable when a
channel's DAC reaches the light's unreachable level. Several passes over memory per block
(the conversion, the product, the inverse's intermediates), so it is several
times slower than the fused kernel of :mod:`.relight_numba`; it is the path
for models that are not separable per channel and a second implementation to
check the fused kernel against.
"""

from __future__ import annotations

import numpy as np

from workbench.display import DisplayModel, quantize_dac

__all__ = ["BLOCK_TEXELS", "relight_level2_planes_numpy"]

BLOCK_TEXELS = 1 << 16
"""Texels per block (a few MB of float64 intermediates)."""


def relight_level2_planes_numpy(planes: np.ndarray, XYZ_matrix: np.ndarray, XYZ_offset: np.ndarray,
                                display: DisplayModel, texel_table: np.ndarray,
                                unreachable_dac: np.ndarray, out: np.ndarray) -> int:
    """Level-2 texels for flattened coefficient planes (module doc).

    Parameters
    ----------
    planes : ndarray (K, N), float16
    XYZ_matrix : ndarray (K, 3)
        Basis × source weights, on the display's XYZ scale.
    XYZ_offset : ndarray (3,)
        The mean reflectance's ``XYZ_t``.
    display : DisplayModel
    texel_table : ndarray (3, 256), uint8
    unreachable_dac : ndarray (3,), int
        Per channel, the DAC from which the light cannot carry the texel
        (:func:`~workbench.hyperspectral.level2_texels.level2_unreachable_dac`).
    out : ndarray (N, 3), uint8
        Receives the texels.

    Returns
    -------
    int
        The number of unreachable texels.
    """
    matrix = np.asarray(XYZ_matrix, dtype=np.float32)
    offset = np.asarray(XYZ_offset, dtype=np.float32)
    channels = np.arange(3)
    unreachable = 0
    for start in range(0, planes.shape[1], BLOCK_TEXELS):
        coefficients = planes[:, start:start + BLOCK_TEXELS].astype(np.float32)
        XYZ = coefficients.T @ matrix + offset
        dac = quantize_dac(display.inverse(XYZ))
        out[start:start + dac.shape[0]] = texel_table[channels, dac]
        unreachable += int(np.count_nonzero(np.any(dac >= unreachable_dac, axis=-1)))
    return unreachable
