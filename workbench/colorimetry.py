"""Colorimetry over colour-science: spectra, observers, relative colorimetry, CIEDE2000.

Scale (one, everywhere in the workbench)
----------------------------------------
- Wavelengths in nm; the working sampling is :data:`WORKING_SHAPE`, 380–780 nm
  at 1 nm (the CS-2000's range and resolution). Any other sampling is
  interpolated (Sprague / linear, as colour-science aligns) and, where the
  data stop short, extrapolated with the end values.
- Reflectance on 0..1.
- Tristimulus values absolute (``Y`` in cd/m²) or relative to a display white
  of ``Y = 100``; the functions here take the display white luminance
  ``Y_white`` explicitly and never rescale behind the caller's back.

Relative colorimetry (design §2): a source ``S`` is scaled so that a perfect
white diffuser under it has luminance ``k · Y_white``; a surface of reflectance
``ρ`` then has ``XYZ_t = k · Y_white · ∫ρ S x̄ dλ / ∫S ȳ dλ``. Every CIEDE2000
figure uses CIELAB whose reference white is ``XYZ_t`` of the perfect diffuser
under the same source.

All integration and colour-difference arithmetic is colour-science's
(:func:`colour.msds_to_XYZ`, :func:`colour.delta_E`); this module only fixes
the scale and validates inputs.
"""

from __future__ import annotations

from functools import lru_cache

import colour
import numpy as np

from workbench.errors import InputError

__all__ = [
    "WORKING_SHAPE",
    "WORKING_WAVELENGTHS",
    "DEFAULT_K",
    "OBSERVERS",
    "DEFAULT_OBSERVER",
    "observer_cmfs",
    "as_spectral_distribution",
    "as_reflectances",
    "XYZ_relative_weights",
    "reflectances_to_XYZ_relative",
    "white_XYZ_relative",
    "delta_E2000",
    "XYZ_to_Lab_relative",
]

WORKING_SHAPE = colour.SpectralShape(380, 780, 1)
"""Working spectral sampling: 380–780 nm at 1 nm (the CS-2000's)."""

WORKING_WAVELENGTHS = WORKING_SHAPE.wavelengths

DEFAULT_K = 0.85
"""Scene-white factor: a perfect diffuser has 85 % of the display white luminance (the paper's)."""

OBSERVERS = {
    "cie1931-2": "CIE 1931 2 Degree Standard Observer",
    "cie1964-10": "CIE 1964 10 Degree Standard Observer",
}
"""Observer choices: id → colour-science colour-matching functions name."""

DEFAULT_OBSERVER = "cie1931-2"


def _observer_name(observer: str) -> str:
    if observer in OBSERVERS:
        return OBSERVERS[observer]
    if observer in OBSERVERS.values():
        return observer
    raise InputError(f"unknown observer {observer!r}; use one of {sorted(OBSERVERS)}")


@lru_cache(maxsize=8)
def _cmfs(name: str, shape: tuple[float, float, float]) -> colour.MultiSpectralDistributions:
    return colour.MSDS_CMFS[name].copy().align(colour.SpectralShape(*shape))


def observer_cmfs(observer: str = DEFAULT_OBSERVER, shape: colour.SpectralShape = WORKING_SHAPE):
    """Colour-matching functions of ``observer`` (an id of :data:`OBSERVERS`) at ``shape``.

    Returns a fresh copy: callers may modify it.
    """
    return _cmfs(_observer_name(observer), (shape.start, shape.end, shape.interval)).copy()


def _check_values(values: np.ndarray, what: str, *, allow_negative: bool = False) -> None:
    if values.size == 0:
        raise InputError(f"{what} is empty; give at least one value")
    if not np.all(np.isfinite(values)):
        bad = int(np.argmax(~np.isfinite(values.reshape(-1))))
        raise InputError(f"{what} holds a NaN or infinite value (flat index {bad}); "
                         "remove or re-measure it")
    if not allow_negative and np.any(values < 0):
        raise InputError(f"{what} holds negative values (min {values.min():.4g}); "
                         "spectral power and reflectance cannot be negative")


