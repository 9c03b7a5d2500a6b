"""Diagnostics: what the paper's display model gets wrong, why, and how much an extension gains.

:func:`diagnose` runs one detector per effect of the vocabulary (design §5,
:data:`DETECTORS`), extends the model with exactly the terms found, and scores
baseline and extension on the validation colours neither was fitted on.
"""

from workbench.diagnostics.detectors import DETECTORS, THRESHOLDS, DetectorResult
from workbench.diagnostics.extension import TERMS, fit_extended
from workbench.diagnostics.selection import Diagnosis, ValidationScore, diagnose

__all__ = ["DETECTORS", "THRESHOLDS", "TERMS", "DetectorResult", "Diagnosis",
           "ValidationScore", "diagnose", "fit_extended"]
