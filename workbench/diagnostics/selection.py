"""Diagnose a session: baseline, findings, the extended model, and the gain on held-out colours.

Protocol ``holdout``: the baseline (the paper's gamma + 3×3) and the extended
model are fitted on every row but the ``validation`` ones, and both are
scored in CIEDE2000 on the validation rows only (CIELAB white: the measured
display white, the mean of the white rows). A finding is an effect whose
test is significant over all detectors together and whose impact on a fixed
colour set is material (:mod:`workbench.diagnostics.significance`); its term
enters the extended model only where it improves a cross-validated
prediction of the fit rows (:mod:`workbench.diagnostics.cross_validation`).
The validation rows are read once the model is final: for the score, the
attribution and the ``unexplained-residual`` check, never to choose a term.

Rows shown as a window or on a lit surround (``apl-dependence``): the
baseline, the extension and every other detector read the full-field rows
only (the reference load); the APL test reads every distinct fit row, and
when ``apl-dependence`` is found the model gains a load term, the APL curve
(:mod:`workbench.apl.curve`), fitted on the patches measured under several
frames and scored by leaving one window size or surround level out
(:class:`~workbench.apl.diagnosis.AplDiagnosis`): a patch on a frame of load
``L`` shows ``gain(L) / gain(L_ref)`` of the full-field prediction.

Findings are ordered with ``temporal-drift`` first (the other detectors read
its correction, so it is the cause they are conditioned on), then by impact
on the fixed colours, each consequence right after its cause (a power limit's
bend on the sweeps, :mod:`workbench.diagnostics.power_limit`: the finding
carries ``consequence_of``), then ``unexplained-residual``.

The exported model is then chosen by the same cross-validation among the
term selection's model and the alternatives the rows allow
(:mod:`workbench.diagnostics.model_choice`: the power-limit model where a
power limit was identified, the seed authors' grey-ramp linearisation and its
sweep-corrected form where the fit rows hold a grey ramp); each finding then
says whether the exported model answers it, and ``model_choice`` why that
model was taken.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from workbench.apl.diagnosis import AplDiagnosis, diagnose_apl, full_field_rows, subset_with_labels
from workbench.colorimetry import delta_E2000
from workbench.diagnostics.detectors import (
    APL_EFFECT,
    DetectorResult,
    DiagnosisContext,
    additivity_p_value,
    build_context,
    run_detectors,
    family_size,
)
from workbench.diagnostics.cross_validation import (
    CV_Z,
    TIMED_DRIFT_Z,
    cross_validated_errors,
    group_mean,
    is_timed_drift,
    paired_gain,
    select_terms,
)
from workbench.diagnostics.evidence import partial_greys
from workbench.diagnostics.power_limit import mixtures_show_load_gain, tone_bend_explained
from workbench.diagnostics.model_choice import (
    ALTERNATIVE_CANDIDATES,
    GREY_RAMP_CANDIDATES,
    WEIGHTED_CANDIDATES,
    ModelChoice,
    candidate_errors,
    choose_model,
    coarse_grey_ramp,
    fit_candidate,
)
from workbench.diagnostics.extension import (
    MATERIALITY_INTERACTION_EXPONENT,
    PARAMETRIC_TONE_FORMS,
    TERMS,
    constrained_by_whites,
    fit_extended,
    fitted_on,
)
from workbench.diagnostics.significance import (
    FAMILY_ALPHA,
    FIXED_COLOURS,
    MATERIALITY_FLOOR_DE00,
    mean_dE00_on_fixed_colours,
)
from workbench.diagnostics.noise import estimate_noise
from workbench.diagnostics.unexplained import unexplained_residual
from workbench.display import DisplayModel, GammaMatrixDisplay
from workbench.display.residual_lut import fit_residual_lut
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["ValidationScore", "Diagnosis", "NoDisplayModelError", "diagnose", "score_validation", "APL_TERM",
           "load_relative_noise"]

APL_TERM = "load term: output × gain(L) / gain(L_ref), the APL curve of the frame's load"
"""What the extended model gains when ``apl-dependence`` is found."""


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
    fallback_protocol: str = ""
    attribution: dict | None = None
    unexplained: DetectorResult | None = None
    cross_validation: dict = field(default_factory=dict)
    apl: AplDiagnosis | None = None
    model_choice: ModelChoice | None = None

    @property
    def apl_curve(self):
        """The load term's APL curve where ``apl-dependence`` was found and modelled, else None."""
        return None if self.apl is None else self.apl.curve

    def forward_on_frame(self, rgb, window=None, surround=None) -> np.ndarray:
        """XYZ of ``rgb`` shown as ``window`` (default full field) on ``surround`` (default black).

        The extended model's full-field prediction times the load term's
        ``gain(L) / gain(L_ref)`` where ``apl-dependence`` is in the model.
        """
        rgb = np.asarray(rgb, dtype=float).reshape(-1, 3)
        XYZ = self.extended.forward(rgb)
        curve = self.apl_curve
        if curve is None or window is None:
            return XYZ
        surround = np.zeros_like(rgb) if surround is None else surround
        window = np.broadcast_to(np.asarray(window, dtype=float), (len(rgb),))
        return XYZ * curve.relative_gain(rgb, window, surround)[:, None]

    @property
    def findings(self) -> tuple[DetectorResult, ...]:
        """Found effects: drift first, then by impact on the fixed colours, each consequence right
        after its cause; then unexplained."""
        named = sorted((r for r in self.results if r.found),
                       key=lambda r: (r.effect != "temporal-drift", -(r.impact_dE00 or 0.0)))
        causes = [r for r in named if not r.details.get("consequence_of")]
        ordered = []
        for cause in causes:
            ordered.append(cause)
            ordered += [r for r in named if r.details.get("consequence_of") == cause.effect]
        ordered += [r for r in named if r not in ordered]
        return tuple(ordered) + ((self.unexplained,) if self.unexplained is not None else ())

    @property
    def untested(self) -> tuple[tuple[str, str], ...]:
        """(effect, why) for every effect the session could not test, and how drift was tested."""
        notes = [(r.effect, r.evidence.removeprefix("not testable: ")) for r in self.results
                 if not r.testable]
        if self.context.time_basis == "row order" and self.context.drift is not None:
            notes.append(("temporal-drift", "tested on row order: the session has no times, its "
                                            "rows are taken to be in measurement order"))
        return tuple(notes)

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

    def _attribution_json(self) -> dict | None:
        if self.attribution is None:
            return None
        full = float(np.mean(self.extended_dE))
        return {
            "note": "the extension refitted without each term, scored on the same validation "
                    "colours; reported only, never used to choose terms",
            "no_terms_refit": {"mean_dE00": self.attribution["no_terms_refit_mean_dE00"]},
            "terms": [{"effect": effect, "mean_dE00_without": value,
                       "contribution_dE00": value - full}
                      for effect, value in self.attribution["without_term_mean_dE00"].items()],
        }

    def to_json(self) -> dict:
        base, ext = self.baseline_score, self.extended_score
        return {
            "session": {"source": self.session.source, "measurements": len(self.session),
                        "validation": int(self.session.mask("validation").sum())},
            "baseline": {"model": self.baseline.describe(),
                         "validation": None if base is None else base.to_json()},
            "findings": [_finding_json(r) for r in self.findings],
            "checked": [_finding_json(r) for r in self.results if not r.found],
            "untested": [{"effect": e, "reason": why} for e, why in self.untested],
            "noise": self.context.noise.to_json(),
            "significance": {"family_alpha": FAMILY_ALPHA, "method": "Bonferroni over the "
                             f"{family_size(self.context.apl_testable)} detectors",
                             "materiality_floor_dE00": MATERIALITY_FLOOR_DE00,
                             "materiality_colours": "5×5×5 cube of DAC values 0, 64, 128, 191, 255"},
            "cross_validation": {k: v for k, v in self.cross_validation.items()
                                 if k not in ("tone_forms", "by_effect")},
            "extended": {"model": self.extended.describe(), "protocol": self.protocol,
                         "terms": [_term_json(r.effect, self) for r in self.findings
                                   if r.in_model],
                         "validation": None if ext is None else ext.to_json()},
            "model_choice": None if self.model_choice is None else self.model_choice.to_json(),
            "gain": {"mean_dE00_reduction_pct": self.gain_pct},
            "attribution": self._attribution_json(),
            "fallback": None if self.fallback_dE is None else {
                "model": self.fallback_model, "protocol": self.fallback_protocol,
                "validation": score_validation(self.fallback_dE).to_json()},
            "reference_white": "measured display white (mean of the white rows), CIELAB for ΔE00",
            **({"unexplained": _finding_json(self.unexplained)} if self.unexplained else {}),
            "apl": None if self.apl is None else self.apl.to_json(),
        }


