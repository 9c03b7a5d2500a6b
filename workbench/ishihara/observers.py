"""Simulated observers: normal, anomalous and dichromatic, computed from spectra.

An observer turns spectral radiance into cone excitations with its cone
fundamentals, then into coordinates of its own chromatic space, in which the
Euclidean distance is the colour difference in just-noticeable differences
(JND) of the receptor-noise-limited model.

Cone fundamentals (:data:`OBSERVER_FUNDAMENTALS`; the ``@ID`` of an observer's name)
    ``sp1975`` (the default): Smith & Pokorny (1975) on the CIE 1931 2°
    observer (:mod:`workbench.ishihara.cones`). Anomalous trichromats follow
    Machado et al. (2009) as colour-science implements it
    (:func:`colour.msds_cmfs_anomalous_trichromacy_Machado2009`): the
    anomalous fundamental is a *blend* of the normal one and the other,
    ``L_a = α·L + 0.96·(A_L/A_M)·(1 − α)·M`` for a protan (the deutan's M_a
    likewise), ``α = (20 − Δλ)/20``, ``Δλ = 20 nm × severity`` (``A``: the
    curves' areas) — Machado et al.'s linear stand-in for a Δλ shift of the
    pigment, not a shift. At severity 1, ``L ∝ M``: the observer is a
    dichromat (protanope or deuteranope), which is also how Machado et al.
    define dichromacy. Every one of these observers' cones is a linear
    function of CIE 1931 XYZ, so any rendering that matches ``XYZ_t``
    matches all of them: they cannot see observer metamerism.

    ``ss2000``: Stockman & Sharpe (2000) 2°, physiologically based and *not*
    a linear transform of CIE 1931. Anomalous trichromats have the L (protan)
    or M (deutan) photopigment moved along the wavelength axis towards the
    other by ``severity ×`` the distance between the two pigments' peaks
    (~29 nm), behind pre-receptoral filters that stay put
    (:func:`~workbench.ishihara.cones.cone_fundamental_shifted_StockmanSharpe2000`);
    at severity 1 the pigment *is* the other one (``L = M``, the replacement
    model of dichromacy; the shift reaches it within 1.5 % of the peak).
    Level 2 is computed for the CIE 1931 observer; for these observers the
    HMD's narrow-band primaries are a metamer of the plate, not a match, and
    they show how far level 2 holds for cones that are not CIE 1931's
    (observer metamerism).

    A tritanope (severity 1 only) has no S cones at all, with either set.
Chromatic space
    The receptor-noise-limited (RNL) model of Vorobyev & Osorio (1998): the
    signal of receptor ``i`` is ``f_i = ln q_i`` (``q_i`` its excitation), each
    carries noise of standard deviation ``e_i`` (a Weber fraction), and the
    chromatic distance is the Mahalanobis distance of the receptor *contrasts*
    ``P·Δf`` (``P`` takes differences between receptors, so that a change of
    intensity alone is invisible): ``ΔS² = (PΔf)ᵀ (P diag(e²) Pᵀ)⁻¹ (PΔf)``.
    For a trichromat this is Vorobyev & Osorio's Eq. (4), for a dichromat
    ``ΔS = |Δf₁ − Δf₂| / √(e₁² + e₂²)``. ``ΔS = 1`` is one JND. Being built on
    log ratios, it is blind to lightness and to von Kries adaptation — the
    Ishihara plates' random dot lightness is meant to make lightness useless.
Weber fractions
    ``e_L = e_M = 0.003`` and ``e_S = 0.03``: the model then detects about
    0.2 % L/M cone contrast along the L−M direction and about 3 % S-cone
    contrast, the order of magnitude of human cone-contrast detection thresholds
    (red–green roughly ten times more sensitive than S; Chaparro et al. 1993;
    Eskew et al. 1999). These set the scale of every JND figure.

Scale: radiance in any unit (W·sr⁻¹·m⁻²·nm⁻¹ or reflectance × source) on the
working wavelengths, 380–780 nm at 1 nm; coordinates and distances in JND.

References
----------
Machado, G. M., Oliveira, M. M., & Fernandes, L. A. F. (2009). A
physiologically-based model for simulation of color vision deficiency. *IEEE
Transactions on Visualization and Computer Graphics*, 15(6), 1291–1298.

Vorobyev, M., & Osorio, D. (1998). Receptor noise as a determinant of colour
thresholds. *Proceedings of the Royal Society B*, 265(1394), 351–358.

Chaparro, A., Stromeyer, C. F., Huang, E. P., Kronauer, R. E., & Eskew, R. T.
(1993). Colour is what the eye sees best. *Nature*, 361, 348–350.

Eskew, R. T., McLellan, J. S., & Giulianini, F. (1999). Chromatic detection
and discrimination. In K. R. Gegenfurtner & L. T. Sharpe (Eds.), *Color
Vision: From Genes to Perception* (pp. 345–368). Cambridge University Press.

Smith, V. C., & Pokorny, J. (1975); Stockman, A., & Sharpe, L. T. (2000), see
:mod:`workbench.ishihara.cones`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import colour
import numpy as np

from workbench.colorimetry import WORKING_WAVELENGTHS
from workbench.errors import InputError
from workbench.ishihara.cones import (
    CONES,
    cone_fundamental_shifted_StockmanSharpe2000,
    cone_fundamentals_Smith_Pokorny1975,
    cone_fundamentals_StockmanSharpe2000,
    photopigment_peaks_StockmanSharpe2000,
)

__all__ = [
    "WEBER_FRACTIONS",
    "MACHADO2009_DICHROMAT_SHIFT_NM",
    "ConeFundamentalsSet",
    "OBSERVER_FUNDAMENTALS",
    "DEFAULT_FUNDAMENTALS",
    "Observer",
    "OBSERVER_DEFICIENCIES",
    "simulated_observer",
    "parse_observer",
]

WEBER_FRACTIONS = np.array([0.003, 0.003, 0.03])
"""Receptor-noise Weber fractions ``e_L, e_M, e_S`` (module notes)."""

MACHADO2009_DICHROMAT_SHIFT_NM = 20.0
"""Peak shift of the anomalous pigment at which Machado et al. (2009) reach dichromacy."""


@dataclass(frozen=True, eq=False)
class Observer:
    """A simulated observer.

    Attributes
    ----------
    name : str
        What :func:`parse_observer` reads back, e.g. ``"protan:0.5"`` or
        ``"deutan@ss2000"``.
    deficiency : str
        ``"normal"``, ``"protan"``, ``"deutan"`` or ``"tritan"``.
    severity : float
        0 for a normal trichromat, (0, 1) for an anomalous trichromat, 1 for a
        dichromat.
    fundamentals : ndarray, shape (401, 3)
        L, M, S cone fundamentals on the working wavelengths (after the shift).
    receptors : tuple of int
        The cone classes present (indices into L, M, S).
    weber_fractions : ndarray, shape (3,)
        Receptor noise ``e_L, e_M, e_S``.
    fundamentals_id : str
        The key of :data:`OBSERVER_FUNDAMENTALS` the fundamentals come from.
    """

    name: str
    deficiency: str
    severity: float
    fundamentals: np.ndarray
    receptors: tuple
    weber_fractions: np.ndarray
    fundamentals_id: str = "sp1975"

    def __post_init__(self):
        receptors = tuple(int(r) for r in self.receptors)
        noise = np.asarray(self.weber_fractions, dtype=float)[list(receptors)]
        differences = np.diff(np.eye(len(receptors)), axis=0)  # rows: f[i+1] − f[i]
        covariance = differences @ np.diag(noise ** 2) @ differences.T
        whitening = np.linalg.inv(np.linalg.cholesky(covariance)) @ differences
        object.__setattr__(self, "receptors", receptors)
        object.__setattr__(self, "_whitening", whitening)

    @property
    def description(self) -> str:
        """E.g. ``"protanomalous trichromat (severity 0.5, L blended towards M …)"``."""
        cones = OBSERVER_FUNDAMENTALS[self.fundamentals_id]
        suffix = "" if self.fundamentals_id == DEFAULT_FUNDAMENTALS else f"; {cones.name}"
        if self.deficiency == "normal":
            return f"normal trichromat ({cones.name})" if suffix else "normal trichromat"
        if self.deficiency == "tritan":
            return f"tritanope (no S cones{suffix})"
        if self.severity >= 1.0:
            kind = {"protan": "protanope", "deutan": "deuteranope"}[self.deficiency]
            return f"{kind} (dichromat: {cones.dichromacy(self.deficiency)}{suffix})"
        kind = {"protan": "protanomalous", "deutan": "deuteranomalous"}[self.deficiency]
        return (f"{kind} trichromat (severity {self.severity:g}, "
                f"{cones.anomaly(self.deficiency, self.severity)}{suffix})")

    @property
    def dimensions(self) -> int:
        """Number of chromatic dimensions (receptor classes − 1)."""
        return len(self.receptors) - 1

    def cone_excitations(self, radiance) -> np.ndarray:
        """Excitations ``(…, 3)`` of L, M, S for spectral radiance ``(…, 401)``."""
        radiance = np.asarray(radiance, dtype=float)
        if radiance.shape[-1] != WORKING_WAVELENGTHS.size:
            raise InputError(f"observer {self.name!r}: radiance has {radiance.shape[-1]} bands; "
                             f"give {WORKING_WAVELENGTHS.size} values at 380–780 nm, 1 nm")
        if not np.all(np.isfinite(radiance)) or np.any(radiance < 0):
            raise InputError(f"observer {self.name!r}: radiance holds NaN, infinite or negative "
                             "values; spectral radiance is finite and non-negative")
        return radiance @ self.fundamentals

    def chromatic_coordinates(self, radiance) -> np.ndarray:
        """Coordinates ``(…, dimensions)`` in the observer's RNL space, in JND.

        Lights that are black for a receptor class (no excitation at all) have
        no chromaticity: an :class:`InputError` names them.
        """
        excitations = self.cone_excitations(radiance)[..., list(self.receptors)]
        if np.any(excitations <= 0):
            raise InputError(f"observer {self.name!r}: a light excites none of the "
                             f"{'/'.join(CONES[r] for r in self.receptors)} cones of some class "
                             "(black or monochromatic beyond their range); it has no chromaticity")
        return np.log(excitations) @ self._whitening.T

    def colour_difference(self, radiance_a, radiance_b) -> np.ndarray:
        """Chromatic difference ``ΔS`` (JND) between two radiances ``(…, 401)``."""
        delta = self.chromatic_coordinates(radiance_a) - self.chromatic_coordinates(radiance_b)
        return np.linalg.norm(delta, axis=-1)


@lru_cache(maxsize=32)
def _fundamentals_Machado2009(cone: int, severity: float) -> np.ndarray:
    """Machado et al. (2009) blend of the L (cone 0) or M (cone 1) fundamental towards the other."""
    fundamentals = np.asarray(cone_fundamentals_Smith_Pokorny1975())
    d_LMS = np.zeros(3)
    d_LMS[cone] = MACHADO2009_DICHROMAT_SHIFT_NM * severity
    cmfs = colour.colorimetry.LMS_ConeFundamentals(
        fundamentals, WORKING_WAVELENGTHS, labels=("l_bar", "m_bar", "s_bar"),
        name="Smith & Pokorny 1975 (CIE 1931 2°)")
    shifted = np.array(colour.msds_cmfs_anomalous_trichromacy_Machado2009(cmfs, d_LMS).values)
    shifted.setflags(write=False)
    return shifted


def _anomaly_Machado2009(deficiency: str, severity: float) -> str:
    cone, other = ("L", "M") if deficiency == "protan" else ("M", "L")
    return (f"{cone} blended towards {other} as Machado 2009 model a "
            f"{MACHADO2009_DICHROMAT_SHIFT_NM * severity:g} nm shift")


def _dichromacy_Machado2009(deficiency: str) -> str:
    cone, other = ("L", "M") if deficiency == "protan" else ("M", "L")
    return f"{cone} proportional to {other}, Machado 2009"


def _StockmanSharpe2000_separation_nm() -> float:
    peak_L, peak_M, _ = photopigment_peaks_StockmanSharpe2000()
    return peak_L - peak_M


@lru_cache(maxsize=32)
def _fundamentals_StockmanSharpe2000(cone: int, severity: float) -> np.ndarray:
    """The L (cone 0) or M (cone 1) photopigment moved ``severity`` of the way onto the other."""
    fundamentals = np.array(cone_fundamentals_StockmanSharpe2000())
    other = 1 - cone
    if severity >= 1.0:
        fundamentals[:, cone] = fundamentals[:, other]  # replacement: the same pigment
    else:
        towards = -1.0 if cone == 0 else 1.0
        shift = towards * severity * _StockmanSharpe2000_separation_nm()
        fundamentals[:, cone] = cone_fundamental_shifted_StockmanSharpe2000(cone, shift)
    fundamentals.setflags(write=False)
    return fundamentals


def _anomaly_StockmanSharpe2000(deficiency: str, severity: float) -> str:
    cone, other = ("L", "M") if deficiency == "protan" else ("M", "L")
    shift = severity * _StockmanSharpe2000_separation_nm()
    return f"{cone} pigment shifted {shift:.1f} nm towards {other}"


def _dichromacy_StockmanSharpe2000(deficiency: str) -> str:
    cone, other = ("L", "M") if deficiency == "protan" else ("M", "L")
    return f"the {cone} cones hold the {other} pigment"


@dataclass(frozen=True)
class ConeFundamentalsSet:
    """A set of cone fundamentals and how it makes anomalous trichromats.

    Attributes
    ----------
    id : str
        Key of :data:`OBSERVER_FUNDAMENTALS` (the ``@ID`` of observer names).
    name : str
    linear_in_cie1931 : bool
        Whether every observer built on it is a linear function of CIE 1931
        XYZ (then level 2 matches it by construction).
    normal : callable
        ``() → (401, 3)`` fundamentals of the normal trichromat.
    anomalous : callable
        ``(cone, severity) → (401, 3)``: L (0) or M (1) made anomalous,
        severity in (0, 1] (1: a dichromat).
    anomaly, dichromacy : callable
        Describe what ``anomalous`` did, for :attr:`Observer.description`.
    """

    id: str
    name: str
    linear_in_cie1931: bool
    normal: Callable
    anomalous: Callable
    anomaly: Callable
    dichromacy: Callable


OBSERVER_FUNDAMENTALS = {
    "sp1975": ConeFundamentalsSet(
        "sp1975", "Smith & Pokorny 1975 on CIE 1931 2°", True,
        cone_fundamentals_Smith_Pokorny1975, _fundamentals_Machado2009,
        _anomaly_Machado2009, _dichromacy_Machado2009),
    "ss2000": ConeFundamentalsSet(
        "ss2000", "Stockman & Sharpe 2000 2°", False,
        cone_fundamentals_StockmanSharpe2000, _fundamentals_StockmanSharpe2000,
        _anomaly_StockmanSharpe2000, _dichromacy_StockmanSharpe2000),
}
"""Cone fundamentals id → :class:`ConeFundamentalsSet` (module notes)."""

DEFAULT_FUNDAMENTALS = "sp1975"


def _fundamentals_set(fundamentals: str) -> ConeFundamentalsSet:
    try:
        return OBSERVER_FUNDAMENTALS[fundamentals]
    except KeyError:
        raise InputError(f"unknown cone fundamentals {fundamentals!r}; use one of "
                         f"{sorted(OBSERVER_FUNDAMENTALS)} (e.g. 'normal@ss2000')") from None


def _named(base: str, cones: ConeFundamentalsSet) -> str:
    return base if cones.id == DEFAULT_FUNDAMENTALS else f"{base}@{cones.id}"


def _check_severity(deficiency: str, severity: float) -> float:
    severity = float(severity)
    if not (np.isfinite(severity) and 0.0 < severity <= 1.0):
        raise InputError(f"{deficiency} severity {severity!r} must be in (0, 1]: 1 is a "
                         "dichromat, e.g. 0.5 an anomalous trichromat with half the shift")
    return severity


def _normal(severity: float | None, cones: ConeFundamentalsSet) -> Observer:
    if severity not in (None, 0, 0.0):
        raise InputError(f"a normal observer has no severity (got {severity!r}); write 'normal', "
                         "or 'protan:S' / 'deutan:S' for an anomalous trichromat")
    return Observer(_named("normal", cones), "normal", 0.0, cones.normal(), (0, 1, 2),
                    WEBER_FRACTIONS, cones.id)


def _red_green(deficiency: str, cone: int):
    def build(severity: float | None, cones: ConeFundamentalsSet) -> Observer:
        severity = _check_severity(deficiency, 1.0 if severity is None else severity)
        base = deficiency if severity == 1.0 else f"{deficiency}:{severity:g}"
        return Observer(_named(base, cones), deficiency, severity,
                        cones.anomalous(cone, severity), (0, 1, 2), WEBER_FRACTIONS, cones.id)
    return build


def _tritan(severity: float | None, cones: ConeFundamentalsSet) -> Observer:
    if severity not in (None, 1, 1.0):
        raise InputError(f"tritan severity {severity!r}: only the tritanope (severity 1) is "
                         "simulated; Machado et al.'s shift model does not reach tritanopia. "
                         "Write 'tritan'")
    return Observer(_named("tritan", cones), "tritan", 1.0, cones.normal(), (0, 1),
                    WEBER_FRACTIONS, cones.id)


OBSERVER_DEFICIENCIES = {
    "normal": _normal,
    "protan": _red_green("protan", 0),
    "deutan": _red_green("deutan", 1),
    "tritan": _tritan,
}
"""Deficiency → builder ``(severity or None, ConeFundamentalsSet) → Observer``."""


def simulated_observer(deficiency: str = "normal", severity: float | None = None,
                       fundamentals: str = DEFAULT_FUNDAMENTALS) -> Observer:
    """The simulated observer with ``deficiency`` at ``severity``.

    Parameters
    ----------
    deficiency : str
        A key of :data:`OBSERVER_DEFICIENCIES`.
    severity : float, optional
        (0, 1] for protan and deutan (default 1: the dichromat); none for a
        normal observer; 1 (the default) for tritan.
    fundamentals : str
        A key of :data:`OBSERVER_FUNDAMENTALS` (default ``"sp1975"``, linear in
        CIE 1931; ``"ss2000"``: Stockman & Sharpe 2000).

    Examples
    --------
    >>> simulated_observer("protan", 0.5).description  # doctest: +ELLIPSIS
    'protanomalous trichromat (severity 0.5, L blended towards M as Machado 2009 model a 10 nm...'
    >>> simulated_observer("protan", 0.5, "ss2000").name
    'protan:0.5@ss2000'
    """
    try:
        builder = OBSERVER_DEFICIENCIES[deficiency]
    except KeyError:
        raise InputError(f"unknown observer {deficiency!r}; use one of "
                         f"{sorted(OBSERVER_DEFICIENCIES)} (with ':SEVERITY' for protan and "
                         "deutan, e.g. 'deutan:0.6', and '@FUNDAMENTALS' for other cones, e.g. "
                         "'protan@ss2000')") from None
    return builder(severity, _fundamentals_set(fundamentals))


def parse_observer(text: str) -> Observer:
    """An observer from ``"normal"``, ``"protan"``, ``"deutan:0.6"``, ``"normal@ss2000"`` ….

    The form is ``DEFICIENCY[:SEVERITY][@FUNDAMENTALS]``; ``@FUNDAMENTALS`` is a
    key of :data:`OBSERVER_FUNDAMENTALS` (default ``sp1975``).
    """
    text = str(text).strip().lower()
    observer, at, fundamentals = text.partition("@")
    if at and not fundamentals:
        raise InputError(f"observer {text!r}: name the cone fundamentals after '@', one of "
                         f"{sorted(OBSERVER_FUNDAMENTALS)}")
    fundamentals = fundamentals or DEFAULT_FUNDAMENTALS
    deficiency, _, severity = observer.partition(":")
    if not severity:
        return simulated_observer(deficiency, fundamentals=fundamentals)
    try:
        value = float(severity)
    except ValueError:
        raise InputError(f"observer {text!r}: severity {severity!r} is not a number; write e.g. "
                         "'protan:0.5'") from None
    return simulated_observer(deficiency, value, fundamentals)
