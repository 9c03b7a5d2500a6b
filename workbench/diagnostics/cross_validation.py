"""Which terms enter the extended model: K-fold cross-validation on the fit rows only.

The validation rows are never read here. The fit rows are split into
:data:`FOLDS` interleaved folds (row ``i`` of the free rows goes to fold
``i mod K``, so every fold holds sweep levels of every channel, greys and
white references from the whole session). The black rows and the full-drive
primaries stay in every training set (no model can be fitted without them),
and so do copies. Each fold's model is refitted on the other folds, drift
correction included (its references are the training whites), and predicts
the fold's rows; the score is the mean CIEDE2000 of those predictions
(CIELAB white: the session's measured white) per group of rows — sweep
points, greys, white references, other mixtures — averaged over the groups,
so each kind of evidence counts the same however many rows the plan spends
on it (the paper's plan has 153 sweep points and 10 whites).

Selection (:func:`select_terms`): start from every found effect; remove,
one at a time from the least material, each term whose removal does not make
the cross-validated error worse; then keep the extension only if it predicts
the fit rows better than the baseline refitted the same way. Tone-curve forms
are chosen once, on all fit rows, and refitted in the folds.
"""

from __future__ import annotations

import numpy as np

from workbench.colorimetry import delta_E2000
from workbench.diagnostics.detectors import DiagnosisContext, build_context
from workbench.diagnostics.extension import fit_extended
from workbench.display import GammaMatrixDisplay
from workbench.errors import InputError

__all__ = ["FOLDS", "fold_of_rows", "cross_validated_dE00", "select_terms"]

FOLDS = 5
"""K of the K-fold cross-validation."""


def fold_of_rows(context: DiagnosisContext, folds: int = FOLDS) -> np.ndarray:
    """Fold index of each fit row; -1 for rows every training set keeps."""
    session = context.raw
    rgb = session.rgb
    lit = rgb > 0
    fixed = (~lit.any(axis=1)) | ((lit.sum(axis=1) == 1) & (rgb.max(axis=1) >= 255))
    fixed |= context.copies
    fold = np.full(len(session), -1)
    free = np.flatnonzero(~fixed)
    fold[free] = np.arange(free.size) % folds
    return fold


def cross_validated_dE00(context: DiagnosisContext, effects, baseline=None, tone_forms=None,
                         folds: int = FOLDS) -> float:
    """Mean ΔE00 of the fit rows predicted by models fitted without them (``effects`` None: baseline)."""
    session = context.raw
    fold = fold_of_rows(context, folds)
    white = context.white if context.white_count else None
    errors, groups = [], []
    drift = effects is not None and "temporal-drift" in effects
    for k in range(folds):
        test = fold == k
        if not test.any():
            continue
        train = session.subset(~test)
        held = session.subset(test)
        try:
            if effects is None:
                model = GammaMatrixDisplay.fit(train)
                predicted = model.forward(held.rgb)
            else:
                fold_context = build_context(train, drift_found=drift, noise=context.noise)
                model = fit_extended(fold_context, effects, baseline, tone_forms)
                predicted = model.forward(held.rgb)
                if drift and fold_context.drift is not None:
                    predicted = predicted * fold_context.drift.gain(held.t_s)[:, None]
        except (InputError, np.linalg.LinAlgError, ValueError):
            return float("inf")
        reference = white if white is not None else context.white
        errors.append(delta_E2000(predicted, held.XYZ, reference))
        groups.append(_group_of_rows(held.rgb))
    if not errors:
        return float("inf")
    errors, groups = np.concatenate(errors), np.concatenate(groups)
    return float(np.mean([errors[groups == g].mean() for g in np.unique(groups)]))


def _group_of_rows(rgb: np.ndarray) -> np.ndarray:
    """0 single-channel sweep points, 1 greys, 2 whites, 3 other mixtures."""
    lit = (rgb > 0).sum(axis=1)
    grey = (rgb[:, 0] == rgb[:, 1]) & (rgb[:, 1] == rgb[:, 2])
    white = np.all(rgb >= 255, axis=1)
    return np.select([lit == 1, white, grey], [0, 2, 1], default=3)


def select_terms(context: DiagnosisContext, found, baseline, impacts=None, tone_forms=None
                 ) -> tuple[list, dict]:
    """The terms of ``found`` that improve the cross-validated prediction (module doc).

    Returns the terms and a JSON-ready record: the cross-validated mean ΔE00
    of the baseline and of each step, a note per effect, whether the
    extension beats the baseline (``use_extension``), and the tone forms
    (``tone_forms``: chosen by BIC on all fit rows when not given).
    """
    record = {"folds": FOLDS, "rows": "fit rows only (the validation rows are never read)",
              "by_effect": {}, "steps": [], "use_extension": False, "tone_forms": None}
    if not found:
        return [], record
    if tone_forms is None:
        full = fit_extended(context, found, baseline)
        tone_forms = tuple(curve.form for curve in full.tone)
    record["tone_forms"] = tone_forms
    base_error = cross_validated_dE00(context, None)
    record["baseline_cv_mean_dE00"] = base_error
    current = list(found)
    error = cross_validated_dE00(context, current, baseline, tone_forms)
    record["steps"].append({"terms": list(current), "cv_mean_dE00": error})
    order = sorted(found, key=lambda e: (impacts or {}).get(e, 0.0))
    for effect in order:
        trial = [e for e in current if e != effect]
        trial_error = (cross_validated_dE00(context, trial, baseline, tone_forms) if trial
                       else cross_validated_dE00(context, [], baseline, tone_forms))
        if trial_error <= error:
            record["by_effect"][effect] = (f"left out of the model: without it the fit rows are "
                                           f"predicted as well or better ({trial_error:.3f} vs "
                                           f"{error:.3f} cross-validated mean ΔE00)")
            current, error = trial, trial_error
            record["steps"].append({"terms": list(current), "cv_mean_dE00": error})
        else:
            record["by_effect"][effect] = (f"in the model: it lowers the cross-validated mean "
                                           f"ΔE00 of the fit rows from {trial_error:.3f} to "
                                           f"{error:.3f}")
    record["extension_cv_mean_dE00"] = error
    record["use_extension"] = bool(current) and error < base_error
    if current and not record["use_extension"]:
        for effect in current:
            record["by_effect"][effect] = (f"not used: the extension predicts the fit rows no "
                                           f"better than the baseline ({error:.3f} vs "
                                           f"{base_error:.3f} cross-validated mean ΔE00)")
    return (current if record["use_extension"] else []), record
