"""Level-2 files of a runtime bundle: basis coefficients, basis, per-light matrices and tables.

For a reflectance cube the bundle holds (in ``level2/<name>/``):

- ``coefficients.bin`` + ``coefficients.json``: the float16 coefficient
  *channels* as ``ceil(C/4)`` RGBA half-float texture layers, raw
  little-endian, layer by layer, rows top first, texels left to right, 4
  channels (channel ``4·layer + i``; padding channels 0). Channels 0..K−1 are
  the K basis coefficients rounded to float16; channels K..K+S−1 hold the
  float16 rounding error of the first S coefficients (a *precision split*:
  ``c ≈ hi + lo``, 22 significant bits where float16 alone keeps 11, which is
  what limits texel-exact agreement), so ``C = K + S``. The runtime needs no
  special case: a split channel's matrix row repeats its coefficient's row;
- ``basis.json``: wavelengths, mean and vectors (``ρ ≈ mean + c · vectors``),
  how K was chosen and the figures it was chosen on;
- ``lights.json``: per light the ``3 × C`` matrix and offset
  ``drive = matrix · channels + offset`` (source × colour-matching functions × basis,
  with the display inverse's linear part folded in), the light colour the
  texels assume, the level-2 texel table (3 × 256: texel for each integer
  ``DAC_t`` per channel, design §2) and the unreachable levels;
- ``preview.png``: the cube's authored sRGB under D65 (what it looks like).

The runtime then does per texel: ``drive`` → the bundle's display inverse
(:mod:`workbench.export.runtime_inverse`) → integer ``DAC_t`` → texel table.

K and S are chosen per cube (:func:`choose_cube_basis`, fewest channels C
first) so that this runtime arithmetic gives **the same 8-bit texel** as the
full-band level-2 path (:func:`workbench.hyperspectral.relight_level2_full_band`)
on at least ``target_share`` of held-out texels (texels the basis was not
fitted on) and ``probe_share`` of the library's materials and their mixtures
(:func:`probe_reflectances`: a cube's held-out texels mix the materials the
basis was fitted on, the probe guards against others), under every light of
the bundle.

The same method relights in the workbench (``relight``, ``bench relight``):
:func:`runtime_texture` holds a cube as the bundle would (its K + S float16
channels, chosen as above), :func:`relight_runtime_texture` relights it under
one light with the runtime's arithmetic (:func:`runtime_level2_texels`: NumPy
as the reference consumer, or the fused compiled kernel where the display
needs no correction table).

Scale: reflectance 0..1; drive 0..1; DAC and texels 8-bit integers.
"""

from __future__ import annotations

import json
import weakref
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np

from workbench.colour_management import light_colour_from_XYZ
from workbench.display import DisplayModel
from workbench.errors import InputError
from workbench.export.runtime_inverse import RuntimeDisplayInverse
from workbench.fileio import atomic_writer
from workbench.hyperspectral import (
    ReflectanceCube,
    RelitTexture,
    authored_srgb8_cube,
    fit_cube_basis,
    plan_relight,
    relight_level2_full_band,
    write_png_rgb8,
)
from workbench.hyperspectral.basis import SpectralBasis, split_held_out
from workbench.hyperspectral.channel_inverse import DacCells, dac_cells
from workbench.hyperspectral.level2_texels import level2_texel_table
from workbench.hyperspectral.resampling import XYZ_band_weights

__all__ = [
    "COEFFICIENTS_FORMAT",
    "DEFAULT_IDENTICAL_SHARE",
    "ComponentChoice",
    "Level2Light",
    "MAX_SPLIT",
    "MAX_BUNDLE_COMPONENTS",
    "DEFAULT_PROBE_SHARE",
    "RUNTIME_KERNELS",
    "RuntimeTexture",
    "probe_reflectances",
    "resolve_runtime_kernel",
    "level2_light",
    "encode_channels",
    "runtime_level2_texels",
    "runtime_texture",
    "relight_runtime_texture",
    "choose_cube_basis",
    "write_json",
    "write_level2_cube",
]

