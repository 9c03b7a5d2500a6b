"""Dot reflectances of the virtual Ishihara plates, designed on confusion lines.

The palette starts from the paper's ten dot colours of its plate 3 (Table 5,
"calculated" under CIE D65: four families — green, ochre, purple,
bluish-green) and derives the colours the plates need so that figure and
background lie *exactly* on one confusion line of the deficiency they target
(:mod:`workbench.ishihara.cones` gives the copunctal points):

``ochre``
    The figure colour: the ochre family's mean chromaticity, at its lightest
    luminance factor.
``green-p``, ``green-d``
    Background colours: the green family's mean chromaticity projected onto
    the protan (``-p``) and the deutan (``-d``) confusion line through
    ``ochre``. A protanope cannot tell ``ochre`` from ``green-p``, a
    deuteranope ``ochre`` from ``green-d``; a background of both hides an
    ochre figure from protans *and* deutans (each sees it merge with half of
    the background), while a normal observer sees a red–green contrast.
``purple``, ``blue-green-p``, ``blue-green-d``
    The same three with their S-cone excitation multiplied by one factor, the
    one that moves ``ochre`` along its tritan confusion line (constant L:M)
    to the purple family's mean chromaticity. The shift is seen by every
    observer with S cones; the protan and deutan pairs stay on one confusion
    line (``purple``/``blue-green-p`` protan, ``purple``/``blue-green-d`` deutan).
``bluish-green``, ``red-protan``, ``red-deutan``
    The classification plate: the bluish-green family's mean as background,
    and two reds on its protan and its deutan confusion line, displaced
    towards red until the *other* dichromat sees them at
    :data:`CLASSIFICATION_MARGIN` times the legibility threshold (the
    deuteranope must read the digit that vanishes for protans, and vice versa).

Each colour is turned into a reflectance by spectral upsampling
(:data:`SPECTRAL_UPSAMPLING_METHODS`, Otsu et al. 2018 by default) followed by
an exact correction in the fundamental-metamer space (Cohen & Kappauf 1982):
the minimal change of the reflectance that puts its D65 tristimulus values on
the design target, iterated with the reflectance clipped to [0, 1]. Dots vary
in lightness by a factor on :attr:`Palette.lightness_range` (the paper's
darkest-to-lightest luminance ratio within a family), which scales the
reflectance and keeps its chromaticity — and so the confusion — exact.

Scale: reflectance on 0..1 at the working wavelengths; design targets are
CIE 1931 xyY under D65 with Y the luminance factor (perfect diffuser = 1).

References
----------
Díaz-Barrancas et al. (2020), Table 5 (see :mod:`workbench.ishihara.paper`).

Otsu, H., Yamamoto, M., & Hachisuka, T. (2018). Reproducing Spectral
Reflectances From Tristimulus Colours. *Computer Graphics Forum*, 37(6), 370–381.

Meng, J., Simon, F., Hanika, J., & Dachsbacher, C. (2015). Physically
Meaningful Rendering using Tristimulus Colours. *Computer Graphics Forum*,
34(4), 31–40.

Cohen, J. B., & Kappauf, W. E. (1982). Metameric color stimuli, fundamental
metamers, and Wyszecki's metameric blacks. *American Journal of Psychology*,
95(4), 537–564.

Ishihara, S. (1917/2009). *Ishihara's Tests for Colour Deficiency*, 38 Plates
Edition, Kanehara Trading (instructions: design of the plate types).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType

import colour
import numpy as np
from scipy.optimize import brentq

from workbench.colorimetry import WORKING_SHAPE, XYZ_relative_weights
from workbench.errors import InputError
from workbench.ishihara.cones import LMS_to_XYZ, XYZ_to_LMS, copunctal_point
from workbench.ishihara.observers import simulated_observer
from workbench.ishihara.paper import PAPER_DOT_FAMILIES, PAPER_TABLE5
from workbench.ishihara.reading import LEGIBILITY_THRESHOLD_JND

__all__ = [
    "CLASSIFICATION_MARGIN",
    "SPECTRAL_UPSAMPLING_METHODS",
    "PaletteColour",
    "Palette",
    "XYZ_to_reflectance",
    "D65_reflectance_XYZ",
    "project_on_confusion_line",
    "paper_dot_colours",
    "design_palette",
]

CLASSIFICATION_MARGIN = 2.0
"""The other dichromat sees a classification digit at this many legibility thresholds."""

_D65 = colour.SDS_ILLUMINANTS["D65"]


@lru_cache(maxsize=1)
def _d65_weights() -> np.ndarray:
    weights = XYZ_relative_weights(_D65, k=1.0, Y_white=1.0)
    weights.setflags(write=False)
    return weights


def D65_reflectance_XYZ(reflectances) -> np.ndarray:
    """CIE 1931 XYZ ``(…, 3)`` of reflectances ``(…, 401)`` under D65 (perfect diffuser Y = 1)."""
    return np.asarray(reflectances, dtype=float) @ _d65_weights()


def _upsample_Otsu2018(XYZ: np.ndarray) -> np.ndarray:
    return colour.XYZ_to_sd(XYZ, method="Otsu 2018")


def _upsample_Meng2015(XYZ: np.ndarray) -> np.ndarray:
    return colour.XYZ_to_sd(XYZ, method="Meng 2015", shape=colour.SpectralShape(380, 780, 10))


SPECTRAL_UPSAMPLING_METHODS = {
    "Otsu 2018": _upsample_Otsu2018,
    "Meng 2015": _upsample_Meng2015,
}
"""Spectral upsampling method → ``XYZ (D65, Y on 0..1) → SpectralDistribution``.

