"""Spectral basis for real-time level 2: PCA weighted by illuminant × colour-matching functions.

A texel's reflectance ``ρ`` (B bands) is stored as K coefficients
``c = (ρ − μ) P`` in float16 and relit as ``XYZ_t ≈ μ W + c (V W)``, where
``W`` (B × 3) are the relative-colorimetry weights of a source
(:func:`workbench.hyperspectral.resampling.XYZ_band_weights`): a lighting
change rebuilds the K × 3 matrix ``V W`` and the texel costs one K-vector
product (design §2, level 2).

Method
------
The error that matters is colorimetric, under the sources the texture will be
lit by: ``Σ_s ‖(ρ − ρ̂) W_s‖²`` = ``‖(ρ − ρ̂) G‖²`` with the metric
``G Gᵀ = Q = Σ_s Ŵ_s Ŵ_sᵀ`` (``Ŵ_s``: the weights of source ``s`` scaled so
that a perfect white has ``Y = 1``, so every source counts alike). PCA of the
training reflectances in that metric (a generalized, non-diagonal weighting
by illuminant × colour-matching functions) gives the K directions that carry
most of the tristimulus variance under all the sources at once. ``Q`` has rank
3 × (number of sources); a ridge ``ε · tr(Q)/B · I`` keeps the basis a
reflectance basis (usable under a source outside the set, and invertible).
With ``S = Q^{1/2}`` and the SVD ``(X − μ) S = U Σ Vᵀ``:
``P = S V_K`` (B × K) and the reconstruction basis is ``V_Kᵀ S⁻¹`` (K × B),
so that encoding then decoding is the identity on the kept subspace. Each
component is scaled so that its training coefficients have unit RMS (float16
keeps 11 significant bits at any scale, this only keeps them away from its
subnormal range).

K is the smallest number of components whose float16 coefficients reproduce
the full-band ``XYZ_t`` of *held-out* reflectances (not used in the fit)
within ``target_max_dE00`` CIEDE2000 under every source of the set (CIELAB
white: the perfect diffuser under each source, design §2).

References
----------
Díaz-Barrancas, F. et al. (2020), Spectral Color Management in Virtual Reality
Scenes, Sensors 20(19) 5658, §2.3. Maloney, L. T. (1986), Evaluation of linear
models of surface spectral reflectance with small numbers of parameters, JOSA A
3(10) 1673–1683. Tzeng, D.-Y., Berns, R. S. (2005), A review of principal
component analysis and its applications to color technology, Color Res. Appl.
30(2) 84–98 (weighted PCA). Sharma, G., Wu, W., Dalal, E. N. (2005), The CIEDE2000
color-difference formula, Color Res. Appl. 30(1) 21–30.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER, delta_E2000
from workbench.errors import InputError
from workbench.hyperspectral.cube import ReflectanceCube, check_cube_wavelengths
from workbench.hyperspectral.resampling import XYZ_band_weights

__all__ = [
    "BASIS_SOURCES",
    "ACCURACY_SOURCES",
    "DEFAULT_TARGET_MAX_DE00",
    "DEFAULT_RIDGE",
    "MAX_COMPONENTS",
    "MIN_SPLIT_SAMPLES",
    "BasisAccuracy",
    "SpectralBasis",
    "BasisCube",
    "source_band_weights",
    "fit_spectral_basis",
    "fit_cube_basis",
    "basis_accuracy",
    "encode_cube",
    "split_held_out",
]

LOGGER = logging.getLogger(__name__)

BASIS_SOURCES = ("cie-d65", "d65-simulator", "d65-two-peak", "cie-d50", "cie-a", "cie-fl11")
"""Default weighting sources: the paper's four (Tables 3–4) plus CIE A and FL11."""

ACCURACY_SOURCES = ("cie-d65", "cie-a", "cie-fl11", "d65-two-peak")
"""The sources the accuracy goal (max ΔE00 ≤ 0.5 vs the full band) is stated for."""