def _term_json(effect: str, diagnosis: "Diagnosis") -> dict:
    if effect == APL_EFFECT:
        return {"effect": effect, "term": APL_TERM, "fitted_on": diagnosis.apl.curve.fitted_on}
    chosen = None if diagnosis.model_choice is None else diagnosis.model_choice.chosen
    if chosen in ALTERNATIVE_CANDIDATES and effect != "temporal-drift":
        return {"effect": effect, **_alternative_term(effect, chosen, diagnosis)}
    return {"effect": effect, "term": TERMS[effect],
            "fitted_on": fitted_on(effect, diagnosis.context.fit, diagnosis.context)}


def _alternative_term(effect: str, chosen: str, diagnosis: "Diagnosis") -> dict:
    """What answers ``effect`` in an alternative model (:data:`ALTERNATIVE_CANDIDATES`)."""
    fit = diagnosis.context.fit
    sweeps = int(fit.mask("ramp-r", "ramp-g", "ramp-b").sum())
    whites = int(fit.mask("white").sum())
    greys = int(np.unique(fit.rgb[partial_greys(fit.rgb), 0]).size)
    if effect == "black-offset":
        return {"term": TERMS[effect], "fitted_on": "the black (0, 0, 0) measurement"}
    if chosen == "power-limit":
        interaction = diagnosis.extended.interaction
        knee = (f"past a knee at {100 * interaction.knee:.0f} % load, as load^"
                f"{interaction.exponent:.1f}" if interaction.knee >= 0.05 else
                f"as load^{interaction.exponent:.1f}")
        return {"channel-interaction": {
                    "term": f"a power limit: one load gain for every patch, "
                            f"{100 * interaction.amount:.1f} % of the light lost at full load, "
                            f"{knee} (load: the channels' outputs weighted by their shares of "
                            "the white)",
                    "fitted_on": f"the {sweeps} sweep points and {whites} white references "
                                 "together"},
                "tone-curve-shape": {
                    "term": "power laws of the undimmed outputs: the bend is the power limit's",
                    "fitted_on": f"the {sweeps} sweep points with the load gain divided out"},
                }.get(effect, {"term": "not in this model", "fitted_on": "—"})
    return {"tone-curve-shape": {
                "term": "the grey ramp's tone curves (the seed authors' linearisation: each "
                        "grey solved for its channels through the full-drive primaries, joined "
                        "by straight lines)",
                "fitted_on": f"the {greys} grey levels, black and white"},
            "channel-interaction": {
                "term": ("each channel's own sweep against its grey-ramp curve, applied as a "
                         "colour leaves the grey axis" if chosen == "grey-ramp+sweeps" else
                         "along the grey axis only, inside the grey ramp's tone curves"),
                "fitted_on": f"the {greys} grey levels and the {sweeps} sweep points"},
            }.get(effect, {"term": "not in this model", "fitted_on": "—"})


