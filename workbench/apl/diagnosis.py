"""Everything the diagnosis needs about ``apl-dependence``, in one call.

:func:`diagnose_apl` runs the test (:mod:`.detector`) with the session's own
relative noise, fits the APL curve (:mod:`.curve`) when any patch was measured
under two frames, and scores it on every held-out grouping the session offers
(:mod:`.holdout`). :func:`full_field_rows` says which rows the rest of the
display model may be fitted on (full-field patches: the reference load).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.apl.curve import AplCurve, fit_apl_curve
from workbench.apl.detector import AplDependenceTest, detect_apl_dependence
from workbench.apl.holdout import AplHoldout, apl_fold_labels, evaluate_apl_holdout
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["AplDiagnosis", "diagnose_apl", "full_field_rows", "subset_with_labels"]


@dataclass(frozen=True)
class AplDiagnosis:
    """The ``apl-dependence`` test, the APL curve and its held-out scores for one session.

    Attributes
    ----------
    test : AplDependenceTest
    curve : AplCurve or None
        ``None`` when no patch was measured under two frames.
    holdouts : tuple of AplHoldout
        One per held-out grouping (window size, surround level, or the
        reader's own labels).
    """

    test: AplDependenceTest
    curve: AplCurve | None
    holdouts: tuple

    def closing_note(self) -> str:
        """The lines a report ends with: the evidence and the held-out error of the curve."""
        if not self.test.testable:
            return f"apl-dependence {self.test.evidence}"
        return "\n".join([f"apl-dependence: {self.test.evidence}", *self.holdout_lines()])

    def holdout_lines(self) -> list[str]:
        """``APL curve, leave one … out: …`` for each held-out grouping (none: an empty list)."""
        return [f"APL curve, {holdout.one_line()}" for holdout in self.holdouts]

    def to_json(self) -> dict:
        """Plain JSON types, for ``diagnose --json``."""
        test = self.test
        return {
            "effect": test.effect, "testable": test.testable, "statistic": test.statistic,
            "standard_error": None if not np.isfinite(test.standard_error) else test.standard_error,
            "z": test.z, "impact_dE00": test.impact_dE00, "evidence": test.evidence,
            "curve": None if self.curve is None else self.curve.to_json(),
            "holdout": [{"by": h.by, "luminance_error_pct": h.luminance_error_pct, "mean_dE00": h.dE00,
                         "p95_luminance_error_pct": h.luminance_error_pct_p95, "p95_dE00": h.dE00_p95,
                         "without_load_term": {"luminance_error_pct": h.luminance_error_pct_without,
                                               "mean_dE00": h.dE00_without},
                         "folds": [fold.__dict__ for fold in h.folds]} for h in self.holdouts],
        }


def full_field_rows(session: Session) -> np.ndarray:
    """Rows shown full field (the reference load the rest of the display model assumes)."""
    return session.window_or_full >= 1.0


def subset_with_labels(session: Session, mask) -> Session:
    """``session.subset(mask)`` with a reader's per-row held-out labels (``apl_folds``) subset too."""
    mask = np.asarray(mask, dtype=bool)
    subset = session.subset(mask)
    folds = session.metadata.get("apl_folds")
    if folds:
        subset.metadata["apl_folds"] = {name: np.asarray(labels, dtype=object)[mask]
                                        for name, labels in folds.items()}
    return subset


def diagnose_apl(session: Session, relative_noise) -> AplDiagnosis:
    """Test, fit and score ``apl-dependence`` on ``session``.

    Parameters
    ----------
    session : Session
        Drift-corrected if it drifts.
    relative_noise : float or array_like, shape (N,)
        The session's relative luminance noise (one measurement's ``ΔY/Y`` sd),
        or one per row.

    Returns
    -------
    AplDiagnosis
    """
    test = detect_apl_dependence(session, relative_noise)
    if not test.testable:
        return AplDiagnosis(test, None, ())
    curve = fit_apl_curve(session)
    holdouts = []
    for by, labels in apl_fold_labels(session).items():
        try:
            holdouts.append(evaluate_apl_holdout(session, labels, by, transfer=curve.transfer))
        except InputError:
            continue
    return AplDiagnosis(test, curve, tuple(holdouts))
