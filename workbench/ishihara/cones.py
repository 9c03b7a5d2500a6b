"""Cone fundamentals of the simulated observers and the dichromats' copunctal points.

Two sets of cone fundamentals, chosen per observer
(:data:`workbench.ishihara.observers.OBSERVER_FUNDAMENTALS`):

Smith & Pokorny (1975) on CIE 1931 (the default)
    A linear transform of the CIE 1931 2° colour-matching functions, the
    observer every other figure of the workbench uses. Because
    ``LMS = T · XYZ`` exactly, two lights with the same CIE 1931 XYZ excite
    these cones identically — for the normal observer and for the anomalous
    ones too, since Machado et al.'s (2009) anomalous fundamentals are blends
    of L and M (still linear in XYZ). A dichromat's confusion line is
    a straight line in the CIE 1931 xy diagram through its copunctal point.
    With these fundamentals, any rendering that matches ``XYZ_t`` matches
    every simulated observer: they cannot reveal observer metamerism.
Stockman & Sharpe (2000) 2°
    Physiologically based fundamentals (the CIE 2006 "physiological"
    observer's LMS, CIE 170-1:2006), derived from the Stiles & Burch (1955)
    2° colour matches and *not* a linear transform of CIE 1931: fitting them
    by ``T · [x̄, ȳ, z̄]`` leaves residuals of ~2 % (L, M) and ~13 % (S) of
    their norm. Two lights that match in CIE 1931 XYZ, e.g. a reflectance
    under a lamp and an OLED's three narrow primaries, can differ for this
    observer. :func:`cone_fundamental_shifted_StockmanSharpe2000` moves the L
    or M photopigment along the wavelength axis (behind the lens and macular
    filters, which stay put) to make anomalous trichromats.

The copunctal points are *computed* from the Smith & Pokorny transform: the
protanope's is the chromaticity of the light that excites only the L cones
(M = S = 0), the deuteranope's only the M cones, the tritanope's only the S
cones. They come out as the published values
(protan 0.7465, 0.2535; deutan 1.40, −0.40; tritan 0.1748, 0.0), which is
checked by the tests.

Scale: fundamentals on the working wavelengths (380–780 nm, 1 nm), energy
based. Smith & Pokorny's as the transform gives them (``L + M = ȳ``); Stockman
& Sharpe's each normalised to a peak of 1 (as tabulated). Cone excitations are
linear in radiance and carry its unit; the simulated observers only use their
ratios, so the scale of each class does not matter.

References
----------
Smith, V. C., & Pokorny, J. (1975). Spectral sensitivity of the foveal cone
photopigments between 400 and 500 nm. *Vision Research*, 15(2), 161–171.

Stockman, A., & Sharpe, L. T. (2000). The spectral sensitivities of the
middle- and long-wavelength-sensitive cones derived from measurements in
observers of known genotype. *Vision Research*, 40(13), 1711–1737.

CIE 170-1:2006. *Fundamental Chromaticity Diagram with Physiological Axes —
Part 1*. Commission Internationale de l'Éclairage.

Govardovskii, V. I., Fyhrquist, N., Reuter, T., Kuzmin, D. G., & Donner, K.
(2000). In search of the visual pigment template. *Visual Neuroscience*,
17(4), 509–528.

Wyszecki, G., & Stiles, W. S. (1982). *Color Science*, 2nd ed., Wiley,
§5.14 (dichromats' confusion lines and copunctal points) and Table 2(8.2.5).

Viénot, F., Brettel, H., & Mollon, J. D. (1999). Digital video colourmaps for
checking the legibility of displays by dichromats. *Color Research &
Application*, 24(4), 243–252 (the same copunctal points, CIE 1931 xy).
"""

from __future__ import annotations

from functools import lru_cache

import colour
import numpy as np
from scipy.optimize import least_squares

from workbench.colorimetry import WORKING_WAVELENGTHS, observer_cmfs

