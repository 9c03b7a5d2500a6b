"""The paper's Ishihara experiment reproduced: Table 5 (dot colours) and Table 6 (readings).

Table 5
    The dot colours of plate 3, calculated under CIE D65 and measured end to
    end, as the paper did: the plate's hyperspectral cube (sampled as the
    paper's, 380–780 nm at 4 nm) → a spectral basis fitted to it
    (:func:`workbench.hyperspectral.fit_cube_basis`), the cube encoded in
    float16 coefficients → the level-2 texture relit for D65 by the real-time
    path (:func:`~workbench.hyperspectral.plan_relight`,
    :func:`~workbench.hyperspectral.relight_texels`) → the texel at a dot's
    centre, rendered by the engine under the level-1 light
    (:func:`~workbench.colour_management.engine_render`) → shown full field
    on the simulated headset → measured by the CS-2000 emulator over a pty,
    through the real driver → measured XYZ. "Calculated" is ``XYZ_t`` of the
    dot's reflectance at the full 1 nm sampling
    (:func:`~workbench.colour_management.level2_texture`), whose texel is also
    the reference each basis-path texel is checked against. Two plates: our
    plate 3 recoloured in the paper's own ten colours
    (:func:`~workbench.ishihara.plates.paper_coloured_plate`; rows P1–P10,
    whose D65 chromaticity and luminance factor are the paper's "calculated"
    values) and our designed plate 3 (one row per designed colour); for each
    colour, its largest dot.

    The headset is the realistic default rig
    (:data:`~workbench.ishihara.hmd.REALISTIC_HEADSET_EFFECTS`: Table 1's
    black, 5 % channel interaction), calibrated with the paper's plan and
    diagnosed; the table is measured twice, once with the paper's baseline
    display model and once with the diagnosis's extended model (the one the
    workbench uses), so it shows what the diagnosis buys.

    CIEDE2000 in CIELAB whose white is ``XYZ_t`` of the perfect diffuser under
    D65 (``k · Y_white``); Y columns on the paper's scale (perfect diffuser = 100).
Table 6
    The simulated observers read the 10-plate set
    (:func:`~workbench.ishihara.plates.generate_plate_set`) under each
    :data:`TABLE6_CONDITIONS`: the real plates (``physical``) and the HMD at
    levels 1 and 2, under CIE D65 and under the two-peak D65 metamer. A virtual
    test is *faithful* under a source when every observer reads on the HMD
    what they read on the real plates under that source; it *misleads* when
    it does not, since it then tells the user something about the test under
    that light that the real test would not. Besides the observers built on
    CIE 1931 (which level 2 matches by construction), :data:`TABLE6_OBSERVERS`
    holds Stockman & Sharpe (2000) observers, whose cones are not a linear
    function of CIE 1931 XYZ: for them level 2 is a metamer, not a match
    (observer metamerism), and each row says how far the dots moved
    (:attr:`Table6Row.dot_shift_jnd`) and how much a figure–ground contrast
    changed (:attr:`Table6Row.max_contrast_change_jnd`). What we find: their
    dots move ~3–4 JND on the HMD (the CIE 1931 observers': 0.1–0.4, from
    8-bit quantisation and the display model), but figure and ground move
    together, so contrasts change by under 2 JND and the normal observer and
    the dichromats read the real plates' answers under both sources. An
    anomalous trichromat whose contrast on some plate lies within a JND or two
    of the legibility threshold can read that plate differently — the CIE 1931
    ones too, from quantisation, but the Stockman & Sharpe ones by more.

References
----------
Díaz-Barrancas et al. (2020), §3.2–3.3, Tables 5 and 6.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from colour import XYZ_to_xyY

from workbench.colorimetry import DEFAULT_K, WORKING_WAVELENGTHS, delta_E2000
from workbench.colour_management import engine_render, level2_texture
from workbench.hyperspectral import (
    PAPER_CUBE_WAVELENGTHS,
    BasisCube,
    ReflectanceCube,
    encode_cube,
    fit_cube_basis,
    plan_relight,
    relight_texels,
    resample_cube,
)
from workbench.illuminants import get_illuminant
from workbench.ishihara.examination import take_test
from workbench.ishihara.hmd import (
    DEFAULT_HEADSET_SEED,
    REALISTIC_HEADSET_EFFECTS,
    HeadsetRig,
    calibrated_headset,
)
from workbench.ishihara.observers import parse_observer
from workbench.ishihara.palette import design_palette
from workbench.ishihara.paper import PAPER_TABLE5, PAPER_TABLE5_MEAN_DE00, PAPER_TABLE6_REFERENCE
from workbench.ishihara.plates import (
    DEFAULT_PLATE_SIZE,
    DEFAULT_SEED,
    Plate,
    generate_plate_set,
    paper_coloured_plate,
)
from workbench.ishihara.viewing import Viewing, dot_radiance

__all__ = [
    "TABLE5_PLATE",
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

TABLE5_PLATE = 3
"""The plate of the paper's set whose dots Table 5 measures."""


