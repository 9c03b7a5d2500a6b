"""Simulated observers: normal, anomalous and dichromatic, computed from spectra.

An observer turns spectral radiance into cone excitations with its cone
fundamentals, then into coordinates of its own chromatic space, in which the
Euclidean distance is the colour difference in just-noticeable differences
(JND) of the receptor-noise-limited model.

Cone fundamentals
    Smith & Pokorny (1975) on the CIE 1931 2° observer
    (:mod:`workbench.ishihara.cones`). Anomalous trichromats follow Machado et
    al. (2009): the L (protan) or M (deutan) fundamental is shifted towards
    the other by ``Δλ = 20 nm × severity``, as colour-science implements it
    (:func:`colour.msds_cmfs_anomalous_trichromacy_Machado2009`); at severity 1
    the shifted pigment equals the other one and the observer is a dichromat
    (protanope or deuteranope), which is also how Machado et al. define
    dichromacy. A tritanope (severity 1 only) has no S cones at all.
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

Smith, V. C., & Pokorny, J. (1975), see :mod:`workbench.ishihara.cones`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import colour
import numpy as np

from workbench.colorimetry import WORKING_WAVELENGTHS
from workbench.errors import InputError
from workbench.ishihara.cones import CONES, cone_fundamentals_Smith_Pokorny1975

__all__ = [
    "WEBER_FRACTIONS",
    "MACHADO2009_DICHROMAT_SHIFT_NM",
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
        What :func:`parse_observer` reads back, e.g. ``"protan:0.5"``.
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
    """

    name: str
    deficiency: str
    severity: float
    fundamentals: np.ndarray
    receptors: tuple
    weber_fractions: np.ndarray

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
        """E.g. ``"protanomalous trichromat (severity 0.5, L cone shifted 10 nm)"``."""
        if self.deficiency == "normal":
            return "normal trichromat"
        if self.deficiency == "tritan":
            return "tritanope (no S cones)"
        cone, other = ("L", "M") if self.deficiency == "protan" else ("M", "L")
        if self.severity >= 1.0:
            kind = {"protan": "protanope", "deutan": "deuteranope"}[self.deficiency]
            return (f"{kind} (dichromat: {cone} pigment shifted "
                    f"{MACHADO2009_DICHROMAT_SHIFT_NM:g} nm onto {other})")
        kind = {"protan": "protanomalous", "deutan": "deuteranomalous"}[self.deficiency]
        shift = MACHADO2009_DICHROMAT_SHIFT_NM * self.severity
        return f"{kind} trichromat (severity {self.severity:g}, {cone} cone shifted {shift:g} nm)"

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
def _shifted_fundamentals(cone: int, shift_nm: float) -> np.ndarray:
    """Machado et al. (2009) shift of the L (cone 0) or M (cone 1) fundamental."""
    fundamentals = np.asarray(cone_fundamentals_Smith_Pokorny1975())
    d_LMS = np.zeros(3)
    d_LMS[cone] = shift_nm
    cmfs = colour.colorimetry.LMS_ConeFundamentals(
        fundamentals, WORKING_WAVELENGTHS, labels=("l_bar", "m_bar", "s_bar"),
        name="Smith & Pokorny 1975 (CIE 1931 2°)")
    shifted = np.array(colour.msds_cmfs_anomalous_trichromacy_Machado2009(cmfs, d_LMS).values)
    shifted.setflags(write=False)
    return shifted


def _check_severity(deficiency: str, severity: float) -> float:
    severity = float(severity)
    if not (np.isfinite(severity) and 0.0 < severity <= 1.0):
        raise InputError(f"{deficiency} severity {severity!r} must be in (0, 1]: 1 is a "
                         "dichromat, e.g. 0.5 an anomalous trichromat with half the shift")
    return severity


def _normal(severity: float | None) -> Observer:
    if severity not in (None, 0, 0.0):
        raise InputError(f"a normal observer has no severity (got {severity!r}); write 'normal', "
                         "or 'protan:S' / 'deutan:S' for an anomalous trichromat")
    return Observer("normal", "normal", 0.0, cone_fundamentals_Smith_Pokorny1975(), (0, 1, 2),
                    WEBER_FRACTIONS)


def _red_green(deficiency: str, cone: int):
    def build(severity: float | None) -> Observer:
        severity = _check_severity(deficiency, 1.0 if severity is None else severity)
        fundamentals = _shifted_fundamentals(cone, MACHADO2009_DICHROMAT_SHIFT_NM * severity)
        name = deficiency if severity == 1.0 else f"{deficiency}:{severity:g}"
        return Observer(name, deficiency, severity, fundamentals, (0, 1, 2), WEBER_FRACTIONS)
    return build


def _tritan(severity: float | None) -> Observer:
    if severity not in (None, 1, 1.0):
        raise InputError(f"tritan severity {severity!r}: only the tritanope (severity 1) is "
                         "simulated; Machado et al.'s shift model does not reach tritanopia. "
                         "Write 'tritan'")
    return Observer("tritan", "tritan", 1.0, cone_fundamentals_Smith_Pokorny1975(), (0, 1),
                    WEBER_FRACTIONS)


OBSERVER_DEFICIENCIES = {
    "normal": _normal,
    "protan": _red_green("protan", 0),
    "deutan": _red_green("deutan", 1),
    "tritan": _tritan,
}
"""Deficiency → builder ``(severity or None) → Observer``."""


def simulated_observer(deficiency: str = "normal", severity: float | None = None) -> Observer:
    """The simulated observer with ``deficiency`` at ``severity``.

    Parameters
    ----------
    deficiency : str
        A key of :data:`OBSERVER_DEFICIENCIES`.
    severity : float, optional
        (0, 1] for protan and deutan (default 1: the dichromat); none for a
        normal observer; 1 (the default) for tritan.

    Examples
    --------
    >>> simulated_observer("protan", 0.5).description
    'protanomalous trichromat (severity 0.5, L cone shifted 10 nm)'
    """
    try:
        builder = OBSERVER_DEFICIENCIES[deficiency]
    except KeyError:
        raise InputError(f"unknown observer {deficiency!r}; use one of "
                         f"{sorted(OBSERVER_DEFICIENCIES)} (with ':SEVERITY' for protan and "
                         "deutan, e.g. 'deutan:0.6')") from None
    return builder(severity)


def parse_observer(text: str) -> Observer:
    """An observer from ``"normal"``, ``"protan"``, ``"deutan:0.6"``, ``"tritan"``."""
    deficiency, _, severity = str(text).strip().lower().partition(":")
    if not severity:
        return simulated_observer(deficiency)
    try:
        value = float(severity)
    except ValueError:
        raise InputError(f"observer {text!r}: severity {severity!r} is not a number; write e.g. "
                         "'protan:0.5'") from None
    return simulated_observer(deficiency, value)
