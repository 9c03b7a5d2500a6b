"""The paper's Ishihara experiment reproduced: Table 5 (dot colours) and Table 6 (readings).

Table 5
    The ten dot colours of the paper's plate 3 (P1–P10, reflectances whose D65
    chromaticity and luminance factor are the paper's "calculated" values),
    and the designed colours of our generated plate 3, calculated under CIE D65
    and measured end to end: level-2 texture → engine → simulated headset →
    CS-2000 emulator (over a pty, through the real driver) → measured XYZ, with
    the display model fitted to a calibration session of that headset measured
    the same way just before. CIEDE2000 in CIELAB whose white is ``XYZ_t`` of
    the perfect diffuser under D65 (``k · Y_white``); Y columns on the paper's
    scale (perfect diffuser = 100).
Table 6
    The simulated normal, protan and deutan observers read the 10-plate set
    (:func:`~workbench.ishihara.plates.generate_plate_set`) under each
    :data:`TABLE6_CONDITIONS`: the real plates (``physical``) and the HMD at
    levels 1 and 2, under CIE D65 and under the two-peak D65 metamer. A virtual
    test is *faithful* under a source when every observer reads on the HMD
    what they read on the real plates under that source; it *misleads* when
    it does not, since it then tells the user something about the test under
    that light that the real test would not.

References
----------
Díaz-Barrancas et al. (2020), §3.2–3.3, Tables 5 and 6.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.colorimetry import DEFAULT_K, delta_E2000
from workbench.colour_management import engine_render, level2_texture
from workbench.illuminants import get_illuminant
from workbench.ishihara.examination import take_test
from workbench.ishihara.hmd import DEFAULT_HEADSET_SEED, HeadsetRig, calibrated_headset
from workbench.ishihara.observers import parse_observer
from workbench.ishihara.palette import XYZ_to_xyY, design_palette
from workbench.ishihara.paper import PAPER_TABLE5, PAPER_TABLE5_MEAN_DE00, PAPER_TABLE6_REFERENCE
from workbench.ishihara.plates import DEFAULT_PLATE_SIZE, DEFAULT_SEED, generate_plate_set
from workbench.ishihara.viewing import Viewing

__all__ = [
    "TABLE6_CONDITIONS",
    "TABLE6_OBSERVERS",
    "Table5Row",
    "Table5",
    "table5",
    "Table6Row",
    "ConditionFinding",
    "Table6",
    "table6",
]


@dataclass(frozen=True)
class Table5Row:
    """One dot colour calculated and measured.

    Attributes
    ----------
    dot : str
        ``"P1"`` … or a palette colour name.
    name : str
    calculated : (float, float, float)
        CIE 1931 x, y, Y under D65 (perfect diffuser Y = 100).
    measured : (float, float, float)
        The same, measured end to end (Y relative to ``XYZ_t`` of the perfect
        diffuser, scaled to 100).
    dE00 : float
        CIEDE2000 between them (white: the perfect diffuser under D65).
    dac : (int, int, int)
        What the engine sent to the headset.
    paper_calculated, paper_measured : (float, float, float) or None
        The paper's Table 5 values (None for our designed colours).
    paper_dE00 : float or None
    """

    dot: str
    name: str
    calculated: tuple
    measured: tuple
    dE00: float
    dac: tuple
    paper_calculated: tuple | None = None
    paper_measured: tuple | None = None
    paper_dE00: float | None = None


@dataclass(frozen=True)
class Table5:
    """Table 5 reproduced.

    Attributes
    ----------
    rows : tuple of Table5Row
        P1–P10, the paper's plate-3 colours.
    plate3_rows : tuple of Table5Row
        The designed colours of our generated plate 3.
    mean_dE00 : float
        Mean CIEDE2000 over :attr:`rows` (the paper: :attr:`paper_mean_dE00`).
    plate3_mean_dE00 : float
    paper_mean_dE00 : float
    display : str
        The fitted display model.
    headset : str
    white_XYZ : (float, float, float)
        ``XYZ_t`` of the perfect diffuser under D65 (cd/m²).
    """

    rows: tuple
    plate3_rows: tuple
    mean_dE00: float
    plate3_mean_dE00: float
    paper_mean_dE00: float
    display: str
    headset: str
    white_XYZ: tuple

    def to_json(self) -> dict:
        def row(r):
            return {k: (list(v) if isinstance(v, tuple) else v) for k, v in r.__dict__.items()}
        return {"rows": [row(r) for r in self.rows],
                "plate3_rows": [row(r) for r in self.plate3_rows],
                "mean_dE00": self.mean_dE00, "plate3_mean_dE00": self.plate3_mean_dE00,
                "paper_mean_dE00": self.paper_mean_dE00, "display": self.display,
                "headset": self.headset, "white_XYZ": list(self.white_XYZ),
                "dE00_reference_white": "XYZ_t of the perfect diffuser under CIE D65 "
                                        "(k * Y_white of the headset)"}


def _rounded(values, digits=(4, 4, 2)) -> tuple:
    return tuple(round(float(v), d) for v, d in zip(values, digits))


def table5(seed: int = DEFAULT_HEADSET_SEED, plan: str = "paper", k: float = DEFAULT_K) -> Table5:
    """Measure the plate-3 dot colours end to end on a freshly calibrated simulated headset.

    Parameters
    ----------
    seed : int
        Headset unit and instrument noise.
    plan : str
        Calibration plan (``"paper"``: 214 patches, ~1 s with the emulator at no wait).
    k : float
        Scene-white factor.
    """
    palette = design_palette()
    plates = generate_plate_set(DEFAULT_PLATE_SIZE, DEFAULT_SEED)
    plate3 = plates[2].colour_names
    names = [d.dot for d in PAPER_TABLE5] + list(plate3)
    d65 = get_illuminant("cie-d65").sd
    with HeadsetRig(seed) as rig:
        hmd = rig.calibrate(plan)
        texture = level2_texture(palette.reflectances(names), d65, hmd.display, k=k)
        dac = engine_render(texture.rgb8, texture.light.rgb8)
        measured = np.array([rig.measure(v).XYZ for v in dac])
    white = texture.light.XYZ
    dE = delta_E2000(measured, texture.XYZ_t, white)
    scale = np.array([1.0, 1.0, 100.0 / white[1]])
    calculated_xyY = XYZ_to_xyY(texture.XYZ_t) * scale
    measured_xyY = XYZ_to_xyY(measured) * scale
    rows = []
    paper = {d.dot: d for d in PAPER_TABLE5}
    for i, name in enumerate(names):
        dot = paper.get(name)
        rows.append(Table5Row(
            dot=name, name=dot.name if dot else palette[name].role,
            calculated=_rounded(calculated_xyY[i]), measured=_rounded(measured_xyY[i]),
            dE00=round(float(dE[i]), 3), dac=tuple(int(v) for v in dac[i]),
            paper_calculated=dot.calculated_xyY if dot else None,
            paper_measured=dot.measured_xyY if dot else None,
            paper_dE00=dot.dE00 if dot else None))
    count = len(PAPER_TABLE5)
    return Table5(rows=tuple(rows[:count]), plate3_rows=tuple(rows[count:]),
                  mean_dE00=float(np.mean(dE[:count])),
                  plate3_mean_dE00=float(np.mean(dE[count:])),
                  paper_mean_dE00=PAPER_TABLE5_MEAN_DE00, display=hmd.display.describe(),
                  headset=hmd.headset.describe(), white_XYZ=tuple(float(v) for v in white))


TABLE6_CONDITIONS = (
    Viewing("cie-d65", "physical"),
    Viewing("cie-d65", "level-2"),
    Viewing("cie-d65", "level-1"),
    Viewing("d65-two-peak", "physical"),
    Viewing("d65-two-peak", "level-1"),
    Viewing("d65-two-peak", "level-2"),
)
"""Viewing conditions of :func:`table6`, each HMD one after the real plate under its source."""

TABLE6_OBSERVERS = ("normal", "protan", "deutan")


@dataclass(frozen=True)
class Table6Row:
    """One observer under one condition.

    Attributes
    ----------
    observer : str
    viewing : Viewing
    answers : tuple of str
    classification : str
    reference : tuple of str
        The paper's reference answers for this observer type (Ref1–Ref3).
    physical : tuple of str
        What the same observer reads on the real plates under the same source.
    physical_classification : str
        And how the real plates classify them.
    contrasts_jnd : tuple of float
        Figure–ground colour difference the observer saw on each plate.
    """

    observer: str
    viewing: Viewing
    answers: tuple
    classification: str
    reference: tuple
    physical: tuple
    physical_classification: str
    contrasts_jnd: tuple

    @property
    def matches_reference(self) -> bool:
        return self.answers == self.reference

    @property
    def matches_physical(self) -> bool:
        return self.answers == self.physical

    @property
    def correctly_classified(self) -> bool:
        return self.classification == self.observer.partition(":")[0]

    @property
    def changed_plates(self) -> tuple:
        """Plate numbers (1-based) read differently from the real plates under the same source."""
        return tuple(i + 1 for i, (a, p) in enumerate(zip(self.answers, self.physical)) if a != p)


@dataclass(frozen=True)
class ConditionFinding:
    """What one viewing condition does to the test.

    Attributes
    ----------
    viewing : Viewing
    faithful : bool
        Every observer reads what they read on the real plates under the source.
    misleads : bool
        Not faithful.
    changed_plates : dict of str to tuple of int
        Per observer, the plates read differently from the real plates.
    misclassified : dict of str to str
        Observers classified as something else than they are, and as what.
    summary : str
    """

    viewing: Viewing
    faithful: bool
    misleads: bool
    changed_plates: dict
    misclassified: dict
    summary: str


@dataclass(frozen=True)
class Table6:
    """Table 6 reproduced with simulated observers.

    Attributes
    ----------
    rows : tuple of Table6Row
    findings : tuple of ConditionFinding
        One per condition.
    plate_size : int
    """

    rows: tuple
    findings: tuple
    plate_size: int

    def finding(self, illuminant: str, path: str) -> ConditionFinding:
        """The finding of the condition (``illuminant``, ``path``)."""
        for f in self.findings:
            if f.viewing.illuminant == illuminant and f.viewing.path == path:
                return f
        raise KeyError((illuminant, path))

    def rows_for(self, viewing: Viewing) -> tuple:
        return tuple(r for r in self.rows if r.viewing == viewing)

    def to_json(self) -> dict:
        return {
            "plate_size_px": self.plate_size,
            "reference": {r.qualification: list(r.answers) for r in PAPER_TABLE6_REFERENCE},
            "conditions": [{
                "illuminant": f.viewing.illuminant, "path": f.viewing.path,
                "faithful": f.faithful, "misleads": f.misleads,
                "changed_plates": {k: list(v) for k, v in f.changed_plates.items()},
                "misclassified": f.misclassified, "summary": f.summary,
                "observers": [{"observer": r.observer, "answers": list(r.answers),
                               "classification": r.classification,
                               "matches_reference": r.matches_reference,
                               "matches_physical": r.matches_physical,
                               "contrasts_jnd": [round(c, 2) for c in r.contrasts_jnd]}
                              for r in self.rows_for(f.viewing)],
            } for f in self.findings],
        }


def _finding(viewing: Viewing, rows) -> ConditionFinding:
    changed = {r.observer: r.changed_plates for r in rows if r.changed_plates}
    misclassified = {r.observer: r.classification for r in rows if not r.correctly_classified}
    faithful = not changed
    where = viewing.describe()
    if viewing.path == "physical":
        verdicts = ", ".join(f"{r.observer} → {r.classification}" for r in rows)
        summary = f"{where}: {verdicts}."
    elif faithful:
        summary = (f"{where}: every observer reads what the real plates show under this source "
                   f"— faithful" + (f"; the real test itself misclassifies "
                                    f"{', '.join(f'{o} as {c}' for o, c in misclassified.items())}"
                                    if misclassified else "") + ".")
    else:
        changes = "; ".join(f"{o} on plates {', '.join(map(str, p))}" for o, p in changed.items())
        verdicts = ", ".join(f"{r.observer} → {r.classification} (real plates: "
                             f"{r.physical_classification})" for r in rows)
        real_wrong = {r.observer: r.physical_classification for r in rows
                      if r.physical_classification != r.observer.partition(":")[0]}
        consequence = ""
        if real_wrong != misclassified:
            def listed(wrong):
                return ", ".join(f"{o} as {c}" for o, c in wrong.items()) or "nobody"
            consequence = (f" The real test under this source misclassifies {listed(real_wrong)}; "
                           f"the virtual one misclassifies {listed(misclassified)}.")
        summary = (f"{where} misleads: answers differ from the real plates under this source "
                   f"({changes}); verdicts {verdicts}.{consequence}")
    return ConditionFinding(viewing=viewing, faithful=faithful, misleads=not faithful,
                            changed_plates=changed, misclassified=misclassified, summary=summary)


def table6(size: int = DEFAULT_PLATE_SIZE, seed: int = DEFAULT_SEED,
           headset_seed: int = DEFAULT_HEADSET_SEED, conditions=TABLE6_CONDITIONS,
           observers=TABLE6_OBSERVERS) -> Table6:
    """The simulated observers take the 10-plate test under each condition.

    Parameters
    ----------
    size : int
        Plate image size (pixels).
    seed : int
        Base seed of the plate set.
    headset_seed : int
        Seed of the simulated headset (calibrated once, through the CS-2000 emulator).
    conditions : sequence of Viewing
        Each HMD condition is compared with the ``physical`` one of its source
        (computed even when not listed).
    observers : sequence of str
        Observer names (:func:`~workbench.ishihara.observers.parse_observer`).
    """
    plates = generate_plate_set(size, seed)
    hmd = calibrated_headset(headset_seed)
    reference = {r.qualification: tuple(r.answers) for r in PAPER_TABLE6_REFERENCE}
    cache = {}

    def examine(observer, viewing):
        key = (observer, viewing)
        if key not in cache:
            cache[key] = take_test(plates, parse_observer(observer), viewing, hmd)
        return cache[key]

    rows = []
    for viewing in conditions:
        physical = Viewing(viewing.illuminant, "physical", viewing.k)
        for observer in observers:
            exam = examine(observer, viewing)
            real = examine(observer, physical)
            row = Table6Row(observer=observer, viewing=viewing, answers=exam.answers,
                            classification=exam.classification,
                            reference=reference.get(observer.partition(":")[0], ()),
                            physical=real.answers, physical_classification=real.classification,
                            contrasts_jnd=tuple(r.contrast_jnd for r in exam.readings))
            rows.append(row)
    findings = tuple(_finding(v, [r for r in rows if r.viewing == v]) for v in conditions)
    return Table6(rows=tuple(rows), findings=findings, plate_size=size)