@dataclass(frozen=True)
class Table5Row:
    """One dot colour calculated and measured, with both display models.

    Attributes
    ----------
    dot : str
        ``"P1"`` … or a designed palette colour name.
    name : str
    calculated : (float, float, float)
        CIE 1931 x, y, Y under D65 of the dot's reflectance, full band
        (perfect diffuser Y = 100).
    measured : (float, float, float)
        The same, measured end to end with the extended (diagnosed) model (Y
        relative to ``XYZ_t`` of the perfect diffuser, scaled to 100).
    dE00 : float
        CIEDE2000 between them (white: the perfect diffuser under D65).
    dac : (int, int, int)
        What the engine sent to the headset.
    baseline_measured, baseline_dE00, baseline_dac
        The same with the paper's baseline model.
    texel : (int, int, int)
        The level-2 texel the basis path wrote at the dot's centre (extended model).
    full_band_texel : (int, int, int)
        The full-band reference texel (:func:`~workbench.colour_management.level2_texture`).
    texel_difference : int
        Largest ``|basis − full band|`` texel difference, counts, over both models.
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
    baseline_measured: tuple
    baseline_dE00: float
    baseline_dac: tuple
    texel: tuple
    full_band_texel: tuple
    texel_difference: int
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
    mean_dE00, baseline_mean_dE00 : float
        Mean CIEDE2000 over :attr:`rows` with the extended and the baseline
        model (the paper: :attr:`paper_mean_dE00`).
    plate3_mean_dE00, plate3_baseline_mean_dE00 : float
    paper_mean_dE00 : float
    display : str
        The extended model (what the workbench uses).
    baseline_display : str
        The paper's model fitted to the same calibration.
    findings : tuple of (str, str)
        ``(effect id, evidence)`` of what the diagnosis found, most important first.
    headset : str
    white_XYZ : (float, float, float)
        ``XYZ_t`` of the perfect diffuser under D65 (cd/m²).
    basis_components : (int, int)
        K of the bases fitted to the paper-coloured and the designed plate's cube.
    max_texel_difference : int
        Largest ``|basis path − full band|`` texel difference over every row and
        both models (counts).
    """

    rows: tuple
    plate3_rows: tuple
    mean_dE00: float
    baseline_mean_dE00: float
    plate3_mean_dE00: float
    plate3_baseline_mean_dE00: float
    paper_mean_dE00: float
    display: str
    baseline_display: str
    findings: tuple
    headset: str
    white_XYZ: tuple
    basis_components: tuple
    max_texel_difference: int

    @property
    def gain_pct(self) -> float:
        """How much the extended model lowers the mean ΔE00 of P1–P10, in % of the baseline's."""
        return 100.0 * (self.baseline_mean_dE00 - self.mean_dE00) / self.baseline_mean_dE00

    def to_json(self) -> dict:
        def row(r):
            return {k: (list(v) if isinstance(v, tuple) else v) for k, v in r.__dict__.items()}
        return {"rows": [row(r) for r in self.rows],
                "plate3_rows": [row(r) for r in self.plate3_rows],
                "mean_dE00": self.mean_dE00, "baseline_mean_dE00": self.baseline_mean_dE00,
                "gain_pct": self.gain_pct,
                "plate3_mean_dE00": self.plate3_mean_dE00,
                "plate3_baseline_mean_dE00": self.plate3_baseline_mean_dE00,
                "paper_mean_dE00": self.paper_mean_dE00, "display": self.display,
                "baseline_display": self.baseline_display,
                "findings": [{"effect": e, "evidence": v} for e, v in self.findings],
                "headset": self.headset, "white_XYZ": list(self.white_XYZ),
                "basis_components": list(self.basis_components),
                "max_texel_difference": self.max_texel_difference,
                "path": "plate cube (380-780 nm, 4 nm) → spectral basis (float16) → "
                        "relight_texels (D65) → texel at the dot's centre → engine_render → "
                        "simulated headset → CS-2000 emulator",
                "dE00_reference_white": "XYZ_t of the perfect diffuser under CIE D65 "
                                        "(k * Y_white of the headset)"}