COEFFICIENTS_FORMAT = "vr-colour-workbench-level2-coefficients"

DEFAULT_IDENTICAL_SHARE = 0.999
"""Share of held-out texels whose runtime texel must equal the full band's (through the
runtime's inverse, under every light) when K is chosen: held-out texels of a cube mix the
materials the basis was fitted on, so the margin over the 99 % promised on materials the
basis never saw is wide (measured: ≥ 99.4 % on CIE TCS + NIST CQS chips for a basis
fitted on ColorChecker + CIE 2017 mixtures)."""

MAX_SPLIT = 6
"""Most coefficients given a second (precision) channel."""

MAX_BUNDLE_COMPONENTS = 32
"""Largest K tried for a bundle (with :data:`MAX_SPLIT`: at most 10 RGBA16F layers)."""

DEFAULT_PROBE_SHARE = 0.995
"""Share of the probe materials (:func:`probe_reflectances`) whose runtime texel must equal
the full band's when K is chosen."""

PROBE_MIXTURES = 2000
"""Random two-material mixtures added to the probe materials."""

_HELD_OUT_TEXELS = 8192


def probe_reflectances(wavelengths, *, mixtures: int = PROBE_MIXTURES, seed: int = 0
                       ) -> np.ndarray:
    """Every library material set (:data:`~workbench.hyperspectral.materials.MATERIAL_SETS`)
    and random two-material mixtures of them, at ``wavelengths``: ``(N, B)``.

    Texels held out of a cube mix the materials the basis was fitted on; these
    guard K against materials outside the cube (paints, chips, skin, foliage).
    """
    from workbench.hyperspectral.materials import MATERIAL_SETS, material_reflectances

    spectra = np.vstack([material_reflectances(name, wavelengths) for name in MATERIAL_SETS])
    rng = np.random.default_rng(seed)
    pairs = rng.integers(0, len(spectra), size=(mixtures, 2))
    weight = rng.uniform(0.0, 1.0, (mixtures, 1))
    mixed = weight * spectra[pairs[:, 0]] + (1 - weight) * spectra[pairs[:, 1]]
    return np.clip(np.vstack([spectra, mixed]), 0.0, 1.0).astype(np.float32)


def encode_channels(cube: ReflectanceCube, basis: SpectralBasis, split: int) -> np.ndarray:
    """float16 channels ``(K + split, H, W)``: the coefficients, then the float16 rounding
    error of the first ``split`` of them (module doc)."""
    if not 0 <= split <= basis.components:
        raise InputError(f"split={split}: between 0 and K={basis.components} coefficients")
    exact = np.moveaxis(cube.data @ basis.projection.astype(np.float32)
                        - (basis.mean @ basis.projection).astype(np.float32), -1, 0)
    high = exact.astype(np.float16)
    low = (exact[:split] - high[:split].astype(np.float32)).astype(np.float16)
    return np.concatenate([high, low], axis=0)


@dataclass(frozen=True, eq=False)
class Level2Light:
    """What the runtime needs for one light and one cube's basis.

    Attributes
    ----------
    id : str
    drive_matrix : ndarray (C, 3), float32
        ``drive = channels @ drive_matrix + drive_offset``.
    drive_offset : ndarray (3,), float32
    light_rgb8 : ndarray (3,) of int
        The engine light colour the texels assume.
    texel_table : ndarray (3, 256), uint8
    unreachable_dac : ndarray (3,), int
    """

    id: str
    drive_matrix: np.ndarray
    drive_offset: np.ndarray
    light_rgb8: np.ndarray
    texel_table: np.ndarray
    unreachable_dac: np.ndarray

    def to_json(self) -> dict:
        """Flat arrays (Unity's JsonUtility reads no nested arrays): ``matrix`` is the
        3 × C matrix row-major (row r, g, b of drive), ``texel_table`` 3 × 256 channel-major."""
        return {"id": self.id,
                "matrix": [float(v) for v in self.drive_matrix.T.reshape(-1)],
                "offset": [float(v) for v in self.drive_offset],
                "light_rgb8": [int(v) for v in self.light_rgb8],
                "texel_table": [int(v) for v in self.texel_table.reshape(-1)],
                "unreachable_dac": [int(v) for v in self.unreachable_dac]}