def load_relative_noise(context: DiagnosisContext) -> np.ndarray:
    """Each load row's relative luminance noise (one measurement), from the noise model."""
    return context.noise.relative_sd_Y(context.load_session.XYZ[:, 1])


def _apl_part(context: DiagnosisContext, results) -> tuple[tuple, AplDiagnosis | None]:
    """The APL curve and its held-out scores where ``apl-dependence`` was found; the term enters."""
    apl = next((r for r in results if r.effect == APL_EFFECT), None)
    if apl is None or not apl.significant:
        return results, None
    found = bool(apl.impact_dE00 is not None and apl.impact_dE00 >= MATERIALITY_FLOOR_DE00)
    if not found:
        return tuple(replace(r, found=False) if r.effect == APL_EFFECT else r
                     for r in results), None
    part = diagnose_apl(context.load_session, load_relative_noise(context))
    held_out = ("; ".join(part.holdout_lines())
                or "no window size or surround level could be held out to score the APL curve")
    note = f"in the model: {held_out}"
    return tuple(replace(r, found=True, in_model=True, cross_validation=note)
                 if r.effect == APL_EFFECT else r for r in results), part


def _number(value):
    value = None if value is None else float(value)
    return None if value is None or not np.isfinite(value) else value


def _finding_json(result: DetectorResult) -> dict:
    return {"effect": result.effect, "evidence": result.evidence, "score": result.score,
            "statistic": result.statistic, "standard_error": _number(result.standard_error),
            "z": _number(result.z), "p_value": result.p_value,
            "critical_z": _number(result.critical_z), "threshold": _number(result.threshold),
            "impact_dE00": _number(result.impact_dE00), "significant": result.significant,
            "testable": result.testable, "in_model": result.in_model,
            "cross_validation": result.cross_validation,
            "consequence_of": result.details.get("consequence_of")}