DEFAULT_TARGET_MAX_DE00 = 0.25
"""Default accuracy target: max CIEDE2000 vs the full-band path on held-out reflectances.

Half the goal of 0.5, a margin for texels the selection never saw. Texel-exact
agreement with the full-band path needs more: where a light channel is dim,
level 2 divides by it, so one count of ``DAC_t`` becomes several texel counts
(under CIE A on sRGB, blue); ≥ 99 % of texels within one count under CIE A
takes a target near 0.1 (two or three more components).
"""

DEFAULT_RIDGE = 1e-3
"""Ridge of the colorimetric metric, relative to its mean eigenvalue (module doc)."""

MAX_COMPONENTS = 24
"""Largest K tried when choosing K by accuracy."""

_ENCODE_ROWS = 32


def source_band_weights(sources: Sequence[str], wavelengths, observer: str = DEFAULT_OBSERVER,
                        *, k: float = DEFAULT_K) -> dict[str, np.ndarray]:
    """Relative-colorimetry weights ``(B, 3)`` of library sources at ``wavelengths`` (Y_white = 100)."""
    from workbench.illuminants import get_illuminant

    return {source: XYZ_band_weights(get_illuminant(source).sd, wavelengths, observer, k=k)
            for source in sources}


@dataclass(frozen=True)
class BasisAccuracy:
    """CIEDE2000 of the basis path against the full-band path, per source.

    ``max_dE00``/``mean_dE00`` map source id → figure over ``samples``
    reflectances, using float16 coefficients as the texture stores them; the
    CIELAB white is ``XYZ_t`` of the perfect diffuser under each source.
    """

    max_dE00: Mapping[str, float]
    mean_dE00: Mapping[str, float]
    samples: int

    @property
    def worst_dE00(self) -> float:
        """The largest ΔE00 over all sources."""
        return max(self.max_dE00.values())

    def to_json(self) -> dict:
        return {"max_dE00": dict(self.max_dE00), "mean_dE00": dict(self.mean_dE00),
                "samples": self.samples}


@dataclass(frozen=True, eq=False)
class SpectralBasis:
    """A colorimetrically weighted PCA basis (module doc).

    Attributes
    ----------
    wavelengths : ndarray (B,)
        Band centres (nm) the basis is sampled at (the cube's).
    mean : ndarray (B,)
        Mean reflectance ``μ`` of the training set.
    vectors : ndarray (K, B)
        Reconstruction basis: ``ρ̂ = μ + c @ vectors``.
    projection : ndarray (B, K)
        Encoder: ``c = (ρ − μ) @ projection``; ``vectors @ projection = I``.
    sources : tuple of str
        Library ids of the weighting sources.
    observer : str
    held_out : BasisAccuracy
        Accuracy on the held-out reflectances K was chosen on.
    target_max_dE00 : float
        The accuracy target K was chosen for (NaN when K was imposed).
    """

    wavelengths: np.ndarray
    mean: np.ndarray
    vectors: np.ndarray
    projection: np.ndarray
    sources: tuple[str, ...]
    observer: str
    held_out: BasisAccuracy
    target_max_dE00: float

    def __post_init__(self):
        K, B = np.shape(self.vectors)
        if np.shape(self.projection) != (B, K) or np.shape(self.mean) != (B,) or \
                np.shape(self.wavelengths) != (B,):
            raise InputError(f"spectral basis: inconsistent shapes (vectors {np.shape(self.vectors)}, "
                             f"projection {np.shape(self.projection)}, mean {np.shape(self.mean)}, "
                             f"wavelengths {np.shape(self.wavelengths)})")

    @property
    def components(self) -> int:
        """K, the number of coefficients per texel."""
        return self.vectors.shape[0]

    @property
    def meets_target(self) -> bool:
        """Whether the held-out accuracy meets the target (True when K was imposed)."""
        return bool(np.isnan(self.target_max_dE00)
                    or self.held_out.worst_dE00 <= self.target_max_dE00)

    def coefficients(self, reflectances) -> np.ndarray:
        """float16 coefficients ``(..., K)`` of reflectances ``(..., B)`` at :attr:`wavelengths`."""
        values = np.asarray(reflectances, dtype=np.float64)
        if values.shape[-1] != self.wavelengths.size:
            raise InputError(f"reflectances have {values.shape[-1]} bands; the basis has "
                             f"{self.wavelengths.size}")
        return ((values - self.mean) @ self.projection).astype(np.float16)

    def reconstruct(self, coefficients) -> np.ndarray:
        """Reflectances ``(..., B)`` from coefficients ``(..., K)``."""
        return self.mean + np.asarray(coefficients, dtype=np.float64) @ self.vectors

    def XYZ_matrix(self, weights) -> tuple[np.ndarray, np.ndarray]:
        """The K × 3 relighting matrix ``V W`` and offset ``μ W`` for band weights ``W`` (B × 3).

        ``XYZ_t ≈ offset + c @ matrix`` for float coefficients ``c``.
        """
        weights = np.asarray(weights, dtype=np.float64)
        return self.vectors @ weights, self.mean @ weights