def level2_light(basis: SpectralBasis, illuminant, display: DisplayModel,
                 inverse: RuntimeDisplayInverse, *, k: float, split: int = 0,
                 weights: np.ndarray | None = None) -> Level2Light:
    """The per-light record: the basis relighting matrix folded with the inverse's linear part,
    one row per channel (a split channel repeats its coefficient's row). ``weights``: the
    source's band weights when already known (:func:`~workbench.hyperspectral.plan_relight`)."""
    plan = plan_relight(basis, illuminant, display, k=k, weights=weights)
    rows = list(range(basis.components)) + list(range(split))
    matrix = (plan.XYZ_matrix[rows] @ inverse.XYZ_to_drive).astype(np.float32)
    offset = (plan.XYZ_offset @ inverse.XYZ_to_drive + inverse.drive_offset).astype(np.float32)
    return Level2Light(id=plan.source, drive_matrix=matrix, drive_offset=offset,
                       light_rgb8=plan.light.rgb8, texel_table=plan.texel_table,
                       unreachable_dac=plan.unreachable_dac)


RUNTIME_KERNELS = ("numpy", "numba")
"""Implementations of the runtime's level-2 arithmetic (:func:`runtime_level2_texels`)."""

_CELLS: "weakref.WeakKeyDictionary[RuntimeDisplayInverse, DacCells | None]" = \
    weakref.WeakKeyDictionary()


def _compiled_cells(inverse: RuntimeDisplayInverse) -> DacCells | None:
    """The inverse's thresholds as the compiled kernel's cells; None where the kernel cannot
    run it (a correction table, or thresholds closer than its cells resolve)."""
    try:
        return _CELLS[inverse]
    except KeyError:
        cells = None if inverse.correction is not None else dac_cells(inverse.thresholds)
        _CELLS[inverse] = cells
        return cells


def resolve_runtime_kernel(inverse: RuntimeDisplayInverse, kernel: str = "auto") -> str:
    """The kernel :func:`runtime_level2_texels` runs for ``kernel`` (``"auto"`` resolved)."""
    if kernel not in (*RUNTIME_KERNELS, "auto"):
        raise InputError(f"unknown relight kernel {kernel!r}; use one of "
                         f"{', '.join(RUNTIME_KERNELS)} or auto")
    if kernel == "auto":
        return "numba" if _compiled_cells(inverse) is not None else "numpy"
    if kernel == "numba" and _compiled_cells(inverse) is None:
        raise InputError("kernel 'numba' runs a display inverse without a correction table "
                         f"({inverse.model} has one, or DAC levels too close for its cells); "
                         "use kernel 'numpy'")
    return kernel