def with_measurement_order(session: Session) -> Session:
    """The session with row numbers as times where it has none and its rows are in measured order.

    A ``.ti3`` (and a session CSV without ``t_s``) lists its rows in the order
    they were measured, so its drift references can be tested against row
    order; Psychtoolbox files and published profiles are not in measurement
    order and keep no times (drift is then untestable, and said so).
    """
    if session.t_s is not None or session.metadata.get("format") in UNORDERED_FORMATS:
        return session
    return replace(session, t_s=np.arange(len(session), dtype=float),
                   metadata={**session.metadata, "time_basis": "row order"})


UNORDERED_FORMATS = ("psychtoolbox", "profile")
"""Session formats whose rows are not in measurement order."""


class NoDisplayModelError(InputError):
    """The session's full-field rows cannot fit the paper's model, but it has windows or surrounds.

    :func:`workbench.diagnostics.load_only.diagnose_what_it_can` then tests
    ``apl-dependence`` alone.
    """


def diagnose(session: Session) -> Diagnosis:
    """Test every effect, extend the model by cross-validation, score both on validation rows once.

    Steps: the noise model and the detectors on the fit rows (significance
    over all detectors); each significant effect's impact on the fixed colour
    set (materiality); the terms of the found effects that improve a K-fold
    cross-validated prediction of the fit rows; then baseline and extension
    scored on the validation rows, and an ``unexplained-residual`` finding
    when the held-out error is far above what the session's noise explains.
    """
    if len(session) == 0:
        raise InputError(f"session {session.source!r} is empty")
    session = with_measurement_order(session)
    load_session = None
    if session.has_surround_data:  # the model reads the full-field rows, the APL test all
        load_session = subset_with_labels(session, ~session.mask("validation"))
        session_full = session.subset(full_field_rows(session))
    else:
        session_full = session
    fit_session = session_full.without("validation")
    validation = session_full.select("validation")
    if "baseline_parameters" in session.metadata:  # published numbers: nothing to fit on
        baseline = GammaMatrixDisplay.from_parameters(session.metadata["baseline_parameters"])
    else:
        try:
            baseline = GammaMatrixDisplay.fit(fit_session)
        except InputError as error:
            if load_session is None:
                raise
            raise NoDisplayModelError(str(error).replace("the paper's model", "the paper's model "
                                      "(full-field rows)")) from None
    noise = estimate_noise(fit_session if load_session is None else load_session)
    context, results = run_detectors(fit_session, noise=noise, load_session=load_session)
    results, apl = _apl_part(context, results)
    tone_forms = None
    significant = [r.effect for r in results if r.significant and r.effect != APL_EFFECT]
    if "tone-curve-shape" in significant:
        # the forms are chosen by BIC on the fit rows (with every significant term, so
        # grey-derived points are read through them); every later fit refits these forms.
        # Materiality is judged among the parametric forms; the spline joins the choice
        # only once the shape is a finding (its leave-one-out score is the costly part)
        tone_forms = _tone_forms(fit_extended(context, significant, baseline,
                                              tone_candidates=PARAMETRIC_TONE_FORMS))
    results = _materiality(context, results, baseline, tone_forms)
    found = [r.effect for r in results if r.found and r.effect != APL_EFFECT]
    results, power_limit = _consequences(context, results, found)
    if "tone-curve-shape" in found:
        tone_forms = _tone_forms(fit_extended(context, significant, baseline))
    if "temporal-drift" not in found and context.drift_found:
        context = build_context(fit_session, drift_found=False, noise=context.noise,
                                load_session=load_session)
    drift_z = next((r.z for r in results if r.effect == "temporal-drift"), None)
    terms, cross_validation = select_terms(
        context, found, baseline, {r.effect: r.impact_dE00 for r in results}, tone_forms,
        drift_z=drift_z)
    if terms and "temporal-drift" not in terms and context.drift_found:
        context = build_context(fit_session, drift_found=False, noise=context.noise,
                                load_session=load_session)
    extended = (fit_extended(context, terms, baseline, tone_forms, with_whites=True)
                if cross_validation.get("use_extension") else baseline)
    drift_in = "temporal-drift" in terms and extended is not baseline
    drift_left_out = "temporal-drift" in found and context.drift is not None and not drift_in
    choice = _choose_model(context, extended is not baseline, terms, cross_validation, baseline,
                           cross_validation.get("tone_forms") or tone_forms,
                           power_limit == "identified", found,
                           power_limit_offered=power_limit == "offered",
                           power_limit_shown=power_limit == "shown",
                           grey_ramp_corrected=_grey_ramp_correction(context, found, drift_z)
                           if drift_left_out else None)
    if choice.chosen == "extension" and constrained_by_whites(context, terms):
        p_value = additivity_p_value(context)
        choice = replace(choice, primaries=(
            f"estimated with the {context.white_count} white references as well: "
            + (f"the white less the black is their sum within noise (additivity test p "
               f"{p_value:.2f}), so each moves by its share of the white's departure"
               if p_value >= FAMILY_ALPHA else
               f"the model has no interaction term, so the white less the black is taken as their "
               f"sum (additivity test p {p_value:.2g}: the departure is beyond noise) and each "
               "moves by its share of it")
            + (", by a gain alone beside flexible tone curves"
               if "tone-curve-shape" in terms else "")))
    by_effect = dict(cross_validation["by_effect"])
    if choice.chosen in GREY_RAMP_CANDIDATES and drift_left_out:
        # the choice scored the candidate on corrected rows where its own cross-validation
        # wanted them; where term selection left the rows corrected they stay so
        # (the found drift's correction carries the rows to the settled state, and a wander
        # found at z 3.4 on the authors' plan, within noise either way on the fit rows, scores
        # 0.092 mean ΔE00 on hidden colours so and 0.157 from the rows as measured)
        if choice.drift_corrected and not context.drift_found:
            context = build_context(fit_session, drift_found=True, noise=context.noise,
                                    load_session=load_session)
        drift_in = context.drift_found
    elif drift_in:
        decided = _grey_ramp_drift(context, choice, found, fit_session, load_session, drift_z)
        if decided is not None:
            context, choice = decided
            drift_in = False
            terms = [t for t in terms if t != "temporal-drift"]
    if choice.chosen in ALTERNATIVE_CANDIDATES:
        extended = fit_candidate(choice.chosen, context, found)
        answered = _answered_by(choice.chosen) | ({"temporal-drift"} if drift_in else set())
        terms = [r.effect for r in results if r.found and r.effect in answered]
        for effect in [r.effect for r in results if r.found and r.effect != APL_EFFECT]:
            by_effect[effect] = (f"in the model through the {choice.chosen} model: {choice.reason}"
                                 if effect in answered else
                                 f"not in the exported model: {choice.reason}")
    in_model_of = (lambda effect: effect in terms and extended is not baseline)
    results = tuple(r if r.effect == APL_EFFECT else
                    replace(r, in_model=in_model_of(r.effect),
                            cross_validation=by_effect.get(r.effect, ""))
                    for r in results)
    white = session_full.white_XYZ if session_full.has_white else context.white
    in_model = [t for t in terms if extended is not baseline]
    if len(validation):
        baseline_dE = delta_E2000(baseline.forward(validation.rgb), validation.XYZ, white)
        extended_dE = _score_extended(extended, context, in_model, validation, white)
        attribution = (None if choice.chosen in ALTERNATIVE_CANDIDATES else
                       _attribution(context, in_model, baseline, validation, white, tone_forms))
    else:
        baseline_dE = extended_dE = np.zeros(0)
        attribution = None
    fallback_dE, fallback_model, fallback_protocol = _residual_lut_fallback(
        extended, session_full, context, in_model, white)
    unexplained = unexplained_residual(context, extended, in_model, validation, white,
                                       np.atleast_1d(extended_dE))
    return Diagnosis(session=session, context=context, results=results, baseline=baseline,
                     extended=extended, white=white, baseline_dE=np.atleast_1d(baseline_dE),
                     extended_dE=np.atleast_1d(extended_dE), protocol="holdout",
                     fallback_dE=fallback_dE, fallback_model=fallback_model,
                     fallback_protocol=fallback_protocol, attribution=attribution,
                     unexplained=unexplained, cross_validation=cross_validation, apl=apl,
                     model_choice=choice)


