"""Reference data of the paper's virtual Ishihara test (Tables 5 and 6).

These are published figures, kept verbatim as reference data; nothing here is
computed.

References
----------
Díaz-Barrancas, F., Cwierz, H., Pardo, P. J., Pérez, Á. L., & Suero, M. I.
(2020). Spectral Color Management in Virtual Reality Scenes. *Sensors*, 20(19),
5658, §3.2–3.3, Tables 5 and 6.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "PaperDot",
    "PAPER_TABLE5",
    "PAPER_TABLE5_MEAN_DE00",
    "PAPER_DOT_FAMILIES",
    "PaperObserver",
    "PAPER_TABLE6_REFERENCE",
    "PAPER_TABLE6_OBSERVERS",
]


@dataclass(frozen=True)
class PaperDot:
    """One dot colour of the paper's plate 3 (Table 5).

    Attributes
    ----------
    dot : str
        ``"P1"`` … ``"P10"``.
    name : str
        The paper's name, e.g. ``"Green Dark"``.
    family : str
        ``"green"``, ``"ochre"``, ``"purple"`` or ``"bluish-green"``.
    calculated_xyY : (float, float, float)
        CIE 1931 x, y and luminance factor Y (perfect diffuser = 100) computed
        from the hyperspectral image under CIE D65.
    measured_xyY : (float, float, float)
        The same dot measured on the HMD (Y on the same relative scale).
    dE00 : float
        The paper's CIEDE2000 between the two.
    """

    dot: str
    name: str
    family: str
    calculated_xyY: tuple
    measured_xyY: tuple
    dE00: float


PAPER_TABLE5 = (
    PaperDot("P1", "Green Dark", "green", (0.3560, 0.3854, 24.6), (0.3557, 0.3850, 25.4), 1.00),
    PaperDot("P2", "Green Medium", "green", (0.3602, 0.3906, 29.1), (0.3601, 0.3903, 30.0), 1.05),
    PaperDot("P3", "Green Light", "green", (0.3734, 0.3986, 38.4), (0.3731, 0.3984, 41.0), 0.82),
    PaperDot("P4", "Ochre Dark", "ochre", (0.3901, 0.3656, 27.1), (0.3895, 0.3655, 28.1), 0.70),
    PaperDot("P5", "Ochre Medium", "ochre", (0.4022, 0.3746, 33.1), (0.4014, 0.3743, 34.3), 0.76),
    PaperDot("P6", "Ochre Light", "ochre", (0.3945, 0.3834, 41.5), (0.3941, 0.3834, 42.8), 1.28),
    PaperDot("P7", "Purple Dark", "purple", (0.3713, 0.3282, 24.2), (0.3709, 0.3282, 25.6), 1.14),
    PaperDot("P8", "Purple Light", "purple", (0.3884, 0.3576, 36.1), (0.3878, 0.3573, 38.0), 0.72),
    PaperDot("P9", "Bluish-Green Dark", "bluish-green", (0.3158, 0.3759, 23.7),
             (0.3159, 0.3763, 22.7), 0.64),
    PaperDot("P10", "Bluish-Green Light", "bluish-green", (0.3182, 0.3881, 33.3),
             (0.3182, 0.3887, 31.7), 1.47),
)
"""Table 5: the ten dot colours of the paper's Ishihara plate 3, calculated (D65) and measured."""

PAPER_TABLE5_MEAN_DE00 = 0.96
"""Table 5's average CIEDE2000 between calculated and measured dot colours."""

PAPER_DOT_FAMILIES = ("green", "ochre", "purple", "bluish-green")
"""The colour families of Table 5, in its order."""


@dataclass(frozen=True)
class PaperObserver:
    """One row of Table 6: an observer's (or a reference's) answers to the 10 plates.

    Attributes
    ----------
    observer : str
        ``"Ref1"`` … ``"Ref3"``, ``"Ob1"`` … ``"Ob10"``.
    qualification : str
        ``"normal"``, ``"protan"`` or ``"deutan"``.
    answers : tuple of str
        Ten answers; ``"-"`` where nothing was read.
    """

    observer: str
    qualification: str
    answers: tuple


PAPER_TABLE6_REFERENCE = (
    PaperObserver("Ref1", "normal", ("12", "8", "6", "5", "3", "7", "3", "-", "-", "26")),
    PaperObserver("Ref2", "protan", ("12", "3", "5", "2", "5", "-", "-", "5", "8", "6")),
    PaperObserver("Ref3", "deutan", ("12", "3", "5", "2", "5", "-", "-", "5", "8", "2")),
)
"""Table 6, reference answers "following the Ishihara Test instructions"."""

PAPER_TABLE6_OBSERVERS = (
    PaperObserver("Ob1", "normal", ("12", "8", "6", "5", "3", "5", "7", "-", "8", "26")),
    PaperObserver("Ob2", "normal", ("12", "8", "6", "5", "3", "5", "7", "-", "-", "26")),
    PaperObserver("Ob3", "normal", ("12", "8", "6", "5", "3", "5", "7", "-", "-", "26")),
    PaperObserver("Ob4", "normal", ("12", "8", "6", "5", "3", "5", "7", "-", "-", "26")),
    PaperObserver("Ob5", "normal", ("12", "8", "6", "5", "3", "5", "7", "-", "-", "26")),
    PaperObserver("Ob6", "normal", ("12", "8", "6", "5", "3", "5", "7", "-", "-", "26")),
    PaperObserver("Ob7", "protan", ("12", "3", "5", "2", "-", "-", "-", "5", "2", "6")),
    PaperObserver("Ob8", "protan", ("12", "3", "5", "2", "5", "-", "-", "5", "8", "6")),
    PaperObserver("Ob9", "deutan", ("12", "3", "5", "2", "-", "-", "-", "5", "8", "2")),
    PaperObserver("Ob10", "protan", ("12", "3", "5", "2", "5", "-", "-", "5", "8", "6")),
)
"""Table 6, the ten real observers' answers in the virtual test."""