def runtime_level2_texels(planes: np.ndarray, light: Level2Light,
                          inverse: RuntimeDisplayInverse, *, kernel: str = "numpy",
                          out: np.ndarray | None = None, threads: int | None = None
                          ) -> tuple[np.ndarray, int]:
    """The runtime's level-2 texels ``(N, 3)`` uint8 from float16 planes ``(C, N)`` and the
    number of texels the light cannot carry (float32 throughout, as a shader).

    ``kernel``: ``"numpy"`` computes as the reference consumer does;
    ``"numba"`` is the fused compiled kernel
    (:mod:`workbench.hyperspectral.relight_numba`: the same count of thresholds,
    the channel sum with fused multiply-adds in channel order, so a texel whose
    drive lies within float32 rounding of a threshold may differ), for an
    inverse without a correction table; ``"auto"``: ``"numba"`` where it can
    run, else ``"numpy"``. ``out`` (``(N, 3)`` uint8) receives the texels;
    ``threads`` as the compiled kernel's.
    """
    kernel = resolve_runtime_kernel(inverse, kernel)
    count = np.shape(planes)[1]
    if out is not None and (out.shape != (count, 3) or out.dtype != np.uint8
                            or not out.flags.c_contiguous):
        raise InputError(f"out must be a C-contiguous uint8 array of shape {(count, 3)}")
    if kernel == "numba":
        cells = _compiled_cells(inverse)
        from workbench.hyperspectral.relight_numba import relight_level2_planes_numba

        out = np.empty((count, 3), dtype=np.uint8) if out is None else out
        unreachable = relight_level2_planes_numba(
            np.ascontiguousarray(planes, dtype=np.float16), light.drive_matrix,
            light.drive_offset, cells.texel_cells(light.texel_table),
            cells.reach_limits(light.unreachable_dac), out, threads=threads)
        return out, unreachable
    coefficients = np.asarray(planes, dtype=np.float16).astype(np.float32)
    drive = coefficients.T @ light.drive_matrix + light.drive_offset
    dac = inverse.dac_from_affine_drive(drive)
    texels = light.texel_table[np.arange(3), dac]
    unreachable = int(np.count_nonzero(np.any(dac >= light.unreachable_dac, axis=-1)))
    if out is None:
        return texels.astype(np.uint8), unreachable
    out[...] = texels
    return out, unreachable


@dataclass(frozen=True)
class ComponentChoice:
    """How K and S were chosen for a cube, and the share of held-out texels the runtime gets right.

    Attributes
    ----------
    components, split : int
        K basis coefficients, S of them given a precision channel.
    identical : mapping
        Light id → share (0..1) of held-out texels whose runtime texel equals
        the full-band level-2 texel through the model's exact inverse (the
        acceptance figure: basis, float16 and the runtime inverse together).
    basis_identical : mapping
        Light id → the same share against the full band through the runtime's
        own inverse: what the basis and float16 alone cost (K is chosen on it,
        so that a correction table's interpolation error does not drive K).
    probe_identical : mapping
        Light id → the same share on the probe materials (:func:`probe_reflectances`),
        against the full band through the runtime's inverse.
    tried : mapping
        ``"K+S"`` → the smallest share over the lights, held-out texels and probe.
    """

    components: int
    split: int
    identical: MappingProxyType
    basis_identical: MappingProxyType
    probe_identical: MappingProxyType
    tried: MappingProxyType
    target_share: float
    probe_share: float
    held_out_texels: int

    @property
    def meets_target(self) -> bool:
        return (min(self.basis_identical.values()) >= self.target_share
                and min(self.probe_identical.values()) >= self.probe_share)

    def to_json(self) -> dict:
        return {"K": self.components, "split": self.split,
                "channels": self.components + self.split,
                "target_basis_identical_share": self.target_share,
                "target_probe_identical_share": self.probe_share,
                "held_out_texels": self.held_out_texels,
                "identical_share": {key: round(v, 5) for key, v in self.identical.items()},
                "basis_identical_share": {key: round(v, 5)
                                          for key, v in self.basis_identical.items()},
                "probe_identical_share": {key: round(v, 5)
                                          for key, v in self.probe_identical.items()},
                "tried": {key: round(v, 5) for key, v in self.tried.items()},
                "meets_target": self.meets_target,
                "criterion": "runtime 8-bit texel equal to the full-band level-2 texel on texels "
                             "the basis was not fitted on and on the library's materials, under "
                             "every light of the bundle; K+S chosen against the full band through "
                             "the runtime's inverse (basis_identical_share, "
                             "probe_identical_share), identical_share against the model's exact "
                             "inverse"}


def _largest_basis(cube: ReflectanceCube, components: int, **options) -> SpectralBasis:
    """The basis with the most components up to ``components`` the cube supports."""
    return fit_cube_basis(cube, components=components, clip_components=True, **options)


def _shares(runtime: np.ndarray, references: dict, light_id: str) -> float:
    return float(np.mean(np.all(runtime == references[light_id], axis=-1)))