def _grey_ramp_drift(context: DiagnosisContext, choice: ModelChoice, found, fit_session,
                     load_session, drift_z: float | None):
    """``(context, choice)`` fitted on the rows as measured where term selection kept the drift
    correction, a grey-ramp candidate was chosen and its own cross-validation does not want
    the correction; else None.

    Term selection keeps or drops ``temporal-drift`` by what it does for the extension; a grey
    ramp chosen over the extension decides it by the same rule on its own errors (both versions
    predict the fit rows as measured, in the same folds, the corrected one times its drift
    gain): the correction stays where it lowers the candidate's cross-validated error, and for
    a drift found on measurement times at z ≥ 4 (:func:`is_timed_drift`) unless the uncorrected
    candidate predicts the rows better beyond noise (the settled state, as in term selection).
    The other way, a correction term selection left out, the choice decides as it scores the
    candidates (:func:`_grey_ramp_correction`).

    A real HP EliteBook chart (four whites, 94–103 %, drift tested on row order at z 2.6)
    exported the grey ramp from corrected rows at 2.75 mean ΔE00 on its held-out mixtures,
    where the same ramp from the rows as measured scores 2.59 and the seed authors' method 2.71.
    """
    if not (choice.chosen in GREY_RAMP_CANDIDATES and "temporal-drift" in found
            and context.drift is not None and context.drift_found):
        return None
    name = choice.chosen
    apart = coarse_grey_ramp(context) and name == "grey-ramp"
    plain = build_context(fit_session, drift_found=False, noise=context.noise,
                          load_session=load_session)

    def errors_on(fold_source, drift):
        return candidate_errors(name, fold_source, found, drift=drift, greys_apart=apart)

    corrected, measured = errors_on(context, True), errors_on(plain, False)
    if corrected is None or measured is None:
        return None
    gain, standard_error = paired_gain(measured, corrected)  # what the correction buys
    timed = is_timed_drift(context, drift_z)
    if gain > (-TIMED_DRIFT_Z * standard_error if timed else 0.0):
        return None
    with_drift, without = group_mean(*corrected), group_mean(*measured)
    verdict = ("predicts them worse beyond noise" if timed else
               "does not lower its cross-validated error")
    reason = (f"{choice.reason}; fitted on the rows as measured: the drift correction "
              f"{verdict} ({without:.3f} without it vs {with_drift:.3f} with it, a gain of "
              f"{gain:.3f} ± {standard_error:.3f})")
    return plain, replace(choice, reason=reason, cv_mean_dE00={**choice.cv_mean_dE00,
                                                               name: without})