@dataclass(frozen=True, eq=False)
class BasisCube:
    """A cube compressed to a spectral basis: what a level-2 texture keeps in memory.

    Attributes
    ----------
    coefficients : ndarray (K, H, W), float16
        Coefficient planes (like K/4 RGBA half-float textures on a GPU).
    basis : SpectralBasis
    source : str
    """

    coefficients: np.ndarray
    basis: SpectralBasis
    source: str

    @property
    def height(self) -> int:
        return self.coefficients.shape[1]

    @property
    def width(self) -> int:
        return self.coefficients.shape[2]


MIN_SPLIT_SAMPLES = 5
"""Fewest samples :func:`split_held_out` splits (so that both sides keep some)."""


def split_held_out(count: int, held_out_fraction: float = 0.2, *, seed: int = 0
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Disjoint (training, held-out) index arrays for ``count`` samples.

    Raises
    ------
    InputError
        Fewer than :data:`MIN_SPLIT_SAMPLES` samples: nothing can be held out
        and still leave a training set, so there is no held-out figure to give.
    """
    if count < MIN_SPLIT_SAMPLES:
        raise InputError(f"{count} reflectance(s) cannot be split into a training and a held-out "
                         f"set; give at least {MIN_SPLIT_SAMPLES} (a larger cube or more "
                         "reflectances), or pass held-out reflectances of their own")
    order = np.random.default_rng(seed).permutation(count)
    held = max(1, int(round(count * held_out_fraction)))
    return order[held:], order[:held]


def _metric_roots(weights: Mapping[str, np.ndarray], ridge: float) -> tuple[np.ndarray, np.ndarray]:
    bands = next(iter(weights.values())).shape[0]
    Q = np.zeros((bands, bands))
    for W in weights.values():
        W_hat = W / W[:, 1].sum()
        Q += W_hat @ W_hat.T
    Q += ridge * np.trace(Q) / bands * np.eye(bands)
    eigenvalues, eigenvectors = np.linalg.eigh(Q)
    eigenvalues = np.maximum(eigenvalues, eigenvalues.max() * 1e-15)
    root = (eigenvectors * np.sqrt(eigenvalues)) @ eigenvectors.T
    inverse_root = (eigenvectors / np.sqrt(eigenvalues)) @ eigenvectors.T
    return root, inverse_root


def _accuracy(coefficients16: np.ndarray, reflectances: np.ndarray, vectors: np.ndarray,
              mean: np.ndarray, weights: Mapping[str, np.ndarray]) -> BasisAccuracy:
    coefficients = coefficients16.astype(np.float64)
    max_dE, mean_dE = {}, {}
    for source, W in weights.items():
        full = reflectances @ W
        approx = mean @ W + coefficients @ (vectors @ W)
        dE = delta_E2000(approx, full, W.sum(axis=0))
        max_dE[source], mean_dE[source] = float(np.max(dE)), float(np.mean(dE))
    return BasisAccuracy(MappingProxyType(max_dE), MappingProxyType(mean_dE), len(reflectances))


def _as_training(values, wavelengths, what: str) -> np.ndarray:
    values = np.asarray(values, dtype=np.float64)
    if values.ndim == 3:
        values = values.reshape(-1, values.shape[-1])
    if values.ndim != 2 or values.shape[1] != wavelengths.size or len(values) == 0:
        raise InputError(f"{what} must be (N, {wavelengths.size}) reflectances at the basis "
                         f"wavelengths; got shape {values.shape}")
    if not np.all(np.isfinite(values)):
        raise InputError(f"{what} hold NaN or infinite values; remove those texels")
    return values


def fit_spectral_basis(training, wavelengths, *, held_out=None, sources: Sequence[str] = BASIS_SOURCES,
                       components: int | None = None,
                       target_max_dE00: float = DEFAULT_TARGET_MAX_DE00,
                       max_components: int = MAX_COMPONENTS, ridge: float = DEFAULT_RIDGE,
                       observer: str = DEFAULT_OBSERVER, k: float = DEFAULT_K,
                       seed: int = 0, clip_components: bool = False) -> SpectralBasis:
    """Fit a colorimetrically weighted PCA basis and choose K by held-out accuracy (module doc).

    Parameters
    ----------
    training : array_like (N, B) or (H, W, B)
        Reflectances (0..1) the basis is fitted on.
    wavelengths : array_like (B,)
        Their band centres (nm), covering 400–700 nm.
    held_out : array_like (M, B), optional
        Reflectances K is chosen on, not used in the fit. Default: 20 % of
        ``training``, drawn at random (``seed``) and removed from the fit
        (:func:`split_held_out`: at least :data:`MIN_SPLIT_SAMPLES` needed).
    sources : sequence of str
        Library ids of the weighting sources (default :data:`BASIS_SOURCES`).
    components : int, optional
        Impose K instead of choosing it.
    target_max_dE00 : float
        Largest CIEDE2000 allowed between basis and full-band ``XYZ_t`` of the
        held-out reflectances, under every source.
    max_components : int
        Largest K tried; when none meets the target the most accurate K is
        kept (:attr:`SpectralBasis.meets_target` is then False, and a warning
        is logged).
    ridge : float
        Ridge of the metric (module doc).
    observer, k : as :mod:`workbench.colorimetry`.
    seed : int
        Seed of the held-out split.
    clip_components : bool
        With ``components``: keep at most as many as the training set supports
        (its numerical rank) instead of refusing more.

    Returns
    -------
    SpectralBasis
    """
    wavelengths = check_cube_wavelengths(wavelengths, None, "basis wavelengths")
    training = _as_training(training, wavelengths, "training reflectances")
    if held_out is None:
        train_index, held_index = split_held_out(len(training), seed=seed)
        training, held_out = training[train_index], training[held_index]
    else:
        held_out = _as_training(held_out, wavelengths, "held-out reflectances")
    if not sources:
        raise InputError("a spectral basis needs at least one weighting source")
    if not (ridge > 0 and np.isfinite(ridge)):
        raise InputError(f"ridge={ridge!r} must be positive (e.g. {DEFAULT_RIDGE})")
    weights = source_band_weights(tuple(sources), wavelengths, observer, k=k)
    root, inverse_root = _metric_roots(weights, ridge)
    mean = training.mean(axis=0)
    _, singular, right = np.linalg.svd((training - mean) @ root, full_matrices=False)
    # Keep the numerically meaningful components only (a small training set has rank < B).
    rank = max(1, int(np.sum(singular > singular[0] * 1e-9))) if singular[0] > 0 else 1
    right = right[:rank]
    projection = root @ right.T              # (B, r)
    vectors = right @ inverse_root           # (r, B)
    rms = np.sqrt(np.mean(((training - mean) @ projection) ** 2, axis=0))
    rms = np.where(rms > 0, rms, 1.0)
    projection, vectors = projection / rms, vectors * rms[:, None]
    available = projection.shape[1]
    held_coefficients = ((held_out - mean) @ projection).astype(np.float16)

    def accuracy(K: int) -> BasisAccuracy:
        return _accuracy(held_coefficients[:, :K], held_out, vectors[:K], mean, weights)

    if components is not None:
        if clip_components and components > available:
            components = available
        if not 1 <= components <= available:
            raise InputError(f"K={components} components: choose 1..{available} (the training set "
                             f"has {len(training)} reflectances of {wavelengths.size} bands)")
        chosen, result, target = components, accuracy(components), float("nan")
    else:
        if not target_max_dE00 > 0:
            raise InputError(f"target_max_dE00={target_max_dE00!r} must be positive")
        target = float(target_max_dE00)
        chosen, result = None, None
        for K in range(1, min(max_components, available) + 1):
            candidate = accuracy(K)
            if result is None or candidate.worst_dE00 < result.worst_dE00:
                chosen, result = K, candidate
            if candidate.worst_dE00 <= target:
                chosen, result = K, candidate
                break
        if result.worst_dE00 > target:
            LOGGER.warning("no basis of up to %d components meets max ΔE00 ≤ %g on the held-out "
                           "reflectances; keeping K=%d (max ΔE00 %.3g)", min(max_components, available),
                           target, chosen, result.worst_dE00)
    return SpectralBasis(wavelengths=wavelengths, mean=mean, vectors=vectors[:chosen],
                         projection=projection[:, :chosen], sources=tuple(sources),
                         observer=observer, held_out=result, target_max_dE00=target)


def basis_accuracy(basis: SpectralBasis, reflectances, sources: Sequence[str] | None = None, *,
                   k: float = DEFAULT_K) -> BasisAccuracy:
    """ΔE00 of ``basis`` against the full-band path on ``reflectances`` (N, B) under ``sources``.

    Default sources: the basis's own. Reflectances are at the basis wavelengths.
    """
    values = _as_training(reflectances, basis.wavelengths, "reflectances")
    weights = source_band_weights(tuple(sources or basis.sources), basis.wavelengths,
                                  basis.observer, k=k)
    return _accuracy(basis.coefficients(values), values, basis.vectors, basis.mean, weights)


def encode_cube(cube: ReflectanceCube, basis: SpectralBasis) -> BasisCube:
    """Compress ``cube`` to ``basis``: float16 coefficient planes ``(K, H, W)``.

    The cube must be sampled at the basis wavelengths (fit the basis on the
    cube, or resample the cube first). Works a few rows at a time in float32.
    """
    if not np.array_equal(cube.wavelengths, basis.wavelengths):
        raise InputError(f"{cube.source}: the cube's {cube.bands} bands are not the basis's "
                         f"{basis.wavelengths.size}; resample the cube to the basis wavelengths "
                         "or fit the basis on this cube")
    projection = basis.projection.astype(np.float32)
    offset = (basis.mean @ basis.projection).astype(np.float32)
    planes = np.empty((basis.components, cube.height, cube.width), dtype=np.float16)
    for start in range(0, cube.height, _ENCODE_ROWS):
        block = cube.data[start:start + _ENCODE_ROWS] @ projection - offset   # (rows, W, K)
        planes[:, start:start + block.shape[0]] = np.moveaxis(block, -1, 0)
    return BasisCube(planes, basis, cube.source)


def fit_cube_basis(cube: ReflectanceCube, *, components: int | None = None,
                   target_max_dE00: float = DEFAULT_TARGET_MAX_DE00,
                   sources: Sequence[str] = BASIS_SOURCES, observer: str = DEFAULT_OBSERVER,
                   k: float = DEFAULT_K, training_texels: int = 16384,
                   held_out_texels: int = 8192, seed: int = 0,
                   clip_components: bool = False) -> SpectralBasis:
    """A basis for ``cube``, fitted on a random sample of its texels, K chosen on others.

    Draws up to ``training_texels`` texels for the fit and up to
    ``held_out_texels`` *other* texels to choose K on (a fifth of the cube
    each way when it is small), then :func:`fit_spectral_basis`. A cube of
    fewer than :data:`MIN_SPLIT_SAMPLES` texels raises :class:`InputError`.
    ``clip_components`` as :func:`fit_spectral_basis`.
    """
    texels = cube.texels()
    count = len(texels)
    train_index, held_index = split_held_out(count, seed=seed)
    train_index, held_index = train_index[:training_texels], held_index[:held_out_texels]
    return fit_spectral_basis(texels[train_index], cube.wavelengths, held_out=texels[held_index],
                              sources=sources, components=components,
                              target_max_dE00=target_max_dE00, observer=observer, k=k,
                              clip_components=clip_components)