def choose_cube_basis(cube: ReflectanceCube, display: DisplayModel, illuminants: Sequence,
                      inverse: RuntimeDisplayInverse, *, k: float, observer: str,
                      target_share: float = DEFAULT_IDENTICAL_SHARE,
                      probe_share: float = DEFAULT_PROBE_SHARE,
                      max_components: int = MAX_BUNDLE_COMPONENTS, seed: int = 0
                      ) -> tuple[SpectralBasis, ComponentChoice]:
    """The fewest channels ``K + S`` whose runtime texels equal the full band's on
    ≥ ``target_share`` of held-out texels and ≥ ``probe_share`` of the probe materials
    (:func:`probe_reflectances`) under every light (module doc; the full band through the
    runtime's own inverse, :class:`ComponentChoice`); the most accurate ``(K, S)`` tried
    otherwise (:attr:`ComponentChoice.meets_target` False)."""
    if not illuminants:
        raise InputError("choosing K needs at least one light (--lights)")
    texels = cube.texels()
    _, held_index = split_held_out(len(texels), seed=seed)   # the texels fit_cube_basis leaves out
    held = texels[held_index[:_HELD_OUT_TEXELS]]
    held_cube = ReflectanceCube(held.reshape(1, -1, cube.bands), cube.wavelengths,
                                f"held-out texels of {cube.source}")
    probe = probe_reflectances(cube.wavelengths, seed=seed)
    probe_cube = ReflectanceCube(probe.reshape(1, -1, cube.bands), cube.wavelengths,
                                 "probe materials")
    exact, through_runtime, probe_runtime, band_weights = {}, {}, {}, {}
    for illuminant in illuminants:
        weights = XYZ_band_weights(illuminant.sd, cube.wavelengths, observer, k=k,
                                   Y_white=float(display.white_XYZ[1]))
        band_weights[illuminant.id] = weights
        full = relight_level2_full_band(held_cube, illuminant, display, k=k, observer=observer,
                                        weights=weights)
        exact[full.source] = full.texels.reshape(-1, 3)
        # the light as the full band has it: the white diffuser's XYZ is the sum of the weights
        table = level2_texel_table(light_colour_from_XYZ(weights.sum(axis=0), display).linear)
        dac = inverse.dac(held @ weights.astype(np.float32))
        through_runtime[full.source] = table[np.arange(3), dac]
        probe_runtime[full.source] = table[np.arange(3),
                                           inverse.dac(probe @ weights.astype(np.float32))]
    start = fit_cube_basis(cube, observer=observer, k=k, seed=seed).components
    largest = _largest_basis(cube, max_components, observer=observer, k=k, seed=seed)
    tried, best, chosen = {}, None, None
    for K in range(min(start, largest.components), largest.components + 1):
        if chosen is not None and K >= chosen[0].components + chosen[1]:
            break  # no split can give fewer channels than the choice
        basis = replace(largest, vectors=largest.vectors[:K], projection=largest.projection[:, :K])
        held_channels = encode_channels(held_cube, basis, min(MAX_SPLIT, K)).reshape(-1, len(held))
        probe_channels = encode_channels(probe_cube, basis, min(MAX_SPLIT, K)).reshape(-1, len(probe))
        for split in range(0, min(MAX_SPLIT, K) + 1):
            rows = list(range(K)) + list(range(K, K + split))
            runtime, on_probe = {}, {}
            for illuminant in illuminants:
                light = level2_light(basis, illuminant, display, inverse, k=k, split=split,
                                     weights=band_weights[illuminant.id])
                runtime[light.id], _ = runtime_level2_texels(held_channels[rows], light, inverse)
                on_probe[light.id], _ = runtime_level2_texels(probe_channels[rows], light, inverse)
            shares = {key: _shares(value, through_runtime, key) for key, value in runtime.items()}
            probe_shares = {key: _shares(value, probe_runtime, key)
                            for key, value in on_probe.items()}
            candidate = (basis, split, shares,
                         {key: _shares(value, exact, key) for key, value in runtime.items()},
                         probe_shares)
            score = min(min(shares.values()) - target_share,
                        min(probe_shares.values()) - probe_share)
            tried[f"{K}+{split}"] = min(min(shares.values()), min(probe_shares.values()))
            if best is None or score > best[0]:
                best = (score, candidate)
            if score >= 0:
                if chosen is None or K + split < chosen[0].components + chosen[1]:
                    chosen = candidate
                break
    basis, split, shares, identical, probe_shares = chosen or best[1]
    # the same basis (a truncated SVD is the smaller fit), with its own held-out accuracy
    basis = fit_cube_basis(cube, components=basis.components, observer=observer, k=k, seed=seed)
    return basis, ComponentChoice(basis.components, split, MappingProxyType(identical),
                                  MappingProxyType(shares), MappingProxyType(probe_shares),
                                  MappingProxyType(tried), target_share, probe_share, len(held))