def _grey_ramp_correction(context: DiagnosisContext, found, drift_z: float | None):
    """Where a drift was found and term selection left its correction out: for
    :func:`~workbench.diagnostics.model_choice.choose_model`, a grey-ramp candidate's
    cross-validated errors on drift-corrected rows with the correction's gain and its standard
    error, where the correction serves that candidate; else None.

    Term selection decides the correction by what it does for the extension; a grey ramp reads
    its tone curves from the greys, measured in a stretch of the session of their own, and
    decides by its own errors. Taking back a correction term selection left out asks for a gain
    beyond noise (:data:`~workbench.diagnostics.cross_validation.CV_Z` standard errors: it
    overturns term selection's verdict), but for a drift found on measurement times at z ≥ 4
    (:func:`is_timed_drift`): there the correction is in unless the rows as measured predict
    better beyond noise (the settled state, as in term selection).

    On the authors' plan a bluish black beside a 7.2 % step that fell between two references
    while the green sweep's top and the blue sweep's start were measured: the correction's ramp
    across that interval misplaces the green primary by 7 %, the extension predicts the fit
    rows worse with it (2.96 against 2.39 cross-validated mean ΔE00) and term selection dropped
    it; the sweep correction then fitted on the rows as measured (two display states 7.8 %
    apart) scored 0.624 mean ΔE00 on hidden colours against the authors' 0.119. Its own
    cross-validation wants the correction (0.489 → 0.214, a gain of 0.28 ± 0.02), and with it
    the sweep correction scores 0.076. Beyond noise on row order: a real Surface Pro 3 chart
    (drift on row order at z 4.9, left out by term selection) took the correction back for its
    grey ramp on a gain of 0.138 ± 0.072 and scored 1.59 mean ΔE00 on its 108 held-out
    colours, 1.41 from the rows as measured (the seed authors' method 1.41).
    """
    needed_z = -TIMED_DRIFT_Z if is_timed_drift(context, drift_z) else CV_Z

    def corrected(name: str, greys_apart: bool, measured):
        if measured is None:
            return None
        errors = candidate_errors(name, context, found, drift=True, greys_apart=greys_apart)
        if errors is None:
            return None
        gain, standard_error = paired_gain(measured, errors)  # what the correction buys
        return (errors, gain, standard_error) if gain > needed_z * standard_error else None

    return corrected


def _choose_model(context: DiagnosisContext, extension_used: bool, terms, cross_validation,
                  baseline, tone_forms, power_limit: bool = False, found=(),
                  power_limit_offered: bool = False, power_limit_shown: bool = False,
                  grey_ramp_corrected=None) -> ModelChoice:
    """:func:`~workbench.diagnostics.model_choice.choose_model` on term selection's result."""
    baseline_errors = cross_validated_errors(context, None)
    current_errors = (cross_validated_errors(context, terms, baseline, tone_forms)
                      if extension_used else baseline_errors)
    return choose_model(context, "extension" if extension_used else "baseline", current_errors,
                        baseline_errors, drift="temporal-drift" in terms and extension_used,
                        power_limit=power_limit, found=found,
                        power_limit_offered=power_limit_offered,
                        power_limit_shown=power_limit_shown,
                        grey_ramp_corrected=grey_ramp_corrected,
                        extension_terms=tuple(terms) if extension_used else (),
                        current_errors_apart=(lambda: cross_validated_errors(
                            context, terms, baseline, tone_forms, greys_apart=True))
                        if extension_used else None)


