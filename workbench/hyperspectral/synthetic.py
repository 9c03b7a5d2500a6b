"""Synthetic reflectance cubes made of real reflectance sets, mixed smoothly over the image.

The image is cut into square cells; each cell corner gets one reflectance
drawn from a set of materials — by default the ColorChecker (24, BabelColor
average) and the 99 CIE 2017 colour evaluation samples, or any set of
:mod:`workbench.hyperspectral.materials` — and each texel is the
smoothstep-weighted bilinear mixture of its cell's four corners. The cube thus
holds flat patches of real materials (around the corners) joined by soft
gradients of physically plausible mixtures (convex combinations), like painted
objects under a soft shading. Reproducible from the seed.

Scale: reflectance on 0..1, float32; wavelengths in nm (default 380–780 nm at
4 nm, 101 bands, the sampling of the paper's cubes).

References
----------
Díaz-Barrancas, F. et al. (2020), Sensors 20(19) 5658, §2.3 (cubes of 101 bands,
380–780 nm); CIE 224:2017 (the 99 samples); Pascale, D. (2006), BabelColor
ColorChecker data.
"""

from __future__ import annotations

import numpy as np

from workbench.errors import InputError
from workbench.hyperspectral.cube import ReflectanceCube
from workbench.hyperspectral.materials import material_reflectances

__all__ = ["PAPER_CUBE_WAVELENGTHS", "sample_reflectances", "synthesize_cube"]

PAPER_CUBE_WAVELENGTHS = np.arange(380.0, 781.0, 4.0)
"""380–780 nm at 4 nm: the 101 bands of the paper's hyperspectral cubes."""


def sample_reflectances(wavelengths=PAPER_CUBE_WAVELENGTHS) -> np.ndarray:
    """The ColorChecker (24) and CIE 2017 (99) reflectances at ``wavelengths``: ``(123, B)``."""
    return np.vstack([material_reflectances("colorchecker", wavelengths),
                      material_reflectances("ces99", wavelengths)])


def _smoothstep(t: np.ndarray) -> np.ndarray:
    return t * t * (3.0 - 2.0 * t)


def synthesize_cube(height: int, width: int, *, wavelengths=PAPER_CUBE_WAVELENGTHS,
                    cell: int = 64, seed: int = 0, reflectances=None,
                    materials: str | None = None) -> ReflectanceCube:
    """A ``height × width`` cube of real reflectances mixed smoothly (module doc).

    Parameters
    ----------
    height, width : int
        Texels.
    wavelengths : array_like
        Band centres (nm); default 380–780 nm at 4 nm.
    cell : int
        Cell size in texels (the distance between pure samples).
    seed : int
        Random seed of the corner assignment.
    reflectances : ndarray (M, B), optional
        The materials to mix (at ``wavelengths``); default :func:`sample_reflectances`.
    materials : str, optional
        What ``reflectances`` are, for the cube's ``source`` (e.g. "CIE 2017 samples").

    Returns
    -------
    ReflectanceCube
        float32, ``source`` describing how it was made. Memory: ``4·H·W·B``
        bytes (a 1024² × 101 cube is 424 MB); built a row at a time.
    """
    if height < 1 or width < 1 or cell < 1:
        raise InputError(f"a cube needs positive height, width and cell; got {height}, {width}, {cell}")
    wavelengths = np.asarray(wavelengths, dtype=np.float64)
    if reflectances is None:
        spectra = sample_reflectances(wavelengths)
        materials = materials or "ColorChecker + CIE 2017 samples"
    else:
        spectra = np.asarray(reflectances, dtype=np.float64)
        materials = materials or f"{len(spectra)} given reflectances"
    if spectra.ndim != 2 or spectra.shape[1] != wavelengths.size:
        raise InputError(f"reflectances must be (M, {wavelengths.size}); got {spectra.shape}")
    rng = np.random.default_rng(seed)
    rows, cols = -(-height // cell) + 1, -(-width // cell) + 1
    corners = spectra[rng.integers(0, len(spectra), size=(rows, cols))].astype(np.float32)
    x = np.arange(width)
    col_index = x // cell
    fx = _smoothstep((x % cell) / cell).astype(np.float32)[:, None]
    data = np.empty((height, width, wavelengths.size), dtype=np.float32)
    for y in range(height):
        j, fy = y // cell, np.float32(_smoothstep((y % cell) / cell))
        column_spectra = (1 - fy) * corners[j] + fy * corners[j + 1]        # (cols, B)
        data[y] = (1 - fx) * column_spectra[col_index] + fx * column_spectra[col_index + 1]
    source = (f"synthetic {height}×{width} cube: {materials} mixed over {cell}-texel cells "
              f"(seed {seed})")
    return ReflectanceCube(data, wavelengths, source)
