"""Diagnostics: what the paper's display model gets wrong, why, and how much an extension gains.

:func:`diagnose` estimates the session's noise, runs one test per effect of
the vocabulary (design §5, :data:`DETECTORS`), names the effects that are
significant over all detectors together and material on a fixed colour set,
extends the model with the terms that improve a cross-validated prediction
of the fit rows, and scores baseline and extension on the validation colours
neither was fitted on. A session with windows or surrounds (``apl-dependence``)
but no full-field ramps is diagnosed for that effect alone
(:func:`diagnose_what_it_can`).
"""

from workbench.diagnostics.detectors import DETECTORS, DetectorResult
from workbench.diagnostics.extension import TERMS, fit_extended
from workbench.diagnostics.noise import NoiseModel, estimate_noise
from workbench.diagnostics.selection import Diagnosis, ValidationScore, diagnose
from workbench.diagnostics.load_only import LoadOnlyDiagnosis, diagnose_what_it_can
from workbench.diagnostics.significance import FAMILY_ALPHA, MATERIALITY_FLOOR_DE00

__all__ = ["DETECTORS", "TERMS", "DetectorResult", "Diagnosis", "FAMILY_ALPHA",
           "MATERIALITY_FLOOR_DE00", "LoadOnlyDiagnosis", "NoiseModel", "ValidationScore", "diagnose",
           "diagnose_what_it_can",
           "estimate_noise", "fit_extended"]
