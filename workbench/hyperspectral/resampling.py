"""Spectral resampling of cubes, and colorimetric weights at a cube's own bands.

Resampling is linear interpolation with the end values held outside the data
(:func:`numpy.interp`), exactly what :func:`workbench.colorimetry.as_reflectances`
does to a reflectance given at other wavelengths. Because that is a linear map
``ρ_working = R · ρ_cube``, integrating a resampled cube with the working
weights ``W`` (380–780 nm, 1 nm) equals integrating the cube at its own bands
with ``Rᵀ W``: :func:`XYZ_band_weights` gives those ``(B, 3)`` weights, so a
101-band cube is integrated by a ``(N, 101) @ (101, 3)`` product without ever
being resampled to 401 bands (4× the memory).

Scale: wavelengths in nm; weights as :func:`workbench.colorimetry.XYZ_relative_weights`
(``XYZ_t = ρ @ W``, a perfect diffuser at ``Y = k · Y_white``).
"""

from __future__ import annotations

import numpy as np

from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER, WORKING_WAVELENGTHS, XYZ_relative_weights
from workbench.hyperspectral.cube import ReflectanceCube

__all__ = ["resampling_matrix", "resample_cube", "XYZ_band_weights"]

_RESAMPLE_ROWS = 32


def resampling_matrix(from_wavelengths, to_wavelengths) -> np.ndarray:
    """The ``(T, B)`` matrix ``R`` with ``ρ_to = R @ ρ_from`` (linear, ends held).

    Parameters
    ----------
    from_wavelengths : array_like, shape (B,)
        Source band centres (nm), strictly increasing.
    to_wavelengths : array_like, shape (T,)
        Target wavelengths (nm).

    Returns
    -------
    ndarray, shape (T, B), float64
        Each row sums to 1; it is :func:`numpy.interp` applied to unit impulses.
    """
    source = np.asarray(from_wavelengths, dtype=np.float64)
    target = np.asarray(to_wavelengths, dtype=np.float64)
    impulses = np.eye(source.size)
    return np.stack([np.interp(target, source, impulse) for impulse in impulses], axis=1)


def resample_cube(cube: ReflectanceCube, wavelengths=WORKING_WAVELENGTHS) -> ReflectanceCube:
    """``cube`` resampled to ``wavelengths`` (default: the working 380–780 nm, 1 nm).

    Notes
    -----
    Memory: the result has ``H · W · T`` float32 values (a 1024² cube at the
    working sampling is 1.6 GB); the work is done a few rows at a time.
    Relighting never needs this (see :func:`XYZ_band_weights`).
    """
    target = np.asarray(wavelengths, dtype=np.float64)
    if np.array_equal(target, cube.wavelengths):
        return cube
    matrix = resampling_matrix(cube.wavelengths, target).T.astype(np.float32)
    out = np.empty((cube.height, cube.width, target.size), dtype=np.float32)
    for start in range(0, cube.height, _RESAMPLE_ROWS):
        np.matmul(cube.data[start:start + _RESAMPLE_ROWS], matrix,
                  out=out[start:start + _RESAMPLE_ROWS])
    np.clip(out, 0.0, None, out=out)  # interpolation of non-negative data stays >= 0, up to rounding
    return ReflectanceCube(out, target, cube.source)


def XYZ_band_weights(illuminant, wavelengths, observer: str = DEFAULT_OBSERVER, *,
                     k: float = DEFAULT_K, Y_white: float = 100.0) -> np.ndarray:
    """Weights ``(B, 3)`` such that ``XYZ_t = ρ_cube @ W_B`` for reflectance at ``wavelengths``.

    ``W_B = Rᵀ W`` with ``W`` the working-sampling weights of
    :func:`workbench.colorimetry.XYZ_relative_weights` (colour-science's
    integration) and ``R`` the :func:`resampling_matrix` to the working
    wavelengths; identical, up to rounding, to resampling the reflectance and
    integrating it (design §2 relative colorimetry).

    Parameters
    ----------
    illuminant : colour.SpectralDistribution
        The source (its absolute scale does not matter).
    wavelengths : array_like, shape (B,)
        The cube's band centres (nm).
    observer, k, Y_white
        As :func:`workbench.colorimetry.XYZ_relative_weights`.

    Returns
    -------
    ndarray, shape (B, 3), float64
    """
    weights = XYZ_relative_weights(illuminant, observer, k=k, Y_white=Y_white)
    return resampling_matrix(wavelengths, WORKING_WAVELENGTHS).T @ weights