def _rounded(values, digits=(4, 4, 2)) -> tuple:
    return tuple(round(float(v), d) for v, d in zip(values, digits))


def _largest_dots(plate: Plate, names) -> np.ndarray:
    """Index of the largest dot of each colour in ``names``."""
    colours = np.asarray(plate.dot_colours, dtype=object)
    areas = plate.layout.areas
    chosen = []
    for name in names:
        members = np.flatnonzero(colours == name)
        chosen.append(int(members[np.argmax(areas[members])]))
    return np.array(chosen)


def _centre_pixels(plate: Plate, dots: np.ndarray) -> tuple:
    """(rows, columns) of the pixel of each dot nearest its centre."""
    labels = plate.layout.labels
    rows, cols = [], []
    for dot in dots:
        pixels = np.argwhere(labels == dot + 1)              # (row, column)
        x, y = plate.layout.centres[dot]
        nearest = pixels[np.argmin((pixels[:, 0] - y) ** 2 + (pixels[:, 1] - x) ** 2)]
        rows.append(int(nearest[0]))
        cols.append(int(nearest[1]))
    return np.array(rows), np.array(cols)


@dataclass(frozen=True, eq=False)
class _EncodedPlate:
    """A plate's cube compressed to its spectral basis, and the dots Table 5 reads."""

    plate: Plate
    names: tuple
    dots: np.ndarray
    pixels: tuple            # (rows, columns) of each dot's centre pixel
    texture: BasisCube


@lru_cache(maxsize=2)
def _table5_plates(k: float) -> tuple:
    """Plate 3 in the paper's colours and as designed, each cube fitted and encoded (cached)."""
    palette = design_palette()
    designed = generate_plate_set(DEFAULT_PLATE_SIZE, DEFAULT_SEED)[TABLE5_PLATE - 1]
    encoded = []
    paper_names = tuple(d.dot for d in PAPER_TABLE5)
    for plate, names in ((paper_coloured_plate(designed, palette), paper_names),
                         (designed, designed.colour_names)):
        # sampled as the paper's cubes: 380–780 nm at 4 nm, 101 bands
        cube = resample_cube(ReflectanceCube(plate.cube(), WORKING_WAVELENGTHS,
                                             source=f"Ishihara plate {plate.spec.number} "
                                                    f"({plate.size} px)"),
                             PAPER_CUBE_WAVELENGTHS)
        texture = encode_cube(cube, fit_cube_basis(cube, k=k))
        dots = _largest_dots(plate, names)
        encoded.append(_EncodedPlate(plate, tuple(names), dots, _centre_pixels(plate, dots),
                                     texture))
    return tuple(encoded)


@dataclass(frozen=True)
class _PlateLevel2:
    """Level-2 texels of the Table 5 dots of a plate by the basis path, per display model."""

    components: int
    texels: dict          # model key → (N, 3) basis-path texels
    full_band: dict       # model key → Level2Texture of the dots' reflectances
    lights: dict          # model key → light rgb8


def _level2_by_basis(encoded: _EncodedPlate, illuminant, models: dict, k: float) -> _PlateLevel2:
    """The encoded cube relit for ``illuminant`` per model; the texel at each dot's centre."""
    reflectances = encoded.plate.dot_reflectances[encoded.dots]
    rows, cols = encoded.pixels
    texels, full_band, lights = {}, {}, {}
    for key, display in models.items():
        relit = plan_relight(encoded.texture.basis, illuminant, display, k=k)
        texels[key] = relight_texels(encoded.texture, relit)[rows, cols].astype(int)
        full_band[key] = level2_texture(reflectances, illuminant.sd, display, k=k)
        lights[key] = relit.light.rgb8
        if not np.array_equal(relit.light.rgb8, full_band[key].light.rgb8):
            raise RuntimeError(f"the relight plan's light {relit.light.rgb8} differs from the "
                               f"level-2 texture's {full_band[key].light.rgb8} ({key} model)")
    return _PlateLevel2(components=encoded.texture.basis.components, texels=texels,
                        full_band=full_band, lights=lights)


