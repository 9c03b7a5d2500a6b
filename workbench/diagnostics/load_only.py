"""Diagnose what a session allows: the whole diagnosis, or ``apl-dependence`` alone.

Real OLED measurements of brightness limiting (``shared/data/real/oled-apl/``)
show patches as windows on surrounds but hold no full-field sweep of each
channel, so the paper's model (and every test read against it) cannot be
fitted. :func:`diagnose_what_it_can` runs :func:`~workbench.diagnostics.diagnose`
where it can and otherwise :func:`diagnose_load_only`: the noise model of the
session's own rows (repeats under the same frame; copies left out), the
``apl-dependence`` test at the same family-wise level as a full diagnosis
(Bonferroni over every detector: a session that cannot test an effect does
not earn the others a looser level), the APL curve and its held-out scores
(leave one window size or surround level out), and for every other effect
why it could not be tested.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from workbench.apl.diagnosis import AplDiagnosis, diagnose_apl, subset_with_labels
from workbench.diagnostics.detectors import (
    APL_EFFECT,
    FULL_FIELD_DETECTORS,
    DetectorResult,
    apl_dependence_result,
    family_size,
)
from workbench.diagnostics.noise import NoiseModel, copy_rows, estimate_noise
from workbench.diagnostics.selection import (
    Diagnosis,
    NoDisplayModelError,
    _finding_json,
    diagnose,
    with_measurement_order,
)
from workbench.diagnostics.significance import (
    FAMILY_ALPHA,
    MATERIALITY_FLOOR_DE00,
    critical_p,
    z_of_p,
)
from workbench.session import Session

__all__ = ["LoadOnlyDiagnosis", "diagnose_load_only", "diagnose_what_it_can"]


@dataclass(frozen=True, eq=False)
class LoadOnlyDiagnosis:
    """``apl-dependence`` tested, fitted and held out on a session with no display model.

    Attributes
    ----------
    session : Session
    noise : NoiseModel
        From the session's own rows (repeats under the same frame, copies left out).
    result : DetectorResult
        The ``apl-dependence`` test with the family-wise level applied.
    apl : AplDiagnosis or None
        The APL curve and its held-out scores where the effect was found.
    untested : tuple of (str, str)
        Every other effect and why it could not be tested.
    why : str
        Why the display model could not be fitted.
    """

    session: Session
    noise: NoiseModel
    result: DetectorResult
    apl: AplDiagnosis | None
    untested: tuple
    why: str = ""

    @property
    def findings(self) -> tuple[DetectorResult, ...]:
        return (self.result,) if self.result.found else ()

    @property
    def apl_curve(self):
        return None if self.apl is None else self.apl.curve

    def to_json(self) -> dict:
        """The keys of :meth:`Diagnosis.to_json`; no baseline or extension (no display model)."""
        return {
            "session": {"source": self.session.source, "measurements": len(self.session),
                        "validation": int(self.session.mask("validation").sum())},
            "baseline": None,
            "findings": [_finding_json(r) for r in self.findings],
            "checked": [] if self.result.found else [_finding_json(self.result)],
            "untested": [{"effect": e, "reason": why} for e, why in self.untested],
            "noise": self.noise.to_json(),
            "significance": {"family_alpha": FAMILY_ALPHA, "method": "Bonferroni over the "
                             f"{family_size(True)} detectors (the untested ones "
                             "counted too)",
                             "materiality_floor_dE00": MATERIALITY_FLOOR_DE00,
                             "materiality_colours": "each patch at its lowest and its highest "
                                                    "measured load"},
            "extended": None,
            "gain": {"mean_dE00_reduction_pct": None},
            "attribution": None,
            "fallback": None,
            "apl": None if self.apl is None else self.apl.to_json(),
        }


def diagnose_load_only(session: Session, why: str = "") -> LoadOnlyDiagnosis:
    """Test, fit and hold out ``apl-dependence`` alone (module doc).

    Parameters
    ----------
    session : Session
        With windows or surrounds.
    why : str
        Why the display model could not be fitted (kept in the result).
    """
    session = with_measurement_order(session)
    rows = subset_with_labels(session, ~session.mask("validation"))
    rows = subset_with_labels(rows, ~copy_rows(rows))  # exact copies are not measurements
    noise = estimate_noise(rows)
    level = critical_p(family_size(True), FAMILY_ALPHA)
    result = apl_dependence_result(rows, noise)
    apl = None
    if result.testable:
        significant = result.p_value <= level
        found = significant and (result.impact_dE00 or 0.0) >= MATERIALITY_FLOOR_DE00
        result = replace(result, critical_z=z_of_p(level), significant=significant, found=found)
        if found:
            apl = diagnose_apl(rows, noise.relative_sd_Y(rows.XYZ[:, 1]))
            note = "; ".join(apl.holdout_lines()) or "no window size or surround level could be held out"
            result = replace(result, in_model=True, cross_validation=note)
    reason = "no display model to test it against (the full-field rows hold no sweep of each "\
             "channel)"
    untested = tuple((effect, f"{reason}; measure plan 'paper+apl' for the full diagnosis")
                     for effect in FULL_FIELD_DETECTORS)
    if not result.testable:
        untested += ((APL_EFFECT, result.evidence.removeprefix("not testable: ")),)
    return LoadOnlyDiagnosis(session=session, noise=noise, result=result, apl=apl,
                             untested=untested, why=why)


def diagnose_what_it_can(session: Session) -> Diagnosis | LoadOnlyDiagnosis:
    """:func:`~workbench.diagnostics.diagnose`, or :func:`diagnose_load_only` where the session
    shows windows or surrounds but cannot fit the paper's model (no full-field ramps)."""
    try:
        return diagnose(session)
    except NoDisplayModelError as error:
        return diagnose_load_only(session, str(error))