@dataclass(frozen=True, eq=False)
class RuntimeTexture:
    """A cube as the runtime holds it: the float16 channels of its level-2 files, in memory.

    Attributes
    ----------
    channels : ndarray (C, H, W), float16
        The K basis coefficients, then the float16 rounding error of the first
        S (:func:`encode_channels`).
    basis : SpectralBasis
    split : int
        S.
    choice : ComponentChoice or None
        How K and S were chosen (None: imposed).
    source : str
    """

    channels: np.ndarray
    basis: SpectralBasis
    split: int
    choice: ComponentChoice | None
    source: str

    @property
    def components(self) -> int:
        """K."""
        return self.basis.components

    @property
    def height(self) -> int:
        return self.channels.shape[1]

    @property
    def width(self) -> int:
        return self.channels.shape[2]

    @property
    def planes(self) -> np.ndarray:
        """The channels ``(C, H·W)``, texels row-major."""
        return self.channels.reshape(self.channels.shape[0], -1)


def runtime_texture(cube: ReflectanceCube, display: DisplayModel, illuminants: Sequence,
                    inverse: RuntimeDisplayInverse, *, k: float, observer: str,
                    components: int | None = None, split: int = 0,
                    target_share: float = DEFAULT_IDENTICAL_SHARE,
                    probe_share: float = DEFAULT_PROBE_SHARE, seed: int = 0) -> RuntimeTexture:
    """``cube`` as a bundle holds it: K + S chosen by :func:`choose_cube_basis` under
    ``illuminants`` (``components`` None), or K = ``components`` and S = ``split`` imposed.

    Raises
    ------
    InputError
        ``split`` outside 0..K, or coefficients beyond the float16 range (a basis with more
        components than the cube supports).
    """
    choice = None
    if components is None:
        basis, choice = choose_cube_basis(cube, display, illuminants, inverse, k=k,
                                          observer=observer, target_share=target_share,
                                          probe_share=probe_share, seed=seed)
        split = choice.split
    else:
        basis = fit_cube_basis(cube, components=components, observer=observer, k=k, seed=seed)
    with np.errstate(over="ignore"):
        channels = encode_channels(cube, basis, split)
    if not np.all(np.isfinite(channels)):
        raise InputError(f"{cube.source}: its K = {basis.components} basis coefficients exceed "
                         "the float16 range (a basis with more components than the cube "
                         "supports); choose fewer")
    return RuntimeTexture(np.ascontiguousarray(channels), basis, split, choice, cube.source)