__all__ = [
    "MATRIX_XYZ_TO_LMS_SMITH_POKORNY1975",
    "CONES",
    "COPUNCTAL_DEFICIENCIES",
    "cone_fundamentals_Smith_Pokorny1975",
    "STOCKMAN_SHARPE2000_NAME",
    "cone_fundamentals_StockmanSharpe2000",
    "PEAK_OPTICAL_DENSITY_LM_2DEG",
    "photopigment_absorbance_Govardovskii2000",
    "photopigment_peaks_StockmanSharpe2000",
    "cone_fundamental_shifted_StockmanSharpe2000",
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


STOCKMAN_SHARPE2000_NAME = "Stockman & Sharpe 2 Degree Cone Fundamentals"
"""colour-science's name of the Stockman & Sharpe (2000) 2° fundamentals (energy, 390–830 nm)."""

PEAK_OPTICAL_DENSITY_LM_2DEG = 0.5
"""Peak optical density of the L and M photopigments in a 2° field (CIE 170-1:2006)."""

_EXTRAPOLATION_SPAN_NM = 5.0
_ZERO_SENSITIVITY = 1e-30
_PEAK_FIT_RANGE_NM = (440.0, 680.0)


@lru_cache(maxsize=1)
def _StockmanSharpe2000() -> np.ndarray:
    cmfs = colour.MSDS_CMFS[STOCKMAN_SHARPE2000_NAME]
    wavelengths = np.asarray(cmfs.wavelengths, dtype=float)
    values = np.asarray(cmfs.values, dtype=float)
    first = wavelengths[0]
    near = wavelengths <= first + _EXTRAPOLATION_SPAN_NM
    if np.any(values[near] <= 0):
        raise ValueError(f"colour-science's {STOCKMAN_SHARPE2000_NAME!r} holds non-positive "
                         "values at its short-wavelength end; cannot extend them")
    logs = np.log10(np.maximum(values, _ZERO_SENSITIVITY))  # S is tabulated as 0 beyond 615 nm
    fundamentals = np.empty((WORKING_WAVELENGTHS.size, 3))
    for cone in range(3):
        # below the table (390 nm) the fundamentals fall exponentially under the lens: extend
        # log10 sensitivity on the straight line through the table's first 5 nm
        slope = (logs[near][-1, cone] - logs[0, cone]) / _EXTRAPOLATION_SPAN_NM
        below = logs[0, cone] + slope * (WORKING_WAVELENGTHS - first)
        inside = np.interp(WORKING_WAVELENGTHS, wavelengths, logs[:, cone])
        fundamentals[:, cone] = 10.0 ** np.where(WORKING_WAVELENGTHS < first, below, inside)
    fundamentals /= fundamentals.max(axis=0)
    fundamentals.setflags(write=False)
    return fundamentals


def cone_fundamentals_StockmanSharpe2000() -> np.ndarray:
    """Stockman & Sharpe (2000) 2° L, M, S cone fundamentals (401, 3) at the working wavelengths.

    Returns
    -------
    ndarray, shape (401, 3)
        Energy based, each normalised to a peak of 1 (L at 570 nm, M at 543 nm,
        S at 442 nm): colour-science's table from 390 nm, extended below it on
        the straight line of log10 sensitivity through 390–395 nm. A read-only
        array shared by every caller.

    Notes
    -----
    Not a linear transform of the CIE 1931 colour-matching functions (module
    notes): lights that match for CIE 1931 need not match for this observer.

    References
    ----------
    Stockman & Sharpe (2000); CIE 170-1:2006 (see the module).
    """
    return _StockmanSharpe2000()


def photopigment_absorbance_Govardovskii2000(wavelengths, lambda_max: float) -> np.ndarray:
    """Low-density absorbance spectrum of an A1 visual pigment peaking at ``lambda_max`` nm.

    Govardovskii et al.'s (2000) template: an α band (a function of
    ``λ_max / λ`` only, so the spectrum keeps its shape on a log-wavelength
    axis) plus a β band; 1 at the peak (quantal units).

    References
    ----------
    Govardovskii, V. I., Fyhrquist, N., Reuter, T., Kuzmin, D. G., & Donner, K.
    (2000). In search of the visual pigment template. *Visual Neuroscience*,
    17(4), 509–528.
    """
    lam = np.asarray(wavelengths, dtype=float)
    x = lambda_max / lam
    a = 0.8795 + 0.0459 * np.exp(-((lambda_max - 300.0) ** 2) / 11940.0)
    alpha = 1.0 / (np.exp(69.7 * (a - x)) + np.exp(28.0 * (0.922 - x))
                   + np.exp(-14.9 * (1.104 - x)) + 0.674)
    beta = 0.26 * np.exp(-(((lam - (189.0 + 0.315 * lambda_max))
                            / (-40.5 + 0.195 * lambda_max)) ** 2))
    return alpha + beta


def _absorptance(lambda_max: float) -> np.ndarray:
    """Fraction of the light a 2° L/M cone's pigment absorbs (self-screening at peak density)."""
    absorbance = photopigment_absorbance_Govardovskii2000(WORKING_WAVELENGTHS, lambda_max)
    return 1.0 - 10.0 ** (-PEAK_OPTICAL_DENSITY_LM_2DEG * absorbance)


@lru_cache(maxsize=1)
def _fitted_peaks() -> tuple:
    fundamentals = cone_fundamentals_StockmanSharpe2000()
    inside = (WORKING_WAVELENGTHS >= _PEAK_FIT_RANGE_NM[0]) & \
        (WORKING_WAVELENGTHS <= _PEAK_FIT_RANGE_NM[1])
    # the pre-receptoral filters are common to L and M: their ratio is the pigments' alone
    measured = np.log10(fundamentals[inside, 0] / fundamentals[inside, 1])

    def residuals(p):
        model = np.log10(_absorptance(p[0])[inside]) - np.log10(_absorptance(p[1])[inside])
        return measured - model - p[2]

    fit = least_squares(residuals, [558.0, 530.0, 0.0], x_scale=[10.0, 10.0, 0.1])
    rms = float(np.sqrt(np.mean(fit.fun ** 2)))
    return float(fit.x[0]), float(fit.x[1]), rms


def photopigment_peaks_StockmanSharpe2000() -> tuple:
    """λ_max (nm) of the L and M photopigments that the shift model places under these fundamentals.

    Returns
    -------
    (float, float, float)
        ``λ_max`` of L and of M, and the rms (log10 units) of the fit.

    Notes
    -----
    Fitted so that the ratio of the two pigments' absorptances (the
    :func:`photopigment_absorbance_Govardovskii2000` template at the 2° peak
    optical density :data:`PEAK_OPTICAL_DENSITY_LM_2DEG`) reproduces the ratio
    ``L/M`` of the tabulated fundamentals over 440–680 nm, in which the lens
    and macular filtering, common to both cones, cancels. About 553 and 524 nm,
    within 0.03 log units everywhere in that range; the template's shape
    differs slightly from Stockman & Sharpe's own, hence a few nm below their
    published photopigment peaks.
    """
    return _fitted_peaks()


@lru_cache(maxsize=64)
def _shifted_StockmanSharpe2000(cone: int, shift_nm: float) -> np.ndarray:
    lambda_max = photopigment_peaks_StockmanSharpe2000()[cone]
    shifted = (cone_fundamentals_StockmanSharpe2000()[:, cone]
               * _absorptance(lambda_max + shift_nm) / _absorptance(lambda_max))
    shifted /= shifted.max()
    shifted.setflags(write=False)
    return shifted


def cone_fundamental_shifted_StockmanSharpe2000(cone: int, shift_nm: float) -> np.ndarray:
    """The Stockman & Sharpe (2000) 2° L or M fundamental with its photopigment moved ``shift_nm``.

    Parameters
    ----------
    cone : int
        0 (L) or 1 (M).
    shift_nm : float
        Δλ of the photopigment's peak, nm (negative: towards short
        wavelengths); within ±40 nm.

    Returns
    -------
    ndarray, shape (401,)
        The anomalous fundamental at the working wavelengths, energy based,
        renormalised to a peak of 1.

    Notes
    -----
    A real shift along the wavelength axis, not a blend of two fundamentals
    (Machado et al. 2009 blend L and M, which keeps the observer linear in
    CIE XYZ). The corneal fundamental is the product of the pre-receptoral
    filters (lens, macular pigment) and the pigment's absorptance
    ``1 − 10^(−D·A(λ))``; only the pigment moves. So the fundamental is
    multiplied by ``α(λ; λ_max + Δλ) / α(λ; λ_max)``, the absorptances of the
    moved and of the original pigment (Govardovskii template, whose shape is
    kept on a log-wavelength axis; peak optical density ``D`` = 0.5; ``λ_max``
    from :func:`photopigment_peaks_StockmanSharpe2000`): the filters stay
    where they are and the self-screening is recomputed for the new pigment,
    as in CIE 170-1's construction, without needing the filters' density
    tables (they cancel in the ratio). Moving the L pigment onto the M one
    this way reproduces the tabulated M fundamental within 1.5 % of its peak
    (the M pigment onto the L one: within 5 %).

    References
    ----------
    Stockman & Sharpe (2000); CIE 170-1:2006; Govardovskii et al. (2000).
    """
    cone = int(cone)
    if cone not in (0, 1):
        raise ValueError(f"cone {cone!r}: only the L (0) and M (1) pigments are shifted")
    shift_nm = float(shift_nm)
    if not (np.isfinite(shift_nm) and abs(shift_nm) <= 40.0):
        raise ValueError(f"shift {shift_nm!r} nm: give a finite Δλ within ±40 nm")
    return _shifted_StockmanSharpe2000(cone, shift_nm)


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