def _answered_by(candidate: str) -> set:
    """Named effects an alternative candidate models (its black, its curves, its interaction)."""
    if candidate in WEIGHTED_CANDIDATES:  # the paper's model: no term of any effect
        return set()
    answered = {"black-offset", "tone-curve-shape"}
    return answered | ({"channel-interaction"} if candidate in ("grey-ramp+sweeps", "power-limit")
                       else set())


def _consequences(context: DiagnosisContext, results, found) -> tuple[tuple, str | None]:
    """Mark a finding that another finding explains as its consequence (``consequence_of``).

    A power limit (``channel-interaction`` whose white falls short by one gain
    on every channel, or channel by channel where a bend was found: each
    primary is dimmed at its own load) dims each sweep by its own load, which bends the
    bright channels' tone curves: where one load gain explains the sweeps
    and the white together and, divided out, leaves no sweep off a power law
    (:func:`~workbench.diagnostics.power_limit.tone_bend_explained`),
    ``tone-curve-shape`` is its consequence. Returns the results and
    ``"identified"`` (the model choice then takes the power limit unless it predicts
    worse beyond noise), ``"offered"`` where one load gain explains the sweeps and
    the white but their bend was not a finding (a plan with a few sweep levels: on
    an adaptive session of a knee the power limit scored 0.013 ΔE00 on hidden colours
    where the extension scored 0.130; it must then lower the cross-validated error
    to be taken), ``"shown"`` where the sweeps hold no bend to explain but the greys
    and mixtures show one load gain (a knee above every channel's own load:
    :func:`~workbench.diagnostics.power_limit.mixtures_show_load_gain`; it must then lower the
    cross-validated error beyond noise), or None.
    """
    if "channel-interaction" not in found:
        return results, None
    interaction = next(r for r in results if r.effect == "channel-interaction")
    # the detector's common-gain test: the white short by one gain in X, Y and Z or not. A power
    # limit dims each primary at its own load, so its white can fail that test; one load gain that
    # explains a bend found in the sweeps and the white together still names it
    channel_specific = interaction.details.get("channel_specific")
    if channel_specific and "tone-curve-shape" not in found:
        return results, None
    explained, why, _ = tone_bend_explained(context)
    if channel_specific and not explained:
        return results, None
    if not explained:  # a knee above every channel's own load: only mixtures reach it
        return results, ("shown" if mixtures_show_load_gain(context)[0] else None)
    if "tone-curve-shape" not in found:
        # the bend is there but below the tone test's threshold (a plan with few sweep
        # levels): the power limit is offered to the model choice, not identified
        return results, "offered"
    note = f"the bend that channel-interaction's power limit puts on the sweeps: {why}"
    reread = ("; read with the sweeps, one load gain explains this white and their bend together: "
              "a power limit, which dims each primary at its own load, not subpixel crosstalk")

    def marked(r):
        if r.effect == "tone-curve-shape":
            return replace(r, evidence=f"{r.evidence}; a consequence of channel-interaction, {note}",
                           details={**r.details, "consequence_of": "channel-interaction",
                                    "consequence": note})
        if r.effect == "channel-interaction" and channel_specific:  # its evidence said crosstalk
            return replace(r, evidence=r.evidence + reread,
                           details={**r.details, "power_limit_explains": True})
        return r

    return tuple(marked(r) for r in results), "identified"


def _materiality(context: DiagnosisContext, results, baseline, tone_forms=None
                 ) -> tuple[DetectorResult, ...]:
    """Each significant effect's impact on :data:`FIXED_COLOURS`; found = significant and material."""
    significant = [r.effect for r in results if r.significant and r.effect != APL_EFFECT]
    if not significant:
        return results
    # an interaction whose shape the fit rows cannot identify is judged at the middle shape
    full = fit_extended(context, significant, baseline, tone_forms,
                        interaction_exponent=MATERIALITY_INTERACTION_EXPONENT)
    white = context.white
    predicted = full.forward(FIXED_COLOURS)
    out = []
    for result in results:
        if not result.significant or result.effect == APL_EFFECT:  # the APL test's own impact
            out.append(result)
            continue
        if result.effect == "temporal-drift":
            gains = context.drift.gains
            impact = mean_dE00_on_fixed_colours(predicted * gains.max(), predicted * gains.min(),
                                                white)
        else:
            without = fit_extended(context, [e for e in significant if e != result.effect],
                                   baseline, tone_forms,
                                   interaction_exponent=MATERIALITY_INTERACTION_EXPONENT)
            impact = mean_dE00_on_fixed_colours(predicted, without.forward(FIXED_COLOURS), white)
        out.append(replace(result, impact_dE00=impact,
                           found=bool(impact >= MATERIALITY_FLOOR_DE00)))
    return tuple(out)