def relight_runtime_texture(texture: RuntimeTexture, illuminant, display: DisplayModel,
                            inverse: RuntimeDisplayInverse, *, k: float, kernel: str = "auto",
                            out: np.ndarray | None = None, weights: np.ndarray | None = None,
                            threads: int | None = None) -> RelitTexture:
    """The level-2 texture of ``texture`` under ``illuminant`` as the runtime computes it:
    the light's record (:func:`level2_light`, the work of a lighting change) then the
    per-texel arithmetic (:func:`runtime_level2_texels`). ``out``: ``(H, W, 3)`` uint8
    reused; ``weights``: the source's band weights when known."""
    light = level2_light(texture.basis, illuminant, display, inverse, k=k, split=texture.split,
                         weights=weights)
    shape = (texture.height, texture.width, 3)
    if out is not None and (out.shape != shape or out.dtype != np.uint8
                            or not out.flags.c_contiguous):
        raise InputError(f"out must be a C-contiguous uint8 array of shape {shape}")
    texels, unreachable = runtime_level2_texels(
        texture.planes, light, inverse, kernel=kernel, threads=threads,
        out=None if out is None else out.reshape(-1, 3))
    return RelitTexture(texels=texels.reshape(shape), unreachable=int(unreachable),
                        source=light.id)


def write_json(path: Path, document: dict) -> None:
    """Write ``document`` as indented JSON, atomically (every JSON file of a bundle)."""
    with atomic_writer(path) as handle:
        json.dump(document, handle, indent=1)
        handle.write("\n")


def write_level2_cube(directory, name: str, cube: ReflectanceCube, basis: SpectralBasis,
                      split: int, lights: Sequence[Level2Light],
                      choice: ComponentChoice | None) -> dict:
    """Write one cube's level-2 files (module doc) into ``directory/level2/name``; the
    bundle manifest's entry for it."""
    folder = Path(directory) / "level2" / name
    folder.mkdir(parents=True, exist_ok=True)
    K = basis.components
    channels = K + split
    layers = -(-channels // 4)
    padded = np.zeros((layers * 4, cube.height, cube.width), dtype="<f2")
    with np.errstate(over="ignore"):
        padded[:channels] = encode_channels(cube, basis, split)
    if not np.all(np.isfinite(padded)):
        raise InputError(f"cube {name!r}: its K = {K} basis coefficients exceed the float16 "
                         "range (a basis with more components than the cube supports); the "
                         "runtime could not read them")
    rgba = np.ascontiguousarray(padded.reshape(layers, 4, cube.height, cube.width)
                                .transpose(0, 2, 3, 1))                 # (layers, H, W, 4)
    with atomic_writer(folder / "coefficients.bin", "wb") as handle:
        handle.write(rgba.tobytes())
    header = {"format": COEFFICIENTS_FORMAT, "format_version": 1, "file": "coefficients.bin",
              "width": cube.width, "height": cube.height, "components": K, "split": split,
              "channels": channels, "layers": layers,
              "channel_component": list(range(K)) + list(range(split)),
              "texture_format": "RGBA16F (Unity TextureFormat.RGBAHalf)",
              "dtype": "float16 little-endian", "bytes": int(rgba.nbytes),
              "layout": "[layer][row, top row first][column][RGBA]; channel i is layer i//4, "
                        "component i%4; channel_component[i] is the basis coefficient it holds "
                        "(channels K.. hold the float16 rounding error of the first coefficients); "
                        "padding channels are 0"}
    write_json(folder / "coefficients.json", header)
    write_json(folder / "basis.json", {
        "wavelengths": basis.wavelengths.tolist(), "mean": basis.mean.tolist(),
        "vectors": basis.vectors.tolist(), "observer": basis.observer,
        "sources": list(basis.sources), "components": K,
        "held_out_max_dE00": dict(basis.held_out.max_dE00),
        "choice": None if choice is None else choice.to_json(),
        "cube": cube.source})
    write_json(folder / "lights.json", {"components": K, "channels": channels, "layers": layers,
                                         "lights": [light.to_json() for light in lights]})
    write_png_rgb8(folder / "preview.png", authored_srgb8_cube(cube),
                   {"Description": f"authored sRGB under D65 of {cube.source}"})
    return {"name": name, "folder": f"level2/{name}", "width": cube.width, "height": cube.height,
            "components": K, "split": split, "channels": channels, "layers": layers, "source": cube.source,
            "choice": None if choice is None else choice.to_json()}
