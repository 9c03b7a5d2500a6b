"""The virtual Ishihara test: hyperspectral plates and simulated observers (no Qt).

- :mod:`.cones` — Smith & Pokorny (CIE 1931) and Stockman & Sharpe (2000)
  cone fundamentals, photopigment shifts, copunctal points.
- :mod:`.palette` — dot reflectances designed on protan/deutan confusion lines,
  starting from the paper's Table 5 colours (spectral upsampling, Otsu 2018).
- :mod:`.glyphs`, :mod:`.packing`, :mod:`.plates` — digit font, packed dots,
  the plate types and the paper's 10-plate set; ``.npz`` files and previews.
- :mod:`.observers` — normal, anomalous and dichromatic observers in a
  receptor-noise colour space, on either set of fundamentals (Machado et al.
  2009's blend on CIE 1931; a real pigment shift on Stockman & Sharpe).
- :mod:`.reading`, :mod:`.scoring`, :mod:`.examination` — reading a plate,
  Ishihara's rules, taking the test.
- :mod:`.hmd`, :mod:`.viewing` — the simulated HMD (realistic: black and
  channel interaction) calibrated through the CS-2000 emulator and diagnosed;
  the real plate vs the HMD at levels 1 and 2.
- :mod:`.experiment` — the paper's Tables 5 and 6.

A tiny example::

    from workbench.ishihara import generate_plate_set, parse_observer, take_test, Viewing
    exam = take_test(generate_plate_set(), parse_observer("deutan"), Viewing("cie-d65", "level-2"))
    exam.answers, exam.classification
"""

from workbench.ishihara.cones import (
    cone_fundamental_shifted_StockmanSharpe2000,
    cone_fundamentals_Smith_Pokorny1975,
    cone_fundamentals_StockmanSharpe2000,
    confusion_line_residual,
    copunctal_point,
)
from workbench.ishihara.examination import Examination, read_plate, take_test
from workbench.ishihara.experiment import (
    TABLE5_PLATE,
    TABLE6_CONDITIONS,
    TABLE6_OBSERVERS,
    ConditionFinding,
    Table5,
    Table5Row,
    Table6,
    Table6Row,
    table5,
    table6,
)
from workbench.ishihara.hmd import (
    REALISTIC_HEADSET_EFFECTS,
    CalibratedHeadset,
    HeadsetRig,
    calibrated_headset,
)
from workbench.ishihara.observers import (
    OBSERVER_DEFICIENCIES,
    OBSERVER_FUNDAMENTALS,
    Observer,
    parse_observer,
    simulated_observer,
)
from workbench.ishihara.palette import (
    SPECTRAL_UPSAMPLING_METHODS,
    Palette,
    PaletteColour,
    XYZ_to_reflectance,
    design_palette,
    paper_dot_colours,
)
from workbench.ishihara.paper import PAPER_TABLE5, PAPER_TABLE6_OBSERVERS, PAPER_TABLE6_REFERENCE
from workbench.ishihara.plates import (
    DEFAULT_PLATE_SIZE,
    DEFAULT_SEED,
    PLATE_TYPES,
    Plate,
    PlateSpec,
    generate_plate,
    generate_plate_set,
    load_plate,
    paper_coloured_plate,
    paper_plate_set_specs,
    save_plate,
    write_plate_preview,
)
from workbench.ishihara.reading import Reading, read_dots
from workbench.ishihara.scoring import IshiharaScore, score_answers
from workbench.ishihara.viewing import VIEWING_PATHS, Viewing, dot_radiance

__all__ = [
    # cones
    "cone_fundamentals_Smith_Pokorny1975",
    "cone_fundamentals_StockmanSharpe2000",
    "cone_fundamental_shifted_StockmanSharpe2000",
    "copunctal_point",
    "confusion_line_residual",
    # palette
    "SPECTRAL_UPSAMPLING_METHODS",
    "Palette",
    "PaletteColour",
    "XYZ_to_reflectance",
    "design_palette",
    "paper_dot_colours",
    # plates
    "DEFAULT_PLATE_SIZE",
    "DEFAULT_SEED",
    "PLATE_TYPES",
    "Plate",
    "PlateSpec",
    "generate_plate",
    "generate_plate_set",
    "paper_plate_set_specs",
    "paper_coloured_plate",
    "save_plate",
    "load_plate",
    "write_plate_preview",
    # observers and reading
    "OBSERVER_DEFICIENCIES",
    "OBSERVER_FUNDAMENTALS",
    "Observer",
    "simulated_observer",
    "parse_observer",
    "Reading",
    "read_dots",
    "IshiharaScore",
    "score_answers",
    "Examination",
    "read_plate",
    "take_test",
    # viewing
    "VIEWING_PATHS",
    "Viewing",
    "dot_radiance",
    "REALISTIC_HEADSET_EFFECTS",
    "CalibratedHeadset",
    "HeadsetRig",
    "calibrated_headset",
    # experiment and reference data
    "PAPER_TABLE5",
    "PAPER_TABLE6_REFERENCE",
    "PAPER_TABLE6_OBSERVERS",
    "TABLE5_PLATE",
    "TABLE6_CONDITIONS",
    "TABLE6_OBSERVERS",
    "Table5",
    "Table5Row",
    "Table6",
    "Table6Row",
    "ConditionFinding",
    "table5",
    "table6",
]