def table5(seed: int = DEFAULT_HEADSET_SEED, plan: str = "paper", k: float = DEFAULT_K,
           effects=REALISTIC_HEADSET_EFFECTS) -> Table5:
    """Measure the plate-3 dot colours end to end on the calibrated simulated headset.

    Parameters
    ----------
    seed : int
        Headset unit and calibration noise (the Table 5 measurements use
        ``seed + 1`` for the instrument noise, so they do not depend on what
        was measured before).
    plan : str
        Calibration plan (``"paper"``: 214 patches, ~1.5 s with the emulator at no wait).
    k : float
        Scene-white factor.
    effects : dict or sequence of (str, float)
        Headset effects (default :data:`~workbench.ishihara.hmd.REALISTIC_HEADSET_EFFECTS`;
        ``()``: a clean headset, which is exactly the baseline model).

    Returns
    -------
    Table5
        With the baseline and the extended model. The calibration
        (:func:`~workbench.ishihara.hmd.calibrated_headset`) and the plates'
        compressed cubes are made once per process; each call relights and
        measures again.
    """
    palette = design_palette()
    encoded = _table5_plates(float(k))
    paper_names, designed_names = list(encoded[0].names), list(encoded[1].names)
    hmd = calibrated_headset(seed, plan, effects)
    models = {"extended": hmd.display, "baseline": hmd.baseline}
    d65 = get_illuminant("cie-d65")
    parts = [_level2_by_basis(e, d65, models, k) for e in encoded]
    dac = {key: np.vstack([engine_render(p.texels[key], p.lights[key]) for p in parts])
           for key in models}
    with HeadsetRig(seed, headset=hmd.headset, noise_seed=seed + 1) as rig:
        measured = {key: np.array([rig.measure(v).XYZ for v in dac[key]]) for key in models}
    XYZ_t = np.vstack([p.full_band["extended"].XYZ_t for p in parts])
    white = parts[0].full_band["extended"].light.XYZ
    dE = {key: delta_E2000(measured[key], XYZ_t, white) for key in models}
    scale = np.array([1.0, 1.0, 100.0 / white[1]])
    calculated_xyY = XYZ_to_xyY(XYZ_t) * scale
    measured_xyY = {key: XYZ_to_xyY(measured[key]) * scale for key in models}
    texels = np.vstack([p.texels["extended"] for p in parts])
    full_band = np.vstack([p.full_band["extended"].rgb8 for p in parts])
    difference = np.max([np.abs(np.vstack([p.texels[key] for p in parts])
                                - np.vstack([p.full_band[key].rgb8 for p in parts]).astype(int))
                         for key in models], axis=0).max(axis=1)
    paper = {d.dot: d for d in PAPER_TABLE5}
    rows = []
    for i, name in enumerate(paper_names + designed_names):
        dot = paper.get(name) if i < len(paper_names) else None
        rows.append(Table5Row(
            dot=name, name=dot.name if dot else palette[name].role,
            calculated=_rounded(calculated_xyY[i]), measured=_rounded(measured_xyY["extended"][i]),
            dE00=round(float(dE["extended"][i]), 3),
            dac=tuple(int(v) for v in dac["extended"][i]),
            baseline_measured=_rounded(measured_xyY["baseline"][i]),
            baseline_dE00=round(float(dE["baseline"][i]), 3),
            baseline_dac=tuple(int(v) for v in dac["baseline"][i]),
            texel=tuple(int(v) for v in texels[i]),
            full_band_texel=tuple(int(v) for v in full_band[i]),
            texel_difference=int(difference[i]),
            paper_calculated=dot.calculated_xyY if dot else None,
            paper_measured=dot.measured_xyY if dot else None,
            paper_dE00=dot.dE00 if dot else None))
    count = len(paper_names)
    return Table5(rows=tuple(rows[:count]), plate3_rows=tuple(rows[count:]),
                  mean_dE00=float(np.mean(dE["extended"][:count])),
                  baseline_mean_dE00=float(np.mean(dE["baseline"][:count])),
                  plate3_mean_dE00=float(np.mean(dE["extended"][count:])),
                  plate3_baseline_mean_dE00=float(np.mean(dE["baseline"][count:])),
                  paper_mean_dE00=PAPER_TABLE5_MEAN_DE00, display=hmd.display.describe(),
                  baseline_display=hmd.baseline.describe(),
                  findings=tuple((r.effect, r.evidence) for r in hmd.diagnosis.findings),
                  headset=hmd.headset.describe(), white_XYZ=tuple(float(v) for v in white),
                  basis_components=tuple(p.components for p in parts),
                  max_texel_difference=int(difference.max()))


