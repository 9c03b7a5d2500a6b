"""Relighting a hyperspectral texture: level-2 texels for a source, fast (basis) and full band.

Design §2, level 2: for every texel ``DAC_t = display_inverse(XYZ_t(ρ))`` and
the texel uploaded is ``srgb_encode(srgb_decode(DAC_t) ⊘ light_lin)`` (clipped,
8-bit), so that the engine's ``albedo ⊙ light`` lands on ``DAC_t``.

- :func:`plan_relight` is the work of a lighting change: the K × 3 matrix
  (basis × source weights, folded with the display's XYZ → drive matrix) and
  the light's 256-entry texel tables.
- :func:`relight_level2` runs one per-texel kernel over the float16
  coefficient planes and counts the texels the light cannot carry (design §2:
  "the texel says so"); :func:`relight_texels` is its texels alone. The
  kernels are a registry, :data:`RELIGHT_KERNELS`: ``"numba"`` (fused, for
  separable displays: the default) and ``"numpy"`` (any display model, through
  its own inverse).
- :func:`relight_level2_full_band` is the reference: the ``(N, B) @ (B, 3)``
  float32 product of the full cube with the source weights, then the display
  model's inverse and the same texel arithmetic; :func:`relight_full_band` is
  its texels alone.
- :func:`authored_srgb8_cube` is the level-1 texture: the cube's sRGB under D65
  (the texture as scanned), which level 1 leaves as is.

Scale: XYZ on the display's scale (``Y_white`` = its white luminance, the
perfect diffuser at ``k · Y_white``); texels uint8 ``(H, W, 3)`` in the cube's
spatial layout.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from dataclasses import dataclass

import colour
import numpy as np

from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER
from workbench.colour_management import LightColour, level2_albedo8, light_colour_from_XYZ
from workbench.display import DisplayModel, SRGBDisplay, quantize_dac
from workbench.errors import InputError
from workbench.hyperspectral.basis import BasisCube, SpectralBasis
from workbench.hyperspectral.channel_inverse import (
    ChannelInverseLUT,
    DacCells,
    channel_inverse_lut,
    dac_cells,
    is_channel_separable,
)
from workbench.hyperspectral.cube import ReflectanceCube
from workbench.hyperspectral.level2_texels import level2_texel_table, level2_unreachable_dac
from workbench.hyperspectral.relight_numpy import relight_level2_planes_numpy
from workbench.hyperspectral.resampling import XYZ_band_weights

__all__ = [
    "RelightPlan",
    "RelitTexture",
    "RELIGHT_KERNELS",
    "plan_relight",
    "relight_level2",
    "relight_texels",
    "relight_level2_full_band",
    "relight_full_band",
    "authored_srgb8_cube",
    "display_inverse_lut",
]

_INVERSE_LUTS: "weakref.WeakKeyDictionary[DisplayModel, ChannelInverseLUT | None]" = \
    weakref.WeakKeyDictionary()


def display_inverse_lut(display: DisplayModel) -> ChannelInverseLUT | None:
    """The per-channel inverse tables of ``display`` (built once per model object), or
    None when the model is not separable per channel."""
    try:
        return _INVERSE_LUTS[display]
    except KeyError:
        lut = channel_inverse_lut(display) if is_channel_separable(display) else None
        _INVERSE_LUTS[display] = lut
        return lut


def _illuminant_sd(illuminant) -> tuple[colour.SpectralDistribution, str]:
    if isinstance(illuminant, colour.SpectralDistribution):
        return illuminant, str(illuminant.name)
    sd = getattr(illuminant, "sd", None)
    if isinstance(sd, colour.SpectralDistribution):
        return sd, str(getattr(illuminant, "id", sd.name))
    raise InputError(f"illuminant must be a library Illuminant or a colour.SpectralDistribution, "
                     f"not {type(illuminant).__name__}")


@dataclass(frozen=True, eq=False)
class RelightPlan:
    """What a lighting change computes before the per-texel kernel runs.

    Attributes
    ----------
    source : str
        The illuminant's id (or name).
    basis : SpectralBasis
        The basis the coefficients were encoded with.
    XYZ_matrix : ndarray (K, 3)
        Basis × source weights: ``XYZ_t ≈ XYZ_offset + c @ XYZ_matrix``.
    XYZ_offset : ndarray (3,)
    light : LightColour
        The engine light colour (level 1 of the same source).
    display : DisplayModel
    texel_table : ndarray (3, 256), uint8
        Level-2 texel per integer ``DAC_t``, per channel, for this light.
    unreachable_dac : ndarray (3,), int32
        Per channel, the integer ``DAC_t`` from which the light cannot carry
        the texel (albedo clipped at 1, or a channel the light does not have;
        256: none): a texel is unreachable when any channel reaches it
        (:func:`~workbench.hyperspectral.level2_texels.level2_unreachable_dac`).
    inverse_lut : ChannelInverseLUT or None
        The display inverse as tables (None: the model is not separable).
    drive_matrix, drive_offset : ndarray (K, 3) and (3,), float32, or None
        ``XYZ_matrix``/``XYZ_offset`` folded with the display's XYZ → drive map.
    """

    source: str
    basis: SpectralBasis
    XYZ_matrix: np.ndarray
    XYZ_offset: np.ndarray
    light: LightColour
    display: DisplayModel
    texel_table: np.ndarray
    unreachable_dac: np.ndarray
    inverse_lut: ChannelInverseLUT | None
    drive_matrix: np.ndarray | None
    drive_offset: np.ndarray | None


@dataclass(frozen=True, eq=False)
class RelitTexture:
    """Level-2 texels of a texture under one source, and how many the light cannot carry.

    Attributes
    ----------
    texels : ndarray (H, W, 3), uint8
        The texture to upload.
    unreachable : int
        Texels whose ``DAC_t`` the engine cannot reach under this light: an
        albedo above 1 (clipped) or a channel the light does not have (design
        §2; :func:`workbench.colour_management.level2_albedo8`).
    source : str
    """

    texels: np.ndarray
    unreachable: int
    source: str

    @property
    def unreachable_fraction(self) -> float:
        """``unreachable`` over the number of texels."""
        count = self.texels.shape[0] * self.texels.shape[1]
        return self.unreachable / count if count else 0.0


def _light_from_weights(weights: np.ndarray, display: DisplayModel) -> LightColour:
    """The level-1 light colour from band weights: the perfect diffuser's ``XYZ_t`` is the
    sum of the weights over the bands."""
    return light_colour_from_XYZ(weights.sum(axis=0), display)


def plan_relight(basis: SpectralBasis, illuminant, display: DisplayModel | None = None, *,
                 k: float = DEFAULT_K, weights: np.ndarray | None = None) -> RelightPlan:
    """Rebuild the K × 3 matrix and the light's tables for ``illuminant`` on ``display``.

    Parameters
    ----------
    basis : SpectralBasis
    illuminant : Illuminant or colour.SpectralDistribution
    display : DisplayModel, optional
        Default: the ideal sRGB display.
    k : float
        Scene-white factor.
    weights : ndarray (B, 3), optional
        The source's band weights on this display's scale
        (:func:`~workbench.hyperspectral.resampling.XYZ_band_weights` with
        ``Y_white`` = the display white's Y), when already known: the
        colour-science integration is then skipped (a runtime keeps them per
        source).
    """
    display = display or SRGBDisplay()
    sd, name = _illuminant_sd(illuminant)
    if weights is None:
        weights = XYZ_band_weights(sd, basis.wavelengths, basis.observer, k=k,
                                   Y_white=float(display.white_XYZ[1]))
    weights = np.asarray(weights, dtype=np.float64)
    if weights.shape != (basis.wavelengths.size, 3):
        raise InputError(f"source weights have shape {weights.shape}; the basis needs "
                         f"({basis.wavelengths.size}, 3)")
    XYZ_matrix, XYZ_offset = basis.XYZ_matrix(weights)
    light = _light_from_weights(weights, display)
    lut = display_inverse_lut(display)
    drive_matrix = drive_offset = None
    if lut is not None:
        drive_matrix = np.ascontiguousarray((XYZ_matrix @ lut.XYZ_to_drive).astype(np.float32))
        drive_offset = (XYZ_offset @ lut.XYZ_to_drive + lut.drive_offset).astype(np.float32)
    return RelightPlan(source=name, basis=basis, XYZ_matrix=XYZ_matrix, XYZ_offset=XYZ_offset,
                       light=light, display=display, texel_table=level2_texel_table(light.linear),
                       unreachable_dac=level2_unreachable_dac(light.linear),
                       inverse_lut=lut, drive_matrix=drive_matrix, drive_offset=drive_offset)


_DAC_CELLS: "weakref.WeakKeyDictionary[ChannelInverseLUT, DacCells | None]" = \
    weakref.WeakKeyDictionary()


def _dac_cells(lut: ChannelInverseLUT) -> DacCells | None:
    """The inverse's thresholds as the compiled kernel's cells (built once per table)."""
    try:
        return _DAC_CELLS[lut]
    except KeyError:
        cells = dac_cells(lut.thresholds[:, 1:256])
        _DAC_CELLS[lut] = cells
        return cells


def _relight_numba(planes: np.ndarray, plan: RelightPlan, out: np.ndarray) -> int:
    if plan.inverse_lut is None:
        raise InputError(f"kernel 'numba' needs a display separable per channel; "
                         f"{plan.display.describe()!r} is not: use kernel 'numpy'")
    cells = _dac_cells(plan.inverse_lut)
    if cells is None:   # two DAC levels closer than the cells resolve: the model's own inverse
        return _relight_numpy(planes, plan, out)
    from workbench.hyperspectral.relight_numba import relight_level2_planes_numba

    return relight_level2_planes_numba(planes, plan.drive_matrix, plan.drive_offset,
                                       cells.texel_cells(plan.texel_table),
                                       cells.reach_limits(plan.unreachable_dac), out)


def _relight_numpy(planes: np.ndarray, plan: RelightPlan, out: np.ndarray) -> int:
    return relight_level2_planes_numpy(planes, plan.XYZ_matrix, plan.XYZ_offset, plan.display,
                                       plan.texel_table, plan.unreachable_dac, out)


RELIGHT_KERNELS: dict[str, Callable[[np.ndarray, RelightPlan, np.ndarray], int]] = {
    "numba": _relight_numba,
    "numpy": _relight_numpy,
}
"""Per-texel level-2 kernels: name → ``kernel(planes (K, N) float16, plan, out (N, 3) uint8)``,
which writes ``out`` and returns the number of unreachable texels
(:attr:`RelightPlan.unreachable_dac`)."""


def relight_texels(texture: BasisCube, plan: RelightPlan, *, kernel: str = "auto",
                   out: np.ndarray | None = None) -> np.ndarray:
    """Level-2 texels ``(H, W, 3)`` uint8 of a compressed cube under ``plan``'s source.

    :attr:`RelitTexture.texels` of :func:`relight_level2` (same parameters),
    which also counts the texels the light cannot carry.
    """
    return relight_level2(texture, plan, kernel=kernel, out=out).texels


def relight_level2(texture: BasisCube, plan: RelightPlan, *, kernel: str = "auto",
                   out: np.ndarray | None = None) -> RelitTexture:
    """Level-2 texels of a compressed cube under ``plan``'s source, with the unreachable count.

    Parameters
    ----------
    texture : BasisCube
        float16 coefficient planes.
    plan : RelightPlan
        From :func:`plan_relight` with the same basis.
    kernel : str
        A key of :data:`RELIGHT_KERNELS`, or ``"auto"``: ``"numba"`` when the
        display is separable per channel, else ``"numpy"``.
    out : ndarray (H, W, 3), uint8, optional
        Reused output buffer (a runtime relights into the same texture).

    Returns
    -------
    RelitTexture
        ``texels`` (``out`` when given) and the number of texels the light
        cannot carry, counted in the kernel from :attr:`RelightPlan.unreachable_dac`.
    """
    if plan.basis is not texture.basis:
        raise InputError("the relight plan was built for another basis than the texture's; "
                         "plan with texture.basis")
    if kernel == "auto":
        kernel = "numba" if plan.inverse_lut is not None else "numpy"
    try:
        run = RELIGHT_KERNELS[kernel]
    except KeyError:
        raise InputError(f"unknown relight kernel {kernel!r}; use one of "
                         f"{sorted(RELIGHT_KERNELS)} or 'auto'") from None
    K, height, width = texture.coefficients.shape
    shape = (height, width, 3)
    if out is None:
        out = np.empty(shape, dtype=np.uint8)
    elif out.shape != shape or out.dtype != np.uint8 or not out.flags.c_contiguous:
        raise InputError(f"out must be a C-contiguous uint8 array of shape {shape}")
    planes = np.ascontiguousarray(texture.coefficients).reshape(K, height * width)
    unreachable = run(planes, plan, out.reshape(height * width, 3))
    return RelitTexture(texels=out, unreachable=int(unreachable), source=plan.source)


def relight_full_band(cube: ReflectanceCube, illuminant, display: DisplayModel | None = None, *,
                      k: float = DEFAULT_K, observer: str | None = None,
                      weights: np.ndarray | None = None) -> np.ndarray:
    """Reference level-2 texels ``(H, W, 3)`` uint8 from every band of ``cube``.

    :attr:`RelitTexture.texels` of :func:`relight_level2_full_band` (same
    parameters), which also counts the texels the light cannot carry.
    """
    return relight_level2_full_band(cube, illuminant, display, k=k, observer=observer,
                                    weights=weights).texels


def relight_level2_full_band(cube: ReflectanceCube, illuminant,
                             display: DisplayModel | None = None, *, k: float = DEFAULT_K,
                             observer: str | None = None,
                             weights: np.ndarray | None = None) -> RelitTexture:
    """Reference level-2 texels from every band of ``cube``, with the unreachable count.

    ``XYZ_t = ρ @ W`` as one ``(N, B) @ (B, 3)`` float32 product (design §8),
    then the display model's inverse, rounding and the level-2 texel
    arithmetic (:func:`workbench.colour_management.level2_albedo8`) — the
    naive path the basis kernel is checked and timed against. ``weights``
    (B × 3, on the display's scale) skip the colour-science integration when
    already known, as in :func:`plan_relight`.
    """
    display = display or SRGBDisplay()
    observer = observer or DEFAULT_OBSERVER
    sd, name = _illuminant_sd(illuminant)
    if weights is None:
        weights = XYZ_band_weights(sd, cube.wavelengths, observer, k=k,
                                   Y_white=float(display.white_XYZ[1]))
    weights = np.asarray(weights, dtype=np.float64)
    if weights.shape != (cube.bands, 3):
        raise InputError(f"source weights have shape {weights.shape}; the cube needs "
                         f"({cube.bands}, 3)")
    XYZ = cube.texels() @ weights.astype(np.float32)
    light = _light_from_weights(weights, display)
    dac = quantize_dac(display.inverse(XYZ))
    texels, unreachable = level2_albedo8(dac, light.linear)
    return RelitTexture(texels=texels.astype(np.uint8).reshape(cube.height, cube.width, 3),
                        unreachable=int(np.count_nonzero(unreachable)), source=name)


def authored_srgb8_cube(cube: ReflectanceCube) -> np.ndarray:
    """Level-1 texture: each texel's 8-bit sRGB under CIE D65 (``(H, W, 3)`` uint8).

    As :func:`workbench.colour_management.authored_srgb8`: XYZ under D65 with
    the perfect diffuser at Y = 100 (k = 1), ideal sRGB display, clipped to its
    gamut — the texture as a perfect scan authors it.
    """
    weights = XYZ_band_weights(colour.SDS_ILLUMINANTS["D65"], cube.wavelengths, k=1.0,
                               Y_white=100.0).astype(np.float32)
    XYZ = cube.texels() @ weights
    rgb8 = SRGBDisplay().inverse_rgb8(XYZ).astype(np.uint8)
    return rgb8.reshape(cube.height, cube.width, 3)