def as_spectral_distribution(values, wavelengths=None, name: str = "spectrum",
                             shape: colour.SpectralShape = WORKING_SHAPE,
                             ) -> colour.SpectralDistribution:
    """A validated :class:`colour.SpectralDistribution` at ``shape``.

    Parameters
    ----------
    values : SpectralDistribution or array_like
        Spectral values (power or reflectance), non-negative and finite.
    wavelengths : array_like, optional
        Wavelengths (nm) of ``values`` when they are an array; strictly
        increasing, any sampling.
    """
    if isinstance(values, colour.SpectralDistribution):
        sd = values.copy()
    else:
        values = np.asarray(values, dtype=float)
        if wavelengths is None:
            raise InputError(f"{name}: wavelengths are needed with an array of values")
        wavelengths = np.asarray(wavelengths, dtype=float)
        if values.shape != wavelengths.shape:
            raise InputError(f"{name}: {values.size} values for {wavelengths.size} wavelengths; "
                             "give one value per wavelength")
        _check_values(wavelengths, f"{name} wavelengths", allow_negative=False)
        if np.any(np.diff(wavelengths) <= 0):
            raise InputError(f"{name}: wavelengths must be strictly increasing")
        sd = colour.SpectralDistribution(dict(zip(wavelengths, values)), name=name)
    _check_values(sd.values, name)
    if not sd.is_uniform():
        # Sprague needs uniform sampling; irregular measured data is interpolated linearly.
        sd.interpolator = colour.LinearInterpolator
    return sd.align(shape)


def as_reflectances(reflectances, wavelengths=None, what: str = "reflectances") -> np.ndarray:
    """Reflectances as an ``(N, W)`` array at :data:`WORKING_WAVELENGTHS`.

    ``reflectances`` is an ``(..., W)`` array sampled at ``wavelengths``
    (default: the working ones), a :class:`colour.SpectralDistribution` or a
    :class:`colour.MultiSpectralDistributions`.
    """
    if isinstance(reflectances, colour.MultiSpectralDistributions):
        msds = reflectances.copy().align(WORKING_SHAPE)
        values = msds.values.T
    elif isinstance(reflectances, colour.SpectralDistribution):
        values = reflectances.copy().align(WORKING_SHAPE).values[None, :]
    else:
        values = np.asarray(reflectances, dtype=float)
        if values.size == 0:
            raise InputError(f"{what} is empty; give at least one reflectance spectrum")
        if values.ndim == 1:
            values = values[None, :]
        if wavelengths is not None and not np.array_equal(np.asarray(wavelengths, float),
                                                          WORKING_WAVELENGTHS):
            wavelengths = np.asarray(wavelengths, dtype=float)
            if values.shape[-1] != wavelengths.size:
                raise InputError(f"{what}: last axis has {values.shape[-1]} bands for "
                                 f"{wavelengths.size} wavelengths")
            flat = values.reshape(-1, values.shape[-1])
            values = np.stack([np.interp(WORKING_WAVELENGTHS, wavelengths, row) for row in flat])
        elif values.shape[-1] != WORKING_WAVELENGTHS.size:
            raise InputError(f"{what}: last axis has {values.shape[-1]} bands; the working "
                             f"sampling has {WORKING_WAVELENGTHS.size} (380–780 nm, 1 nm): "
                             "pass the wavelengths to resample")
    _check_values(values, what)
    return values.reshape(-1, WORKING_WAVELENGTHS.size)