TABLE6_CONDITIONS = (
    Viewing("cie-d65", "physical"),
    Viewing("cie-d65", "level-2"),
    Viewing("cie-d65", "level-1"),
    Viewing("d65-two-peak", "physical"),
    Viewing("d65-two-peak", "level-1"),
    Viewing("d65-two-peak", "level-2"),
)
"""Viewing conditions of :func:`table6`, each HMD one after the real plate under its source."""

TABLE6_OBSERVERS = ("normal", "protan", "deutan", "normal@ss2000", "protan@ss2000", "deutan@ss2000")
"""Observers of :func:`table6`: Smith & Pokorny (linear in CIE 1931) and Stockman & Sharpe 2000."""


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
    physical_contrasts_jnd : tuple of float
        The same on the real plates under the same source.
    dot_shift_jnd : float
        Median, over every dot of the set, of the colour difference (JND, this
        observer's) between the dot as shown and the same dot on the real
        plate under the same source: 0 on the real plates; at level 2, only
        quantisation and the display model's error for the CIE 1931-based
        observers, and observer metamerism on top for the others.
    deficiency : str
        The observer's deficiency (``"normal"``, ``"protan"`` …).
    """

    observer: str
    viewing: Viewing
    answers: tuple
    classification: str
    reference: tuple
    physical: tuple
    physical_classification: str
    contrasts_jnd: tuple
    physical_contrasts_jnd: tuple = ()
    dot_shift_jnd: float = 0.0
    deficiency: str = ""

    @property
    def matches_reference(self) -> bool:
        return self.answers == self.reference

    @property
    def matches_physical(self) -> bool:
        return self.answers == self.physical

    @property
    def correctly_classified(self) -> bool:
        return self.classification == (self.deficiency or self.observer.partition(":")[0])

    @property
    def max_contrast_change_jnd(self) -> float:
        """Largest ``|figure–ground contrast here − on the real plates|`` over the plates (JND)."""
        if not self.physical_contrasts_jnd:
            return 0.0
        return float(np.max(np.abs(np.subtract(self.contrasts_jnd, self.physical_contrasts_jnd))))

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
                               "contrasts_jnd": [round(c, 2) for c in r.contrasts_jnd],
                               "max_contrast_change_jnd": round(r.max_contrast_change_jnd, 2),
                               "dot_shift_jnd": round(r.dot_shift_jnd, 2)}
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
                      if r.physical_classification != r.deficiency}
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
    exams, radiances = {}, {}

    def examine(observer, viewing):
        key = (observer, viewing)
        if key not in exams:
            exams[key] = take_test(plates, parse_observer(observer), viewing, hmd)
        return exams[key]

    def radiance(viewing):
        if viewing not in radiances:
            radiances[viewing] = [dot_radiance(p.dot_reflectances, viewing, hmd) for p in plates]
        return radiances[viewing]

    def dot_shift(observer, viewing, physical) -> float:
        if viewing == physical:
            return 0.0
        seen = parse_observer(observer)
        shifts = [seen.colour_difference(shown, real)
                  for shown, real in zip(radiance(viewing), radiance(physical))]
        return float(np.median(np.concatenate(shifts)))

    rows = []
    for viewing in conditions:
        physical = Viewing(viewing.illuminant, "physical", viewing.k)
        for observer in observers:
            exam = examine(observer, viewing)
            real = examine(observer, physical)
            deficiency = parse_observer(observer).deficiency
            row = Table6Row(observer=observer, viewing=viewing, answers=exam.answers,
                            classification=exam.classification,
                            reference=reference.get(deficiency, ()),
                            physical=real.answers, physical_classification=real.classification,
                            contrasts_jnd=tuple(r.contrast_jnd for r in exam.readings),
                            physical_contrasts_jnd=tuple(r.contrast_jnd for r in real.readings),
                            dot_shift_jnd=dot_shift(observer, viewing, physical),
                            deficiency=deficiency)
            rows.append(row)
    findings = tuple(_finding(v, [r for r in rows if r.viewing == v]) for v in conditions)
    return Table6(rows=tuple(rows), findings=findings, plate_size=size)