Otsu et al. (2018) is a clustered PCA basis (~2 ms a colour); Meng et al.
(2015) a smoothness optimisation (~1 s). Jakob & Hanika (2019) is exact too but
its lookup table takes minutes to build, so it is not offered here.
"""

_CORRECTION_TOLERANCE = 1e-10


def _fundamental_metamer_step(weights: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """The smallest (L2) spectral change whose tristimulus values are ``residual``."""
    return weights @ np.linalg.solve(weights.T @ weights, residual)


def XYZ_to_reflectance(XYZ, method: str = "Otsu 2018") -> np.ndarray:
    """A reflectance (401,) on [0, 1] whose D65 tristimulus values are exactly ``XYZ``.

    Parameters
    ----------
    XYZ : array_like, shape (3,)
        CIE 1931 XYZ under D65 with the perfect diffuser at Y = 1.
    method : str
        A key of :data:`SPECTRAL_UPSAMPLING_METHODS`: the smooth first guess.

    Returns
    -------
    ndarray, shape (401,)
        The guess, then the minimal (fundamental-metamer) correction that
        reaches ``XYZ`` to 1e-10, iterated with the reflectance clipped to [0, 1].

    Raises
    ------
    InputError
        Unknown method, or a colour no reflectance on [0, 1] reaches (outside
        the object-colour solid): the message names it.
    """
    try:
        upsample = SPECTRAL_UPSAMPLING_METHODS[method]
    except KeyError:
        raise InputError(f"unknown spectral upsampling method {method!r}; use one of "
                         f"{sorted(SPECTRAL_UPSAMPLING_METHODS)}") from None
    XYZ = np.asarray(XYZ, dtype=float)
    if XYZ.shape != (3,) or not np.all(np.isfinite(XYZ)) or XYZ[1] <= 0:
        raise InputError(f"XYZ {XYZ.tolist()} is not a surface colour; give three finite values "
                         "with 0 < Y <= 1 (D65, perfect diffuser Y = 1)")
    guess = upsample(XYZ).copy().align(WORKING_SHAPE).values
    reflectance = np.clip(guess, 0.0, 1.0)
    weights = _d65_weights()
    for _ in range(50):
        residual = XYZ - reflectance @ weights
        if np.max(np.abs(residual)) < _CORRECTION_TOLERANCE:
            return reflectance
        step = _fundamental_metamer_step(weights, residual)
        # bands pinned at a bound the step pushes further out take no part
        free = ~(((reflectance <= 0.0) & (step < 0)) | ((reflectance >= 1.0) & (step > 0)))
        if not np.all(free):
            step = np.zeros_like(reflectance)
            try:
                step[free] = _fundamental_metamer_step(weights[free], residual)
            except np.linalg.LinAlgError:  # the free bands no longer span XYZ: out of reach
                break
        reflectance = np.clip(reflectance + step, 0.0, 1.0)
    raise InputError(f"no reflectance on [0, 1] has D65 XYZ {np.round(XYZ, 5).tolist()} "
                     f"(residual {np.abs(residual).max():.2g}); the colour lies outside the "
                     "object-colour solid: lower its luminance or its saturation")


def project_on_confusion_line(xy, through_xy, deficiency: str) -> np.ndarray:
    """The point of the ``deficiency`` confusion line through ``through_xy`` nearest ``xy``.

    Orthogonal projection in the CIE 1931 xy diagram onto the line joining the
    copunctal point and ``through_xy``.
    """
    point = copunctal_point(deficiency)
    direction = np.asarray(through_xy, dtype=float) - point
    direction /= np.linalg.norm(direction)
    return point + direction * np.dot(np.asarray(xy, dtype=float) - point, direction)


@dataclass(frozen=True, eq=False)
class PaletteColour:
    """One designed dot colour.

    Attributes
    ----------
    name : str
        E.g. ``"ochre"``, ``"green-p"``, ``"P4"``.
    role : str
        What the plates use it for.
    xyY : ndarray, shape (3,)
        Design target under D65 (Y on 0..1); the reflectance reaches it exactly.
    reflectance : ndarray, shape (401,)
        On [0, 1] at the working wavelengths.
    partners : tuple of (str, str)
        ``(deficiency, colour name)``: colours that lie on one confusion line of
        that deficiency with this one.
    """

    name: str
    role: str
    xyY: np.ndarray
    reflectance: np.ndarray
    partners: tuple = ()


@dataclass(frozen=True, eq=False)
class Palette:
    """The designed colours of the plates.

    Attributes
    ----------
    colours : mapping of str to PaletteColour
    lightness_range : (float, float)
        Factors the dots' reflectances are scaled by (darkest, lightest).
    method : str
        The spectral upsampling method used.
    """

    colours: MappingProxyType
    lightness_range: tuple
    method: str

    def __getitem__(self, name: str) -> PaletteColour:
        try:
            return self.colours[name]
        except KeyError:
            raise InputError(f"the palette has no colour {name!r}; it has "
                             f"{sorted(self.colours)}") from None

    def __iter__(self):
        return iter(self.colours.values())

    def __len__(self) -> int:
        return len(self.colours)

    def reflectances(self, names) -> np.ndarray:
        """Reflectances ``(len(names), 401)`` of the named colours."""
        return np.stack([self[name].reflectance for name in names])


def _paper_XYZ(dot) -> np.ndarray:
    x, y, Y = dot.calculated_xyY
    return colour.xyY_to_XYZ([x, y, Y / 100.0])


@lru_cache(maxsize=4)
def paper_dot_colours(method: str = "Otsu 2018") -> tuple:
    """The paper's ten dot colours of plate 3 (Table 5) as reflectances.

    Returns
    -------
    tuple of PaletteColour
        ``P1`` … ``P10`` whose D65 xyY are the paper's "calculated" values exactly.
    """
    return tuple(
        PaletteColour(name=dot.dot, role=f"paper plate 3: {dot.name}",
                      xyY=np.array([dot.calculated_xyY[0], dot.calculated_xyY[1],
                                    dot.calculated_xyY[2] / 100.0]),
                      reflectance=XYZ_to_reflectance(_paper_XYZ(dot), method))
        for dot in PAPER_TABLE5)


def _family_statistics():
    means, lightest, ratios = {}, {}, []
    for family in PAPER_DOT_FAMILIES:
        dots = [d for d in PAPER_TABLE5 if d.family == family]
        xyY = np.array([d.calculated_xyY for d in dots])
        means[family] = xyY[:, :2].mean(axis=0)
        lightest[family] = xyY[:, 2].max() / 100.0
        ratios.append(xyY[:, 2].min() / xyY[:, 2].max())
    return means, lightest, (float(min(ratios)), 1.0)


def _xyY(XYZ) -> np.ndarray:
    return colour.XYZ_to_xyY(np.asarray(XYZ, dtype=float))


def _with_luminance(XYZ, Y: float) -> np.ndarray:
    XYZ = np.asarray(XYZ, dtype=float)
    return XYZ * (Y / XYZ[1])


def _s_factor_to(LMS: np.ndarray, target_xy: np.ndarray) -> float:
    """The factor on S that moves ``LMS`` along its tritan line to ``target_xy``."""
    point = copunctal_point("tritan")
    target = np.linalg.norm(target_xy - point)

    def offset(log_factor: float) -> float:
        xy = _xyY(LMS_to_XYZ(LMS * [1.0, 1.0, np.exp(log_factor)]))[:2]
        return np.linalg.norm(xy - point) - target

    return float(np.exp(brentq(offset, -3.0, 3.0, xtol=1e-12)))


def _displace_until_seen(ground_XYZ: np.ndarray, cone: int, sign: float, seen_by: str,
                         target_jnd: float, method: str) -> np.ndarray:
    """Move ``ground`` along the confusion line that keeps all cones but ``cone`` fixed.

    Stops where the dichromat ``seen_by`` sees it ``target_jnd`` from the
    ground (computed with the reflectances under D65).
    """
    observer = simulated_observer(seen_by)
    d65 = _D65.copy().align(WORKING_SHAPE).values
    ground = XYZ_to_reflectance(ground_XYZ, method) * d65
    LMS = XYZ_to_LMS(ground_XYZ)

    def colour_at(log_step: float) -> np.ndarray:
        factor = np.ones(3)
        factor[cone] = np.exp(sign * log_step)
        return _with_luminance(LMS_to_XYZ(LMS * factor), ground_XYZ[1])

    def shortfall(log_step: float) -> float:
        radiance = XYZ_to_reflectance(colour_at(log_step), method) * d65
        return float(observer.colour_difference(radiance, ground)) - target_jnd

    upper = 0.05
    while shortfall(upper) < 0:  # grow the bracket; XYZ_to_reflectance says when it cannot
        upper *= 1.5
    return colour_at(brentq(shortfall, 0.0, upper, xtol=1e-6))


@lru_cache(maxsize=4)
def design_palette(method: str = "Otsu 2018") -> Palette:
    """The designed palette of the plates (module notes).

    Parameters
    ----------
    method : str
        Spectral upsampling method (:data:`SPECTRAL_UPSAMPLING_METHODS`).

    Returns
    -------
    Palette
        ``ochre``, ``green-p``, ``green-d``, ``purple``, ``blue-green-p``,
        ``blue-green-d``, ``bluish-green``, ``red-protan``, ``red-deutan`` and
        the paper's ``P1`` … ``P10``.
    """
    means, lightest, lightness_range = _family_statistics()
    protan, deutan = "protan", "deutan"

    ochre = colour.xyY_to_XYZ([*means["ochre"], lightest["ochre"]])
    green = {
        deficiency: colour.xyY_to_XYZ([*project_on_confusion_line(means["green"], _xyY(ochre)[:2],
                                                           deficiency), lightest["green"]])
        for deficiency in (protan, deutan)
    }
    tritan_target = project_on_confusion_line(means["purple"], _xyY(ochre)[:2], "tritan")
    s_factor = _s_factor_to(XYZ_to_LMS(ochre), tritan_target)

    def s_shifted(XYZ, Y):
        return _with_luminance(LMS_to_XYZ(XYZ_to_LMS(XYZ) * [1.0, 1.0, s_factor]), Y)

    purple = s_shifted(ochre, lightest["purple"])
    blue_green = {d: s_shifted(green[d], lightest["bluish-green"]) for d in (protan, deutan)}

    ground = colour.xyY_to_XYZ([*means["bluish-green"], lightest["bluish-green"]])
    target = CLASSIFICATION_MARGIN * LEGIBILITY_THRESHOLD_JND
    red_protan = _displace_until_seen(ground, 0, +1.0, deutan, target, method)
    red_deutan = _displace_until_seen(ground, 1, -1.0, protan, target, method)

    designs = [
        ("ochre", ochre, "figure (red side): the ochre family's mean",
         ((protan, "green-p"), (deutan, "green-d"))),
        ("green-p", green[protan], "background: the green mean on ochre's protan line",
         ((protan, "ochre"),)),
        ("green-d", green[deutan], "background: the green mean on ochre's deutan line",
         ((deutan, "ochre"),)),
        ("purple", purple, f"figure seen by all: ochre with S × {s_factor:.3f} (tritan line)",
         ((protan, "blue-green-p"), (deutan, "blue-green-d"), ("tritan", "ochre"))),
        ("blue-green-p", blue_green[protan], "green-p with the same S shift",
         ((protan, "purple"), ("tritan", "green-p"))),
        ("blue-green-d", blue_green[deutan], "green-d with the same S shift",
         ((deutan, "purple"), ("tritan", "green-d"))),
        ("bluish-green", ground, "classification background: the bluish-green mean",
         ((protan, "red-protan"), (deutan, "red-deutan"))),
        ("red-protan", red_protan, "classification digit that vanishes for protans",
         ((protan, "bluish-green"),)),
        ("red-deutan", red_deutan, "classification digit that vanishes for deutans",
         ((deutan, "bluish-green"),)),
    ]
    colours = {name: PaletteColour(name=name, role=role, xyY=_xyY(XYZ),
                                   reflectance=XYZ_to_reflectance(XYZ, method), partners=partners)
               for name, XYZ, role, partners in designs}
    for dot in paper_dot_colours(method):
        colours[dot.name] = dot
    for c in colours.values():
        c.reflectance.setflags(write=False)
    return Palette(colours=MappingProxyType(colours), lightness_range=lightness_range,
                   method=method)