def XYZ_relative_weights(illuminant, observer: str = DEFAULT_OBSERVER, *,
                         k: float = DEFAULT_K, Y_white: float = 100.0) -> np.ndarray:
    """Weights ``W`` (``(401, 3)``) such that ``XYZ_t = ρ @ W`` (design §2).

    ``W = k · Y_white · S x̄ / ∫S ȳ`` as colour-science integrates it
    (``method="Integration"``); a perfect diffuser gives ``Y = k · Y_white``.
    """
    _check_scale(k, Y_white)
    sd = as_spectral_distribution(illuminant, name=getattr(illuminant, "name", "illuminant"))
    # colour-science's integration applied to unit impulses: exactly the linear
    # map it uses, as a (W, 3) matrix, so that many reflectances (or a cube)
    # are integrated by one matrix product. ~4 ms.
    unit_impulses = np.eye(WORKING_WAVELENGTHS.size)
    weights = colour.msds_to_XYZ(unit_impulses, cmfs=observer_cmfs(observer), illuminant=sd,
                                 method="Integration", shape=WORKING_SHAPE) / 100.0
    return weights * (k * Y_white)


def _check_scale(k: float, Y_white: float) -> None:
    if not (np.isfinite(k) and 0 < k <= 1.5):
        raise InputError(f"scene-white factor k={k!r} must be in (0, 1.5]; the paper uses 0.85")
    if not (np.isfinite(Y_white) and Y_white > 0):
        raise InputError(f"display white luminance Y_white={Y_white!r} must be positive")


def reflectances_to_XYZ_relative(reflectances, illuminant, observer: str = DEFAULT_OBSERVER, *,
                                 k: float = DEFAULT_K, Y_white: float = 100.0,
                                 wavelengths=None) -> np.ndarray:
    """Target tristimulus values ``XYZ_t`` of surfaces under ``illuminant`` (design §2).

    Parameters
    ----------
    reflectances : array_like (..., W), SpectralDistribution or MultiSpectralDistributions
        Reflectance on 0..1.
    illuminant : SpectralDistribution
        The source; its absolute scale does not matter.
    observer : str
        ``"cie1931-2"`` (default) or ``"cie1964-10"``.
    k, Y_white : float
        Scene-white factor and display white luminance.

    Returns
    -------
    ndarray, shape (N, 3)
        ``XYZ_t = k · Y_white · ∫ρ S x̄ / ∫S ȳ``.
    """
    values = as_reflectances(reflectances, wavelengths)
    return values @ XYZ_relative_weights(illuminant, observer, k=k, Y_white=Y_white)


def white_XYZ_relative(illuminant, observer: str = DEFAULT_OBSERVER, *,
                       k: float = DEFAULT_K, Y_white: float = 100.0) -> np.ndarray:
    """``XYZ_t`` of the perfect diffuser (ρ = 1) under ``illuminant``: the reference white."""
    return XYZ_relative_weights(illuminant, observer, k=k, Y_white=Y_white).sum(axis=0)


def XYZ_to_Lab_relative(XYZ, XYZ_white) -> np.ndarray:
    """CIELAB of ``XYZ`` with reference white ``XYZ_white`` (both on the same absolute scale)."""
    XYZ = np.asarray(XYZ, dtype=float)
    XYZ_white = np.asarray(XYZ_white, dtype=float)
    _check_values(XYZ, "XYZ", allow_negative=True)
    _check_values(XYZ_white, "reference white XYZ")
    if XYZ_white[..., 1].min() <= 0:
        raise InputError("reference white has Y <= 0; a white must emit light")
    return colour.XYZ_to_Lab(XYZ / XYZ_white[..., 1:2], colour.XYZ_to_xy(XYZ_white))


def delta_E2000(XYZ_a, XYZ_b, XYZ_white) -> np.ndarray:
    """CIEDE2000 between ``XYZ_a`` and ``XYZ_b`` in CIELAB relative to ``XYZ_white``.

    The reference white is, by the workbench's convention, ``XYZ_t`` of the
    perfect diffuser under the source in question (design §2).

    References
    ----------
    CIE 142-2001, via :func:`colour.delta_E` (``method="CIE 2000"``).
    """
    Lab_a = XYZ_to_Lab_relative(XYZ_a, XYZ_white)
    Lab_b = XYZ_to_Lab_relative(XYZ_b, XYZ_white)
    return np.asarray(colour.delta_E(Lab_a, Lab_b, method="CIE 2000"))
