"""Diagnose a session: baseline, findings, the extended model, and the gain on held-out colours.

Protocol ``holdout``: the baseline (the paper's gamma + 3×3) and the extended
model are fitted on every row but the ``validation`` ones, and both are
scored in CIEDE2000 on the validation rows only (CIELAB white: the measured
display white, the mean of the white rows). The channel-interaction term is
fitted on the white references, the drift correction on the white
references; neither sees a validation row.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.colorimetry import delta_E2000
from workbench.diagnostics.detectors import DetectorResult, DiagnosisContext, run_detectors
from workbench.diagnostics.extension import TERMS, fit_extended, fitted_on
from workbench.display import DisplayModel, GammaMatrixDisplay
from workbench.display.residual_lut import fit_residual_lut
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["ValidationScore", "Diagnosis", "diagnose", "score_validation"]


@dataclass(frozen=True)
class ValidationScore:
    n: int
    mean_dE00: float
    p95_dE00: float
    max_dE00: float

    def to_json(self) -> dict:
        return {"mean_dE00": self.mean_dE00, "p95_dE00": self.p95_dE00,
                "max_dE00": self.max_dE00, "n": self.n}


def score_validation(dE: np.ndarray) -> ValidationScore | None:
    if dE.size == 0:
        return None
    return ValidationScore(n=int(dE.size), mean_dE00=float(dE.mean()),
                           p95_dE00=float(np.percentile(dE, 95)), max_dE00=float(dE.max()))


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """Everything ``diagnose`` found, with the arrays the report plots."""

    session: Session
    context: DiagnosisContext
    results: tuple[DetectorResult, ...]
    baseline: GammaMatrixDisplay
    extended: DisplayModel
    white: np.ndarray
    baseline_dE: np.ndarray
    extended_dE: np.ndarray
    protocol: str
    fallback_dE: np.ndarray | None = None
    fallback_model: str = ""

    @property
    def findings(self) -> tuple[DetectorResult, ...]:
        return tuple(sorted((r for r in self.results if r.found), key=lambda r: r.score,
                            reverse=True))

    @property
    def baseline_score(self) -> ValidationScore | None:
        return score_validation(self.baseline_dE)

    @property
    def extended_score(self) -> ValidationScore | None:
        return score_validation(self.extended_dE)

    @property
    def gain_pct(self) -> float | None:
        base, ext = self.baseline_score, self.extended_score
        if base is None or ext is None or base.mean_dE00 == 0:
            return None
        return 100.0 * (base.mean_dE00 - ext.mean_dE00) / base.mean_dE00

    def to_json(self) -> dict:
        base, ext = self.baseline_score, self.extended_score
        return {
            "session": {"source": self.session.source, "measurements": len(self.session),
                        "validation": int(self.session.mask("validation").sum())},
            "baseline": {"model": self.baseline.describe(),
                         "validation": None if base is None else base.to_json()},
            "findings": [{"effect": r.effect, "evidence": r.evidence, "score": r.score,
                          "statistic": r.statistic, "threshold": r.threshold}
                         for r in self.findings],
            "extended": {"model": self.extended.describe(), "protocol": self.protocol,
                         "terms": [{"effect": r.effect, "term": TERMS[r.effect],
                                    "fitted_on": fitted_on(r.effect, self.context.fit)}
                                   for r in self.findings],
                         "validation": None if ext is None else ext.to_json()},
            "gain": {"mean_dE00_reduction_pct": self.gain_pct},
            "fallback": None if self.fallback_dE is None else {
                "model": self.fallback_model, "protocol": FALLBACK_PROTOCOL,
                "validation": score_validation(self.fallback_dE).to_json()},
            "reference_white": "measured display white (mean of the white rows), CIELAB for ΔE00",
        }


def diagnose(session: Session) -> Diagnosis:
    """Run the detectors, fit baseline and extended models, score both on validation rows."""
    if len(session) == 0:
        raise InputError(f"session {session.source!r} is empty")
    fit_session = session.without("validation")
    validation = session.select("validation")
    if "baseline_parameters" in session.metadata:  # published numbers: nothing to fit on
        baseline = GammaMatrixDisplay.from_parameters(session.metadata["baseline_parameters"])
    else:
        baseline = GammaMatrixDisplay.fit(fit_session)
    context, results = run_detectors(fit_session)
    found = [r.effect for r in results if r.found]
    extended = fit_extended(context, found, baseline) if found else baseline
    white = context.white if not session.mask("white").any() else session.white_XYZ
    if len(validation):
        baseline_dE = delta_E2000(baseline.forward(validation.rgb), validation.XYZ, white)
        predicted = extended.forward(validation.rgb)
        if "temporal-drift" in found and validation.t_s is not None:
            predicted = predicted * context.drift.gain(validation.t_s)[:, None]
        extended_dE = delta_E2000(predicted, validation.XYZ, white)
    else:
        baseline_dE = extended_dE = np.zeros(0)
    fallback_dE, fallback_model = _residual_lut_fallback(extended, validation, context, found, white)
    return Diagnosis(session=session, context=context, results=results, baseline=baseline,
                     extended=extended, white=white, baseline_dE=np.atleast_1d(baseline_dE),
                     extended_dE=np.atleast_1d(extended_dE), protocol="holdout",
                     fallback_dE=fallback_dE, fallback_model=fallback_model)


FALLBACK_FOLDS = 5
FALLBACK_MIN_MIXTURES = 25
FALLBACK_PROTOCOL = (f"{FALLBACK_FOLDS}-fold cross-validation on the validation colours (the "
                     "residual LUT learns from mixtures, and the validation colours are the "
                     "session's only mixtures)")


def _residual_lut_fallback(model, validation: Session, context, found, white):
    """Cross-validated CIEDE2000 of ``model`` + a 3D-LUT residual, or (None, "")."""
    if len(validation) < FALLBACK_MIN_MIXTURES:
        return None, ""
    drift = (context.drift.gain(validation.t_s)[:, None]
             if "temporal-drift" in found and validation.t_s is not None else 1.0)
    corrected = validation.XYZ / drift
    folds = np.random.default_rng(0).permutation(len(validation)) % FALLBACK_FOLDS
    predicted = np.zeros_like(corrected)
    for k in range(FALLBACK_FOLDS):
        train = folds != k
        fitted = fit_residual_lut(model, validation.rgb[train], corrected[train])
        predicted[~train] = fitted.forward(validation.rgb[~train])
    return delta_E2000(predicted * drift, validation.XYZ, white), fitted.describe()


