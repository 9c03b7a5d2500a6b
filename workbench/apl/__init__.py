"""APL dependence: OLED panels dim what they show when more of the picture is lit.

Qt-free science for the ``apl-dependence`` effect (design §5): the load of a
frame (:mod:`.load`), the APL curve and its fit (:mod:`.curve`), its held-out
score (:mod:`.holdout`), the detector (:mod:`.detector`), all three in one call
(:mod:`.diagnosis`), prediction with the
optional ``window, sr, sg, sb`` columns (:mod:`.predict`) and readers for real
OLED measurements (:mod:`.readers`).
"""

from workbench.apl.curve import AplCurve, estimate_transfer, fit_apl_curve, load_rows, unlimited_XYZ
from workbench.apl.detector import AplDependenceTest, detect_apl_dependence
from workbench.apl.diagnosis import AplDiagnosis, diagnose_apl, full_field_rows
from workbench.apl.holdout import AplHoldout, AplHoldoutFold, apl_fold_labels, evaluate_apl_holdout
from workbench.apl.load import ChannelTransfer, channel_transfer, frame_load, reference_load
from workbench.apl.predict import PredictRows, apl_curve_from_json, predict_XYZ_on_surround, read_predict_rows

__all__ = [
    "AplCurve",
    "AplDependenceTest",
    "AplDiagnosis",
    "AplHoldout",
    "AplHoldoutFold",
    "ChannelTransfer",
    "PredictRows",
    "apl_curve_from_json",
    "predict_XYZ_on_surround",
    "read_predict_rows",
    "apl_fold_labels",
    "channel_transfer",
    "detect_apl_dependence",
    "diagnose_apl",
    "estimate_transfer",
    "evaluate_apl_holdout",
    "fit_apl_curve",
    "frame_load",
    "full_field_rows",
    "load_rows",
    "reference_load",
    "unlimited_XYZ",
]
