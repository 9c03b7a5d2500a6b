"""Hyperspectral textures: reflectance cubes, their files, and real-time level-2 relighting.

- :mod:`.cube`: :class:`ReflectanceCube` (``(H, W, B)`` float32 reflectance,
  wavelengths in nm) and its validation.
- :mod:`.io`: one reader/writer dispatcher over a registry of formats by
  suffix (:data:`CUBE_FORMATS`: ENVI, ``.npz``, HDF5, MATLAB); atomic writes.
- :mod:`.resampling`: to other wavelengths; colorimetric weights at a cube's bands.
- :mod:`.materials`: sets of real reflectances by material
  (:data:`MATERIAL_SETS`), to fit, choose and check bases apart.
- :mod:`.basis`: the colorimetrically weighted PCA basis, K chosen by held-out
  CIEDE2000, float16 coefficient planes.
- :mod:`.relight`: a lighting change (:func:`plan_relight`), the fused
  per-texel kernel (:func:`relight_level2`: texels and the count of texels the
  light cannot carry; :func:`relight_texels`: the texels), the full-band
  reference (:func:`relight_level2_full_band`, :func:`relight_full_band`) and
  the level-1 texture.
- :mod:`.benchmark`: the relight benchmark behind ``python -m workbench bench relight``.
- :mod:`.png`: the texture file.

Scale: reflectance 0..1; wavelengths nm; XYZ on the display's scale; texels
uint8 sRGB-encoded (design §2).

The numba kernel is imported on first use, so importing this package does not
compile anything.
"""

from __future__ import annotations

from workbench.hyperspectral.basis import (
    ACCURACY_SOURCES,
    BASIS_SOURCES,
    BasisAccuracy,
    BasisCube,
    SpectralBasis,
    basis_accuracy,
    encode_cube,
    fit_cube_basis,
    fit_spectral_basis,
)
from workbench.hyperspectral.channel_inverse import (
    ChannelInverseLUT,
    channel_inverse_lut,
    is_channel_separable,
)
from workbench.hyperspectral.cube import REFLECTANCE_RANGE, REQUIRED_RANGE_NM, ReflectanceCube
from workbench.hyperspectral.io import CUBE_FORMATS, CubeFormat, read_cube, write_cube
from workbench.hyperspectral.materials import MATERIAL_SETS, material_reflectances
from workbench.hyperspectral.png import write_png_rgb8
from workbench.hyperspectral.relight import (
    RELIGHT_KERNELS,
    RelightPlan,
    RelitTexture,
    authored_srgb8_cube,
    plan_relight,
    relight_full_band,
    relight_level2,
    relight_level2_full_band,
    relight_texels,
)
from workbench.hyperspectral.resampling import XYZ_band_weights, resample_cube, resampling_matrix
from workbench.hyperspectral.synthetic import PAPER_CUBE_WAVELENGTHS, synthesize_cube

__all__ = [
    "ACCURACY_SOURCES",
    "BASIS_SOURCES",
    "BasisAccuracy",
    "BasisCube",
    "ChannelInverseLUT",
    "CUBE_FORMATS",
    "CubeFormat",
    "MATERIAL_SETS",
    "PAPER_CUBE_WAVELENGTHS",
    "REFLECTANCE_RANGE",
    "RELIGHT_KERNELS",
    "REQUIRED_RANGE_NM",
    "ReflectanceCube",
    "RelightPlan",
    "RelitTexture",
    "SpectralBasis",
    "XYZ_band_weights",
    "authored_srgb8_cube",
    "basis_accuracy",
    "channel_inverse_lut",
    "encode_cube",
    "fit_cube_basis",
    "fit_spectral_basis",
    "is_channel_separable",
    "material_reflectances",
    "plan_relight",
    "read_cube",
    "relight_full_band",
    "relight_level2",
    "relight_level2_full_band",
    "relight_texels",
    "resample_cube",
    "resampling_matrix",
    "synthesize_cube",
    "write_cube",
    "write_png_rgb8",
]