def _tone_forms(model) -> tuple[str, ...] | None:
    return tuple(curve.form for curve in model.tone) if hasattr(model, "tone") else None


def _score_extended(model, context: DiagnosisContext, found, validation: Session, white):
    predicted = model.forward(validation.rgb)
    if "temporal-drift" in found and validation.t_s is not None:
        predicted = predicted * context.drift.gain(validation.t_s)[:, None]
    return delta_E2000(predicted, validation.XYZ, white)


def _attribution(context: DiagnosisContext, found, baseline, validation: Session, white,
                 tone_forms=None):
    """What each term buys on the validation colours: the extension refitted without it.

    Also the extension refitted with no term at all (same rows, same fitting as
    the extension: black-subtracted sweeps, grey-derived points, weighted
    curves), so a gain that comes from fitting the data better rather than
    from a named effect shows as such. Reported, never used to choose a term.
    """
    if not found:
        return None

    def without(effects):
        if "temporal-drift" in found and "temporal-drift" not in effects:
            rebuilt = build_context(context.raw, drift_found=False, noise=context.noise)
        else:
            rebuilt = context
        model = fit_extended(rebuilt, effects, baseline, tone_forms, with_whites=True)
        return float(np.mean(_score_extended(model, rebuilt, effects, validation, white)))

    return {
        "no_terms_refit_mean_dE00": without([]),
        "without_term_mean_dE00": {effect: without([e for e in found if e != effect])
                                   for effect in found},
    }


FALLBACK_FOLDS = 5
FALLBACK_MIN_MIXTURES = 25


def _mixture_rows(session: Session) -> np.ndarray:
    """Rows with two or more channels lit, other than white."""
    lit = (session.rgb > 0).sum(axis=1)
    return (lit >= 2) & ~np.all(session.rgb >= 255, axis=1)


def _residual_lut_fallback(model, session: Session, context, found, white):
    """CIEDE2000 on the validation colours of ``model`` + a 3D-LUT residual, its name and protocol.

    The LUT always learns from every fit row (black, white, sweeps, greys,
    mixtures) after the same drift correction as the extended model. With at
    least :data:`FALLBACK_MIN_MIXTURES` mixtures among the fit rows it is
    scored on the validation colours as a true holdout; otherwise the
    validation colours are the only mixtures and it is scored by
    :data:`FALLBACK_FOLDS`-fold cross-validation over them (each fold's LUT
    also learns from the other folds). Returns (None, "", "") without
    validation colours.
    """
    validation = session.select("validation")
    if len(validation) < FALLBACK_FOLDS:
        return None, "", ""
    fit = context.fit  # drift-corrected where drift was found

    def drift_of(rows):
        if "temporal-drift" in found and rows.t_s is not None:
            return context.drift.gain(rows.t_s)[:, None]
        return 1.0

    target = validation.XYZ / drift_of(validation)
    n_mixtures = int(_mixture_rows(fit).sum())
    if n_mixtures >= FALLBACK_MIN_MIXTURES:
        fitted = fit_residual_lut(model, fit.rgb, fit.XYZ)
        predicted = fitted.forward(validation.rgb)
        protocol = (f"holdout: the LUT learned from the {len(fit)} fit rows "
                    f"({n_mixtures} of them mixtures), scored on the validation colours")
    else:
        folds = np.random.default_rng(0).permutation(len(validation)) % FALLBACK_FOLDS
        predicted = np.zeros_like(target)
        smoothing = None  # chosen by the LUT's inner cross-validation on the first fold's rows
        for k in range(FALLBACK_FOLDS):
            train = folds != k
            fitted = fit_residual_lut(model, np.vstack([fit.rgb, validation.rgb[train]]),
                                      np.vstack([fit.XYZ, target[train]]), smoothing=smoothing)
            smoothing = fitted.smoothing
            predicted[~train] = fitted.forward(validation.rgb[~train])
        protocol = (f"{FALLBACK_FOLDS}-fold cross-validation on the validation colours: the fit "
                    f"rows hold only {n_mixtures} mixtures, so each fold's LUT also learns from "
                    "the other folds' validation colours")
    return (delta_E2000(predicted * drift_of(validation), validation.XYZ, white),
            fitted.describe(), protocol)


