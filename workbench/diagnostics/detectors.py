"""Effect detectors: one per effect id of the diagnostics vocabulary (design §5), each a test.

Every detector reads the rows a model may be fitted on and returns a
statistic, its standard error propagated from the session's noise model
(:mod:`workbench.diagnostics.noise`), and the p-value of a test of "the
paper's model holds for this effect":

``temporal-drift``
    two tests of the distinct white references (copies left out), each an
    F-test against the noise estimate's own degrees of freedom, the smaller
    p-value doubled (Bonferroni over the two). *Any change*: their χ² about
    their mean, ``n − 1`` dof; with six or more references it must also
    hold without the most deviant one when that one is less than
    :data:`OUTLIER_SIGMA` standard deviations off (one bad reading is not a
    drift; a reference far beyond that, such as the first one of a warm-up,
    is a real change). *A smooth trend*: the part of that χ² a weighted
    Legendre polynomial in time of degree :data:`DRIFT_TREND_DEGREE`
    explains (a warm-up, a decline, a step, a slow wander: few dof, so more
    power, and one bad reading spreads over the whole curve), which must
    also hold without the most deviant reference where it is within
    :data:`TREND_OUTLIER_SIGMA`, or is the last one and within
    :data:`OUTLIER_SIGMA`; against
    session time, or against row order
    where the session has no times (a ``.ti3``: its rows are in measurement
    order), and the evidence says which. Statistic: the span of the
    references. The form is named: warm-up, decline, step or wander.
``black-offset``
    t of the mean black luminance against 0 (one-sided, the noise estimate's
    degrees of freedom). Statistic: black / white in Y.
``channel-interaction``
    χ² (3 dof) of ``W + 2K − (R + G + B)`` in X, Y and Z with its covariance
    (white, black and full-drive primaries; the noise model's, the
    chromaticity noise carried into each one's X and Z included: ±0.0002 in
    xy is 0.4 % of a deep blue's X and Z), as an F-test against the
    degrees of freedom of the noise estimate (Satterthwaite's, where the
    chromaticity noise, estimated apart or the instrument's stated figure,
    carries part of the variance). Statistic: ``1 − (W − K)/Σ(P − K)`` in Y.
``chromaticity-shift``
    per channel, generalized least squares of the black-subtracted sweep's
    xy against ``(1 − d)`` and ``(1 − d)²`` (the full-drive point included,
    the subtracted black's own error a nuisance parameter): F-test of the
    four slopes, which with eight usable points or more must also hold
    without the point farthest from the fit with no shift where that one
    is within :data:`OUTLIER_SIGMA` (one reading is not a shift); the
    smallest p times 3 channels. Statistic: the fitted xy distance at the
    lowest usable level.
``tone-curve-shape``
    per channel, ``K + k·d^γ`` against ``K + k·f(d)`` with ``f`` GOG,
    extended power (one more parameter each) or the power law plus two sine
    harmonics of drive (two more: an S or a bump), weighted by the noise
    model, black rows at ``d = 0``: F-test of the extra parameters; and the
    power law's lack of fit, its χ² against the noise model (an F-test on
    the noise estimate's degrees of freedom), which a shape none of the
    alternatives bends to still fails; the smallest p times 4 tests times
    the channels tested. A channel whose sweep is too
    short (a DisplayCAL ``.ti3`` has 4 levels) is tested on its sweep and the
    channel outputs the greys imply, in normalized output. Statistic: the largest gap
    between the two fitted curves, in normalized output.

``apl-dependence``
    the same patch's ln luminance regressed on its frame's load, one
    intercept per patch (:mod:`workbench.apl.detector`), on every distinct
    row (copies left out) shown as a window or on a lit surround beside the
    same patch's other frames, drift-corrected when drift was found; each
    row's relative noise from the noise model; one-sided Student t on the
    noise estimate's degrees of freedom. Statistic: the loss of ln luminance
    per unit of load. Its impact is the test's own: the mean ΔE00 between
    each patch at its lowest and its highest measured load.

Every detector but ``apl-dependence`` reads the full-field rows only: a
patch shown as a window is shown at another load than the model's.

The F-tests divide by the larger of the noise model and the fit's own
residual variance, so a sweep that scatters more than the noise model says
cannot turn into a finding. :func:`run_detectors` then applies the
family-wise significance level (:mod:`workbench.diagnostics.significance`);
materiality and whether a term enters the model are decided by
:mod:`workbench.diagnostics.selection`.

Registry: :data:`DETECTORS` (effect id → detector), run in that order:
drift first, and when it is significant the other detectors read
drift-corrected data, so drift cannot masquerade as another effect.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from itertools import product

import numpy as np
from scipy.optimize import least_squares

from workbench.diagnostics.evidence import (
    ChannelSweep,
    DriftCorrection,
    channel_sweeps,
    drift_references,
    partial_greys,
    xy_of,
    MIN_CHROMATICITY_OUTPUT,
)
from workbench.diagnostics.noise import NoiseModel, copy_rows, estimate_noise
from workbench.diagnostics.significance import (
    FAMILY_ALPHA,
    chi2_sf,
    critical_p,
    f_sf,
    t_sf,
    z_of_chi2,
    z_of_p,
)
from workbench.session import Session

APL_EFFECT = "apl-dependence"

__all__ = [
    "APL_EFFECT",
    "FULL_FIELD_DETECTORS",
    "apl_dependence_result",
    "detect_apl_dependence_in_context",
    "family_size",
    "DetectorResult",
    "DiagnosisContext",
    "DETECTORS",
    "build_context",
    "run_detectors",
    "detect_temporal_drift",
    "drift_form",
    "detect_black_offset",
    "detect_channel_interaction",
    "common_gain_test",
    "CommonGainTest",
    "CHANNEL_SPECIFIC_ALPHA",
    "CHANNEL_SPECIFIC_SHARE",
    "detect_chromaticity_shift",
    "detect_tone_curve_shape",
    "tone_data",
    "additivity_p_value",
    "mean_covariance",
    "white_against_sum",
    "primaries_off_their_sweeps",
    "PRIMARY_OFF_SWEEP_Z",
    "PRIMARY_SWEEP_TOP",
    "PRIMARY_SWEEP_LEVELS",
    "PRIMARY_SWEEP_DEGREE",
    "primary_correction_covariance",
    "primary_drift_covariance",
    "curve_variance",
]

CHANNEL_NAMES = ("red", "green", "blue")
OUTLIER_SIGMA = 8.0
"""A single white reference closer than this (in σ) to the others' median may be a bad reading:
instrument readings have heavier tails than a Gaussian (a Student t), but not this heavy."""

TREND_OUTLIER_SIGMA = 4.0
"""The smooth-trend part of the drift test must also hold without the one white reference farthest
from the others' median where it is closer than this (in σ): a first white read 2.5–4σ low by a
heavy-tailed instrument has an endpoint's leverage on a low-degree trend and read as "a step up"
(4 of 270 sessions of the peer bench, all one display's noise). A fast warm-up's first reference
is farther off than that (at 8σ, as for the change test, it lost 6 of 170 drifts in the
940-session suite). The last reference is left out up to :data:`OUTLIER_SIGMA`: no warm-up
speaks for a lone reading far off at the session's end, and a change that only the last
reference shows moved only the rows read after the one before it (what the test gives up
naming). On fresh seeds of the peer bench (59000–59009) one display's noise read its last white
5.0σ high (a Student-t draw of the generator's) and the trend named "a rise" beside a shoulder,
an S-curve, a soft toe and a backlight on ``paper+greys`` (4 of 460 grey-ramp sessions; now
none, three of them 0.04–0.06 ΔE00 better on hidden colours, the fourth unchanged). A wander of
that display's noise is no longer named either (without that reading its whites pass the drift
test), and scores 0.263 → 0.138 (the authors' method 0.171): its correction had carried the rows
to that last reading. The 940-session suite and the peer bench's 636 drift sessions are
unchanged by it, session for session."""

DRIFT_TREND_DEGREE = 3
"""Highest Legendre degree of the drift test's smooth trend (fewer where there are fewer
references): a cubic in time follows a warm-up that settles, a decline, a step seen by a few
references and a wander of one or two swings, with three dof where the any-change test spends
``n − 1``."""

MIN_TONE_LEVELS = 5
"""A channel's shape is tested only with this many sweep levels below full drive."""


@dataclass(frozen=True)
class DetectorResult:
    """One detector's test.

    Attributes
    ----------
    effect : str
    found : bool
        Significant and material (set by the selection; detectors set ``significant``).
    statistic, standard_error : float
        The effect's size and its standard error from the noise model.
    p_value : float
        The test's p-value (1 where not testable).
    z : float
        One-sided normal quantile of ``p_value``.
    critical_z : float
        ``z`` a finding needs: the family-wise level over the tested detectors.
    testable : bool
        False where the session lacks what the test needs (``evidence`` says what).
    significant : bool
    impact_dE00 : float or None
        Mean ΔE00 the term makes on the fixed colour set (materiality).
    in_model : bool
        Whether the term entered the extended model (cross-validation).
    """

    effect: str
    found: bool
    statistic: float
    standard_error: float
    p_value: float
    z: float
    critical_z: float
    testable: bool
    evidence: str
    significant: bool = False
    impact_dE00: float | None = None
    in_model: bool = False
    cross_validation: str = ""
    details: dict = field(default_factory=dict)

    @property
    def threshold(self) -> float:
        """The statistic a finding needs at this standard error (critical z × SE)."""
        return float(self.critical_z * self.standard_error)

    @property
    def score(self) -> float:
        """``z`` over the critical ``z``: how far beyond noise the evidence is."""
        if not self.testable or not np.isfinite(self.z):
            return 0.0
        return float(self.z / self.critical_z)


@dataclass(frozen=True, eq=False)
class DiagnosisContext:
    """What the detectors read: fit rows (drift-corrected if drift was found), black, sweeps, noise."""

    raw: Session
    fit: Session
    drift: DriftCorrection | None
    drift_found: bool
    black: np.ndarray
    white: np.ndarray
    sweeps: tuple[ChannelSweep, ...]
    noise: NoiseModel
    time_basis: str
    copies: np.ndarray
    black_count: int
    white_count: int
    load_session: Session | None = None
    """Every distinct fit row, windows and surrounds included (drift-corrected where the fit
    rows are): what ``apl-dependence`` reads. None: the session shows every patch full field."""

    @property
    def apl_testable(self) -> bool:
        """Whether some patch was measured under two frames (the APL test counts then)."""
        return _apl_testable(self.load_session)


def _untestable(effect: str, why: str) -> DetectorResult:
    return DetectorResult(effect, False, 0.0, 0.0, 1.0, float("-inf"), np.inf, False,
                          f"not testable: {why}")


def _result(effect, statistic, standard_error, p_value, evidence, details, z=None
            ) -> DetectorResult:
    """A tested result; ``z`` from the p-value, or the caller's where the p-value underflows."""
    z = z_of_p(p_value) if (z is None or p_value > 1e-15) else z
    return DetectorResult(effect, False, float(statistic), float(standard_error), float(p_value),
                          float(z), np.inf, True, evidence, details=details)


def family_size(apl_testable: bool) -> int:
    """Detectors the family-wise level divides among: all, the APL test only when testable."""
    return len(DETECTORS) - (0 if apl_testable else 1)


def build_context(fit_session: Session, drift_found: bool | None = None,
                  noise: NoiseModel | None = None, load_session: Session | None = None
                  ) -> DiagnosisContext:
    """The detectors' view of ``fit_session`` (full-field rows).

    ``drift_found`` None: decided by the drift test at the family-wise level
    for all detectors; ``noise`` None: estimated from ``fit_session``;
    ``load_session``: the fit rows with windows and surrounds too, for
    ``apl-dependence`` (None where every patch is full field).
    """
    noise = estimate_noise(fit_session) if noise is None else noise
    copies = copy_rows(fit_session)
    drift, time_basis = drift_references(fit_session, copies)
    if load_session is not None and not load_session.has_surround_data:
        load_session = None
    if drift_found is None:
        test = detect_temporal_drift_raw(drift, time_basis, noise)
        drift_found = test.testable and test.p_value <= critical_p(family_size(_apl_testable(load_session)))
    if drift is not None and drift_found:
        # the correction follows the references only as far as they rise above their noise
        drift = drift.smoothed_to_noise(noise.sd_Y(drift.luminances) / drift.luminances)
    corrected = drift.correct(fit_session) if (drift is not None and drift_found) else fit_session
    blacks = np.all(corrected.rgb <= 0, axis=1) & ~copies
    black = corrected.XYZ[blacks].mean(axis=0) if blacks.any() else np.zeros(3)
    whites = np.all(corrected.rgb >= 255, axis=1) & ~copies
    uncertain = (drift.uncertainty(fit_session.t_s) if (drift is not None and drift_found)
                 else None)
    sweeps = channel_sweeps(corrected, black, keep=~copies, correction_sd=uncertain,
                            times=None if uncertain is None else np.asarray(fit_session.t_s,
                                                                            dtype=float))
    white = (corrected.XYZ[whites].mean(axis=0) if whites.any()
             else black + sum(s.full_XYZ for s in sweeps))  # ramps only: the additive white
    if load_session is not None:
        from workbench.apl.diagnosis import subset_with_labels

        load_session = subset_with_labels(load_session, ~copy_rows(load_session))
        if drift is not None and drift_found and load_session.t_s is not None:
            load_session = _with_labels_of(load_session, drift.correct(load_session))
    return DiagnosisContext(raw=fit_session, fit=corrected, drift=drift, drift_found=drift_found,
                            black=black, white=white, sweeps=sweeps, noise=noise,
                            time_basis=time_basis, copies=copies, black_count=int(blacks.sum()),
                            white_count=int(whites.sum()), load_session=load_session)


def _apl_testable(load_session: Session | None) -> bool:
    """Whether some patch of ``load_session`` was measured under two frames."""
    from workbench.apl import load_rows

    return load_session is not None and len(load_rows(load_session)) > 0


def _with_labels_of(labelled: Session, corrected: Session) -> Session:
    """``corrected`` (same rows as ``labelled``) with ``labelled``'s held-out labels."""
    if "apl_folds" in labelled.metadata:
        corrected.metadata["apl_folds"] = labelled.metadata["apl_folds"]
    return corrected


def _drift_form(drift: DriftCorrection, sd: float) -> str:
    """warm-up, decline, step or wander, from the steps between successive references."""
    steps = np.diff(drift.gains)
    threshold = 2.5 * np.sqrt(2) * sd  # a change between two references beyond their noise
    clear = steps[np.abs(steps) > threshold]
    span = drift.span
    if clear.size == 0:
        return "a slow trend"
    if clear.size == 1 and abs(clear[0]) > 0.6 * span:
        form = "a step" + (" up" if clear[0] > 0 else " down")
        if clear[0] > 0 and abs(steps[0]) > threshold:
            # the first two references alone cannot tell a step from a warm-up that settled
            # between them, and a display's first minutes are when it warms up
            form += (" after the first reference (or a warm-up that settled before the second: "
                     "no reference between them to tell)")
        return form
    if np.all(clear > 0):
        return "a warm-up (rising, then settling)" if np.argmax(steps) < steps.size / 2 else \
            "a rise"
    if np.all(clear < 0):
        return "a decline"
    return "a wander (the display is unstable)"


def drift_form(drift: DriftCorrection, noise: NoiseModel) -> str:
    """The drift's form (warm-up, decline, step, wander, slow trend) at the references' noise."""
    Y = drift.luminances
    return _drift_form(drift, float(np.median(noise.sd_Y(Y) / Y)))


def _trend_chi2(times: np.ndarray, Y: np.ndarray, sd: np.ndarray, degree: int) -> float:
    """χ² a weighted Legendre polynomial in time of ``degree`` explains beyond the weighted mean."""
    span = float(np.ptp(times))
    x = 2.0 * (times - times.min()) / span - 1.0 if span > 0 else np.zeros_like(times)
    basis = np.polynomial.legendre.legvander(x, degree) / sd[:, None]
    coefficients, *_ = np.linalg.lstsq(basis, Y / sd, rcond=None)
    mean = float(np.sum(Y / sd ** 2) / np.sum(1.0 / sd ** 2))
    return float(np.sum((basis @ coefficients - mean / sd) ** 2))


def detect_temporal_drift_raw(drift: DriftCorrection | None, time_basis: str,
                              noise: NoiseModel) -> DetectorResult:
    """The drift test on already collected references (module doc)."""
    if drift is None:
        return _untestable("temporal-drift", time_basis)
    Y = drift.luminances
    sd = noise.sd_Y(Y)

    def steady_chi2(keep):
        weights = 1.0 / sd[keep] ** 2
        mean = float(np.sum(weights * Y[keep]) / np.sum(weights))
        return float(np.sum(((Y[keep] - mean) / sd[keep]) ** 2))

    everything = np.ones(Y.size, dtype=bool)
    chi2 = steady_chi2(everything)
    dof = Y.size - 1
    p = f_sf(chi2 / dof, dof, noise.dof)  # the noise is estimated: F, not χ²
    deviation = np.abs(Y - np.median(Y)) / sd
    worst = int(np.argmax(deviation))
    degree = min(DRIFT_TREND_DEGREE, dof)
    trend_chi2 = _trend_chi2(drift.times, Y, sd, degree)
    p_trend = f_sf(trend_chi2 / degree, degree, noise.dof)
    without = everything.copy()
    without[worst] = False
    if Y.size >= 6 and deviation[worst] < OUTLIER_SIGMA:
        # one reading a few σ off could be a bad reading, not a drift: the drift must show
        # without it too (a reference far beyond that is a real change, e.g. a warm-up); the
        # trend, to which an endpoint is leverage, within TREND_OUTLIER_SIGMA (the last
        # reference within OUTLIER_SIGMA: at the end no warm-up speaks for a lone reading)
        p = max(p, f_sf(steady_chi2(without) / (dof - 1), dof - 1, noise.dof))
    last_alone = worst == Y.size - 1 and deviation[worst] < OUTLIER_SIGMA
    if Y.size >= 6 and (deviation[worst] < TREND_OUTLIER_SIGMA or last_alone):
        trend_degree = min(DRIFT_TREND_DEGREE, dof - 1)
        p_trend = max(p_trend, f_sf(_trend_chi2(drift.times[without], Y[without], sd[without],
                                                trend_degree) / trend_degree, trend_degree,
                                    noise.dof))
    p_any = p
    p = min(1.0, 2.0 * min(p_any, p_trend))
    relative_sd = float(np.median(sd / Y))
    form = _drift_form(drift, relative_sd)
    unit = "s" if time_basis == "time" else ""
    where = ("over the session" if time_basis == "time" else
             "over the session's rows (no times: tested on row order, the order of measurement)")
    low, high = int(np.argmin(drift.gains)), int(np.argmax(drift.gains))
    evidence = (f"the {Y.size} distinct white references vary by {100 * drift.span:.1f} % {where} "
                f"(χ² {chi2:.1f} on {dof} dof against a steady white with the session's "
                f"{100 * relative_sd:.2f} % repeatability, {trend_chi2:.1f} of it on a smooth "
                f"trend of {degree} dof): {form}; lowest "
                f"{100 * drift.gains[low]:.1f} % of the reference state at "
                f"{'t = ' if unit else 'row '}{drift.times[low]:.0f}{' s' if unit else ''}, "
                f"highest {100 * drift.gains[high]:.1f} %")
    return _result("temporal-drift", drift.span, np.sqrt(2) * relative_sd, p, evidence,
                   {"times": drift.times.tolist(), "time_basis": time_basis,
                    "relative_white": drift.gains.tolist(), "chi2": chi2, "dof": dof,
                    "trend_chi2": trend_chi2, "trend_dof": degree, "p_any_change": p_any,
                    "p_smooth_trend": p_trend, "form": form}, z=z_of_chi2(chi2, dof))


def detect_temporal_drift(context: DiagnosisContext) -> DetectorResult:
    return detect_temporal_drift_raw(context.drift, context.time_basis, context.noise)


def detect_black_offset(context: DiagnosisContext) -> DetectorResult:
    if context.black_count == 0:
        return _untestable("black-offset", "no black (0, 0, 0) measurement")
    noise = context.noise
    white_Y = float(context.white[1])
    black_Y = float(context.black[1])
    sd = float(noise.sd_Y(black_Y)) / np.sqrt(context.black_count)
    ratio = black_Y / white_Y
    z = black_Y / sd
    p_Y = t_sf(z, noise.dof)  # Student t: the noise is estimated
    # light has all three tristimulus values: the black as a whole must stand out of the noise
    # too (χ² on 3 dof), or a Y read high by one heavy-tailed reading, at a chromaticity no
    # light has, is named a black level
    covariance = mean_covariance(noise, context.black, context.black_count)
    chi2 = float(context.black @ np.linalg.solve(covariance, context.black))
    p_XYZ = f_sf(chi2 / 3, 3, noise.dof if np.isfinite(noise.dof) else 10 ** 6)
    p = max(p_Y, p_XYZ)
    xy = xy_of(context.black)
    evidence = (f"black measures {100 * ratio:.2f} % of white (Y {black_Y:.4g} ± {sd:.2g} of "
                f"{white_Y:.4g}, {context.black_count} distinct black row(s); X, Y, Z together "
                f"χ² {chi2:.1f} on 3 dof) at xy ({xy[0]:.3f}, {xy[1]:.3f}); the baseline predicts "
                "no light at DAC 0 and lets black leak into every primary")
    return _result("black-offset", ratio, sd / white_Y, p, evidence,
                   {"black_XYZ": context.black.tolist(), "ratio": ratio, "chi2_XYZ": chi2,
                    "p_Y": p_Y, "p_XYZ": p_XYZ}, z=z if p == p_Y else None)


def mean_covariance(noise: NoiseModel, XYZ: np.ndarray, count: int) -> np.ndarray:
    """Covariance of the mean of ``count`` measurements of ``XYZ`` (the chromaticity noise included)."""
    return noise.covariance(XYZ) / max(count, 1)


def _mean_chromaticity_covariance(noise: NoiseModel, XYZ: np.ndarray, count: int) -> np.ndarray:
    """The chromaticity noise's part of :func:`mean_covariance`."""
    return noise.chromaticity_covariance(XYZ) / max(count, 1)


def _scale_dof(noise: NoiseModel, covariance: np.ndarray, chromatic: np.ndarray,
               projector: np.ndarray | None = None) -> float:
    """Satterthwaite's degrees of freedom of a χ²'s noise scale whose ``covariance`` has a
    ``chromatic`` part estimated apart (``noise.xy_dof``) from the rest (``noise.dof``).

    Each part's share is its expected share of the χ² under no effect,
    ``tr(C⁻¹ P Cᵢ Pᵀ) / tr(C⁻¹ P C Pᵀ)`` (``P``: the projector onto what the
    test leaves, identity by default); the scale's relative variance is
    ``Σ 2 wᵢ²/νᵢ``. A test whose variance is mostly the instrument's stated
    chromaticity noise is then not held to the few degrees of freedom of a
    luminance noise estimated from three repeated whites.
    """
    projector = np.eye(3) if projector is None else projector
    inverse = np.linalg.inv(covariance)
    total = float(np.trace(inverse @ projector @ covariance @ projector.T))
    share = float(np.trace(inverse @ projector @ chromatic @ projector.T)) / total if total > 0 \
        else 0.0
    share = min(max(share, 0.0), 1.0)
    return float(1.0 / ((1.0 - share) ** 2 / noise.dof + share ** 2 / noise.xy_dof))


def _additivity_test(noise: NoiseModel, difference: np.ndarray, covariance: np.ndarray,
                     chromatic: np.ndarray) -> tuple[float, float]:
    """(χ², p) of the white's departure from R+G+B (:func:`white_against_sum`) on 3 dof."""
    chi2 = float(difference @ np.linalg.solve(covariance, difference))
    # the noise is estimated: F, not χ²
    return chi2, f_sf(chi2 / 3, 3, _scale_dof(noise, covariance, chromatic))


def additivity_p_value(context: DiagnosisContext) -> float | None:
    """The p-value of :func:`detect_channel_interaction`'s test (None where no white was
    measured): how well the white less the black is the sum of the full-drive primaries."""
    if context.white_count == 0:
        return None
    white, summed, covariance, chromatic = white_against_sum(context)
    return _additivity_test(context.noise, white - summed, covariance, chromatic)[1]


def detect_channel_interaction(context: DiagnosisContext) -> DetectorResult:
    if context.white_count == 0:
        return _untestable("channel-interaction", "no white measured beside the primaries")
    white, summed, covariance, chromatic = white_against_sum(context)
    chi2, p = _additivity_test(context.noise, white - summed, covariance, chromatic)
    placed = _placements_of_uncertain_primaries(context)
    ramp_p = p
    if placed:
        # the change between two references came at an unknown moment: an interaction must show
        # wherever it came, so the white is also tested against each primary corrected as if the
        # change came before it or after it (a step's error is all or nothing, not Gaussian)
        p = max([p] + [_additivity_test(context.noise, white - alternative, covariance,
                                        chromatic)[1] for alternative in placed])
    placement = (f", p {p:.2g} at the least favourable moment of the drift's change for the "
                 "primaries read between two references that disagree" if p > ramp_p else "")
    placed_p = p
    for channel, departure, z_off, alternative, alternative_covariance in \
            primaries_off_their_sweeps(context, summed, covariance):
        # a full-drive reading far off its own sweep's top levels is the reading's, not the
        # panel's: the white must also stand off the sum with that primary read from its sweep
        p = max(p, _additivity_test(context.noise, white - alternative, alternative_covariance,
                                    chromatic)[1])
        if p > placed_p:
            placement += (f", p {p:.2g} with the {CHANNEL_NAMES[channel]} primary read from its "
                          f"own sweep's top levels (its full-drive reading {100 * departure:+.1f} "
                          f"% off them, {z_off:.1f} σ)")
            placed_p = p
    ratio = white / summed
    statistic = 1.0 - float(ratio[1])
    standard_error = float(np.sqrt(covariance[1, 1]) / summed[1])
    direction = "falls short of" if ratio[1] < 1 else "exceeds"
    common = common_gain_test(context)
    evidence = (f"white measures {100 * ratio[1]:.1f} % of R+G+B in luminance "
                f"(X {100 * ratio[0]:.1f} %, Z {100 * ratio[2]:.1f} %, black subtracted; "
                f"± {100 * standard_error:.2f} %, χ² {chi2:.1f} on 3 dof{placement}): the "
                f"full-drive mixture {direction} the sum of its primaries; "
                + ("channel by channel (one gain common to every channel leaves χ² "
                   f"{common.chi2:.1f} on 2 dof, p {common.p_value:.2g}; the channels' own "
                   f"shortfalls {', '.join(f'{100 * a:.1f}' for a in common.amounts)} % against "
                   f"{100 * (1 - common.gain):.1f} % common: subpixel crosstalk)"
                   if common.channel_specific else
                   "as one gain on every channel (the channels' own shortfalls "
                   f"{', '.join(f'{100 * a:.1f}' for a in common.amounts)} % against "
                   f"{100 * (1 - common.gain):.1f} % common: a backlight or a power limit)"))
    z = z_of_chi2(chi2, 3)
    details = {"white_over_sum": ratio.tolist(), "chi2": chi2,
               "common_gain_chi2": common.chi2, "common_gain_p": common.p_value,
               "channel_specific": common.channel_specific}
    greys = greys_against_sum(context)
    if greys is not None:
        # two parts, the white and the greys at partial drive: Bonferroni over the two
        p = min(1.0, 2.0 * min(p, greys.p_value))
        z = max(z, greys.z) if p < 1e-15 else z_of_p(p)
        evidence += (f"; the {greys.count} greys above {100 * GREY_SUM_MIN_DRIVE:.0f} % drive measure "
                     f"{100 * greys.ratio:.1f} % of the sum of their channels' sweeps at the same "
                     f"drive (from {100 * greys.low:.1f} to {100 * greys.high:.1f} %; χ² "
                     f"{greys.chi2:.1f} on {greys.dof} dof, p {greys.p_value:.2g})")
        details.update({"greys_over_sum": greys.ratio, "greys_chi2": greys.chi2,
                        "greys_dof": greys.dof, "greys_p": greys.p_value,
                        "greys_ratio_range": [greys.low, greys.high]})
    return _result("channel-interaction", statistic, standard_error, p, evidence, details, z=z)


@dataclass(frozen=True)
class GreysAgainstSum:
    """Greys at partial drive against the sum of their channels' sweeps at the same drive."""

    count: int
    chi2: float
    dof: int
    p_value: float
    ratio: float  # mean luminance of the greys over the sums
    low: float
    high: float

    @property
    def z(self) -> float:
        return z_of_chi2(self.chi2, self.dof)


GREY_SUM_MIN_DRIVE = 0.2
"""Greys below this drive are left out of the additivity test: their sums are a few percent of
white, where the black's error and a drive-dependent chromaticity (a bluish black beside a
desaturation toward white: a false interaction at p 0.0004 from greys at 13–19 % drive) weigh
more than any interaction (a crosstalk or backlight grows with drive: still named 6/6)."""

GREY_SUM_MAX_GAP = 16
"""A grey is tested only where sweep points of every channel lie within this many DAC counts on
both sides (the sums are interpolated between them, log-log: exact for a local power law)."""


def _sweep_at(sweep: ChannelSweep, drive: float) -> np.ndarray | None:
    """The channel's black-subtracted XYZ at ``drive`` between the neighbouring points (Y log-log,
    X/Y and Z/Y linearly)."""
    d = sweep.drive
    if np.any(np.isclose(d, drive, rtol=0, atol=1e-9)):
        return sweep.XYZ[int(np.argmin(np.abs(d - drive)))]
    below, above = d[d < drive], d[d > drive]
    if not below.size or not above.size:
        return None
    lo, hi = int(np.flatnonzero(d == below.max())[0]), int(np.flatnonzero(d == above.min())[0])
    if 255 * (d[hi] - d[lo]) > 2 * GREY_SUM_MAX_GAP:
        return None
    a, b = sweep.XYZ[lo], sweep.XYZ[hi]
    if a[1] <= 0 or b[1] <= 0:
        u = (drive - d[lo]) / (d[hi] - d[lo])
        return a + u * (b - a)
    # the luminance log-log, each tristimulus value's share of it linearly: a red primary's Z or a
    # blue one's X near zero may read at or below it after the black is subtracted, and a straight
    # chord of all three (as the fallback once was) lies up to 9 % above a gamma-2.4 curve midway
    # through a 32-DAC gap, a false interaction on the sparse sweeps of the adaptive plan
    u = np.log(drive / d[lo]) / np.log(d[hi] / d[lo])
    Y = float(np.exp(np.log(a[1]) + u * (np.log(b[1]) - np.log(a[1]))))
    return (a / a[1] + u * (b / b[1] - a / a[1])) * Y


def greys_against_sum(context: DiagnosisContext) -> GreysAgainstSum | None:
    """The greys' additivity test, or None where fewer than three greys can be tested.

    ``G − K − Σ_c (S_c(d) − K)`` for each grey ``G`` at drive ``d`` above
    :data:`GREY_SUM_MIN_DRIVE`, ``S_c(d)`` the channel's sweep at the same
    drive; χ² with the full covariance (each grey's and each interpolated
    sweep point's own, and four times the black's, shared by every grey),
    F-tested on the noise estimate's dof. A display whose channels add up at
    full drive but not below (drive-dependent crosstalk, a backlight that
    follows the mean drive) fails it.
    """
    rgb = context.fit.rgb
    greys = np.flatnonzero(partial_greys(rgb) & ~context.copies
                           & (rgb[:, 0] / 255.0 > GREY_SUM_MIN_DRIVE))
    if greys.size < 3 or len(context.sweeps) != 3:
        return None
    rows, sums = [], []
    for index in greys:
        drive = rgb[index, 0] / 255.0
        parts = [_sweep_at(s, drive) for s in context.sweeps]
        if any(part is None for part in parts):
            continue
        rows.append(index)
        sums.append(parts)
    if len(rows) < 3:
        return None
    noise = context.noise
    grey_XYZ = context.fit.XYZ[rows]
    sums = np.asarray(sums)  # (n, 3 channels, 3 XYZ)
    difference = (grey_XYZ - context.black - sums.sum(axis=1)).reshape(-1)
    n = len(rows)
    # where drift was corrected, the correction's own uncertainty (a change at an unknown moment
    # between two references) on the grey and on each sweep point, relative to each
    drifting = context.drift_found and context.drift is not None and context.fit.t_s is not None
    grey_u = (context.drift.uncertainty(context.fit.t_s[rows]) if drifting else np.zeros(n))
    grey_curve = curve_variance(context, context.fit.t_s[rows] if drifting else None, n)
    unexplained = unexplained_gain_variance(context)  # a drift not found: a gain on each reading
    covariance = np.zeros((3 * n, 3 * n))
    for i in range(n):
        block = noise.covariance(grey_XYZ[i]) + (grey_u[i] ** 2 + grey_curve[i] + unexplained) * (
            np.outer(grey_XYZ[i], grey_XYZ[i]))
        for sweep, part in zip(context.sweeps, sums[i]):
            block = block + noise.covariance(part + context.black) + unexplained * np.outer(part, part)
            if sweep.correction_sd is not None:
                level = int(np.argmin(np.abs(sweep.drive - rgb[rows[i], 0] / 255.0)))
                u2 = sweep.correction_sd[level] ** 2 + curve_variance(
                    context, None if sweep.times is None else sweep.times[level:level + 1], 1)[0]
                block = block + u2 * np.outer(part, part)
        covariance[3 * i:3 * i + 3, 3 * i:3 * i + 3] = block
    shared = 4.0 * mean_covariance(noise, context.black, context.black_count)
    covariance += np.kron(np.ones((n, n)), shared)
    chi2 = float(difference @ np.linalg.solve(covariance, difference))
    dof = 3 * n
    p = f_sf(chi2 / dof, dof, noise.dof if np.isfinite(noise.dof) else 10 ** 6)
    ratios = (grey_XYZ[:, 1] - context.black[1]) / sums[:, :, 1].sum(axis=1)
    return GreysAgainstSum(count=n, chi2=chi2, dof=dof, p_value=float(p),
                           ratio=float(np.mean(ratios)), low=float(ratios.min()),
                           high=float(ratios.max()))


def _placements_of_uncertain_primaries(context: DiagnosisContext) -> list[np.ndarray]:
    """R+G+B with each primary read between two references that disagree corrected by the one
    reference's gain or the other's instead of the ramp between them (every combination but the
    ramp's); empty where no primary's correction is uncertain."""
    drift = context.drift
    if not context.drift_found or drift is None:
        return []
    options = []
    for sweep in context.sweeps:
        t = None if sweep.times is None else float(sweep.times[-1])
        if sweep.correction_sd is None or t is None or not sweep.correction_sd[-1] > 0:
            options.append([sweep.full_XYZ])
            continue
        g = float(drift.gain(t))
        options.append([sweep.full_XYZ] + [sweep.full_XYZ * g / side
                                           for side in drift.gains_around(t)])
    if all(len(o) == 1 for o in options):
        return []
    return [sum(choice) for choice in product(*options)][1:]


PRIMARY_OFF_SWEEP_Z = 3.5
"""A full-drive primary whose luminance stands more than this many standard deviations off the
log-log extrapolation of its own sweep's top levels (:func:`primaries_off_their_sweeps`) is
also replaced by that extrapolation in the additivity test: instrument readings have heavier
tails than a Gaussian, and one primary read once and far off would otherwise name a channel
interaction that its own sweep and the greys deny."""

PRIMARY_SWEEP_TOP = 0.8
"""The sweep levels from which a full-drive primary is extrapolated: drive at least this and
below full drive (the paper's plan and the authors' hold ten, DAC 205–250)."""

PRIMARY_SWEEP_LEVELS = 5
"""Fewest such levels for the extrapolation (a chart with a few levels a channel has none)."""

PRIMARY_SWEEP_DEGREE = 2
"""Degree of the log-log polynomial extrapolated to full drive: a straight line is exact for a
local power law but not for a shoulder, whose compression near full drive put all three
primaries of an additive display with a shoulder 1.6–3.3 % below it."""


def primaries_off_their_sweeps(context: DiagnosisContext, summed: np.ndarray,
                               covariance: np.ndarray) -> list:
    """Primaries whose full-drive reading stands off their own sweep's top levels.

    Each channel's top levels (:data:`PRIMARY_SWEEP_TOP`, at least
    :data:`PRIMARY_SWEEP_LEVELS` of them) are fitted log-log, the log of X, Y and Z each a
    polynomial of degree :data:`PRIMARY_SWEEP_DEGREE` in ``log d`` weighted by the readings'
    noise, and extrapolated to full drive; where the full-drive reading's luminance stands more than
    :data:`PRIMARY_OFF_SWEEP_Z` standard deviations (reading and extrapolation together) off it,
    the primary is listed as ``(channel, relative departure, z, Σ with it replaced by the
    extrapolation, the covariance with its reading's part replaced by the extrapolation's)``.
    """
    noise = context.noise
    listed = []
    for sweep in context.sweeps:
        top = (sweep.drive >= PRIMARY_SWEEP_TOP) & (sweep.drive < 1.0)
        if int(top.sum()) < PRIMARY_SWEEP_LEVELS or np.any(sweep.XYZ[top] <= 0) \
                or np.any(sweep.full_XYZ <= 0):
            continue
        counts = np.ones(sweep.drive.size) if sweep.counts is None else sweep.counts
        x = np.log(sweep.drive[top])
        read_Y = sweep.XYZ[top, 1] + context.black[1]
        weights = counts[top] / np.maximum(noise.relative_sd_Y(read_Y), 1e-12) ** 2
        design = np.column_stack([x ** k for k in range(PRIMARY_SWEEP_DEGREE + 1)])
        inverse = np.linalg.inv(design.T @ (weights[:, None] * design))
        coefficients = inverse @ (design.T @ (weights[:, None] * np.log(sweep.XYZ[top])))
        predicted = np.exp(coefficients[0])  # at log d = 0
        predicted_variance = float(inverse[0, 0])  # relative, of log Y
        full_read = sweep.full_XYZ + context.black
        read_variance = float(noise.relative_sd_Y(full_read[1]) ** 2) / max(sweep.full_count, 1)
        departure = float(sweep.full_XYZ[1] / predicted[1] - 1.0)
        z = float(np.log(sweep.full_XYZ[1] / predicted[1])
                  / np.sqrt(predicted_variance + read_variance))
        if abs(z) <= PRIMARY_OFF_SWEEP_Z:
            continue
        own = mean_covariance(noise, full_read, sweep.full_count)
        replaced = covariance - own + own * (predicted_variance / read_variance)
        listed.append((sweep.channel, departure, abs(z), summed - sweep.full_XYZ + predicted,
                       replaced))
    return listed


def white_against_sum(context: DiagnosisContext):
    """(white − black, Σ black-subtracted full primaries, covariance of their difference, its
    chromaticity-noise part).

    ``W − K − Σ(P − K) = W + 2K − ΣP``: the white's covariance, four times the
    black's and each primary's, each at its own measured XYZ (so a deep blue
    carries the large X and Z uncertainty its small y gives it), and what the session's drift
    adds to each primary (:func:`primary_drift_covariance`) and to the whites.
    """
    noise = context.noise
    summed = sum(s.full_XYZ for s in context.sweeps)  # black subtracted
    white = context.white - context.black
    measured = [(context.white, context.white_count, 1.0),
                (context.black, context.black_count, 4.0)]
    measured += [(s.full_XYZ + context.black, s.full_count, 1.0) for s in context.sweeps]
    covariance = sum(w * mean_covariance(noise, XYZ, n) for XYZ, n, w in measured)
    covariance = covariance + sum(primary_drift_covariance(context, s) for s in context.sweeps)
    chromatic = sum(w * _mean_chromaticity_covariance(noise, XYZ, n) for XYZ, n, w in measured)
    drifting = unexplained_gain_variance(context)
    if drifting > 0:  # the whites were read at other moments than the primaries (theirs above)
        covariance = covariance + drifting * (
            np.outer(context.white, context.white) / max(context.white_count, 1))
    return white, summed, covariance, chromatic


def curve_variance(context: DiagnosisContext, t_s, size: int) -> np.ndarray:
    """Relative variance (``size``,) that the drift curve's own noise adds to rows corrected at
    ``t_s`` (:meth:`~workbench.diagnostics.evidence.DriftCorrection.curve_sd`); zeros where no
    drift was corrected or ``t_s`` is None.

    A row is corrected by the curve at its moment, and where the curve follows a reference that
    read low, every row measured then is corrected too far. Through the CS-2000 protocol, on the
    authors' plan beside a warm-up at 0.46 % noise (peer seed 62003), a white read 1.7 % low
    (3.6 σ), the curve followed it part way, and the red primary read 3 s later was corrected
    1.2 % too far; its uncertainty had been the moment of change alone (0.07 %), and the white
    against R+G+B named a channel interaction (χ² 16.3 on 3 dof). With the curve's own 0.37 %
    the drift is named alone. Only the additivity tests carry it: carried into the extension's
    fit and the tone test through the correction's uncertainty, it moved the model choice of
    warm-ups for the worse (seed 62002 on the authors' plan, 0.021 → 0.068 ΔE00 against the
    authors' 0.051).
    """
    if t_s is None or not context.drift_found or context.drift is None:
        return np.zeros(size)
    return context.drift.curve_sd(t_s) ** 2


def primary_correction_covariance(sweep: ChannelSweep) -> np.ndarray:
    """Covariance the drift correction's own uncertainty adds to a sweep's full-drive primary
    (zero where no drift was corrected or the primary was read at a reference's moment).

    A primary read between two references across which a step came is corrected by a ramp
    between them, off by up to half the step: on the seed authors' plan a bluish black beside a
    7 % step (peer bench seed 45007) read its green primary 0.97 % uncertain that way, and the
    white against R+G+B, tested without it, named a channel interaction at z 2.9 from a 0.9 %
    green shortfall. The greys' test carries the same uncertainty on each sweep point."""
    if sweep.correction_sd is None:
        return np.zeros((3, 3))
    u = float(sweep.correction_sd[-1])  # the last level is full drive (channel_sweeps)
    return u ** 2 * np.outer(sweep.full_XYZ, sweep.full_XYZ)


def primary_drift_covariance(context: DiagnosisContext, sweep: ChannelSweep) -> np.ndarray:
    """Covariance the session's drift adds to a sweep's full-drive primary: where a drift was
    corrected, the correction's own uncertainty at the primary's moment
    (:func:`primary_correction_covariance`) and the drift curve's noise there
    (:func:`curve_variance`); where none was, the output's change that no correction took out
    (:func:`unexplained_gain_variance`), as a gain.

    One covariance for both places that read it: the white against R+G+B
    (:func:`white_against_sum`) and the step that moves each primary by its share of the white's
    departure (:func:`~workbench.diagnostics.extension.white_constrained`), so each primary's
    share is its own part of the test's covariance. The step had read the moment of change
    alone: with the curve's noise and the unexplained change as well, on the diagnosis suite's
    940 sessions every finding stayed and 25 moved by more than 0.005 mean ΔE00 on validation
    colours, 21 of them better (a log desaturation beside scattering whites 0.185 → 0.126, a
    wander 0.153 → 0.126), the most worse 0.138 → 0.144; mean 0.18303 → 0.18270."""
    curve = curve_variance(context, None if sweep.times is None else sweep.times[-1:], 1)[0]
    gain = curve + unexplained_gain_variance(context)
    return primary_correction_covariance(sweep) + gain * np.outer(sweep.full_XYZ, sweep.full_XYZ)


def unexplained_gain_variance(context: DiagnosisContext) -> float:
    """Relative variance of the display's output over the session that no drift correction takes
    out: where ``temporal-drift`` was not found, the white references' scatter beyond their noise
    (0 where it was found, the rows then being corrected, or where the whites scatter no more
    than noise).

    A warm-up too slow or too noisy for the drift test still moves every reading with it, so a
    primary read at one moment and a white or grey read at another differ by the change between
    them: the additivity tests (the white against R+G+B, the greys against their channels'
    sweeps) carry it as a gain on each reading. Without it, an adaptive session's warm-up (2.5 %
    over six whites at 0.34 % noise, the drift test at z 2.1, short of its 2.33) was named a
    channel interaction: its primaries were read early and dim, its whites later.
    """
    drift = context.drift
    if context.drift_found or drift is None or drift.gains.size < 3:
        return 0.0
    relative_sd = context.noise.sd_Y(drift.luminances) / drift.luminances
    return max(0.0, float(np.var(drift.gains, ddof=1) - np.mean(relative_sd ** 2)))


def beyond_noise_gain_variance(context: DiagnosisContext) -> float:
    """:func:`unexplained_gain_variance` where the white references scatter about their mean
    beyond their noise at :data:`~workbench.diagnostics.significance.FAMILY_ALPHA` (χ² on
    n − 1 dof), else 0: for the tone test, whose sweeps such a gain bends as their levels are
    measured one after another.

    The noise model reads the sweeps' scatter from differences of levels measured one after
    another, which a gain that moves over a few readings leaves untouched; the whites, minutes
    apart, show it. The peer bench's ``correlated-noise`` probe (a slow gain as large as the gain
    noise, carried from reading to reading; seeds 84000–84004, every form, three plans) had a
    finding not injected on 32 of its 345 sessions, most of them a ``tone-curve-shape``; with
    each sweep level carrying this variance, 23. Untested (the variance the whites' chance
    scatter leaves above their noise in about half of all sessions) it weakened the test
    everywhere: seven knees of the generator's own 4134 peer sessions lost the bend they put
    on the sweeps, reported as the interaction's consequence; tested, two do, and nothing else
    moved there, on the 940-session suite or on the 86 real displays. Through the CS-2000
    emulator (``bench plans``, 150 sessions) one paper-plan wander that the drift test did not
    find lost the ``tone-curve-shape`` it had been given, and the extension's tone curves with
    it, which had taken up part of the wander (0.140 → 0.166 mean ΔE00 on hidden colours).
    """
    drift = context.drift
    unexplained = unexplained_gain_variance(context)
    if unexplained <= 0:
        return 0.0
    relative_sd = context.noise.relative_sd_Y(drift.luminances)
    chi2 = float(np.sum(((drift.gains - np.mean(drift.gains)) / relative_sd) ** 2))
    return unexplained if chi2_sf(chi2, drift.gains.size - 1) < FAMILY_ALPHA else 0.0


CHANNEL_SPECIFIC_ALPHA = 0.001
"""Level at which the white's departure from the sum of the primaries is called channel by
channel rather than one gain common to every channel (strict: the call gives an interaction a
shape that reaches every mixture, so a full-drive primary read a few σ off by heavy-tailed
instrument noise must not make it)…"""

CHANNEL_SPECIFIC_SHARE = 0.5
"""…and only where the channels' own amounts depart from the common one by more than this share
of it (a power limit whose white is a trace bluer than R+G+B is still a common gain)."""


@dataclass(frozen=True)
class CommonGainTest:
    """Whether the white's departure from R+G+B is one gain on every channel (``W − K = g Σ``)."""

    gain: float
    chi2: float  # left by the best common gain, 2 dof
    p_value: float
    amounts: tuple = (0.0, 0.0, 0.0)  # each channel's own shortfall at white, 1 − (W−K)/P solved

    @property
    def spread(self) -> float:
        """Largest departure of a channel's own amount from the common one (``1 − gain``)."""
        return float(np.max(np.abs(np.asarray(self.amounts) - (1.0 - self.gain))))

    @property
    def channel_specific(self) -> bool:
        return (self.p_value <= CHANNEL_SPECIFIC_ALPHA
                and self.spread > CHANNEL_SPECIFIC_SHARE * abs(1.0 - self.gain))


def common_gain_test(context: DiagnosisContext) -> CommonGainTest | None:
    """Generalized least squares of ``W − K`` on ``g Σ(P − K)``; F-test of what is left.

    A backlight that follows the picture and a power limit scale every
    channel alike: the white keeps the chromaticity of the primaries' sum.
    Subpixel crosstalk couples each channel to its neighbours by its own
    amount and moves it. None without a white.
    """
    if context.white_count == 0:
        return None
    white, summed, covariance, chromatic = white_against_sum(context)
    inverse = np.linalg.inv(covariance)
    gain = float(summed @ inverse @ white / (summed @ inverse @ summed))
    left = white - gain * summed
    chi2 = float(left @ inverse @ left)
    matrix = np.column_stack([s.full_XYZ for s in context.sweeps])
    amounts = tuple(float(a) for a in 1.0 - np.linalg.solve(matrix, white))
    # what the fit leaves: (I − H) white, H the generalized least squares projector onto Σ
    projector = np.eye(3) - np.outer(summed, summed @ inverse) / float(summed @ inverse @ summed)
    dof = _scale_dof(context.noise, covariance, chromatic, projector)
    return CommonGainTest(gain=gain, chi2=chi2, p_value=f_sf(chi2 / 2, 2, dof), amounts=amounts)


BLACK_PRIOR_INFLATION = 9.0
"""The chromaticity test's prior on the error of the subtracted black is the noise model's
covariance of the black's mean times this (its SD three times): the floor is estimated from a
session's dark points and blacks, often one black, and a black read 1.5σ of the true floor off
in X and Z, against a floor estimated at a third of it, had moved every dark sweep point's xy
alike and read as a shift (6 of the 11 false `chromaticity-shift` in the 940-session suite, 4
beside other effects on one display of the peer bench). A real shift is still told from a black
error by its shape: a black error moves xy as 1/(X + Y + Z), a leak or a desaturation as the
drive falls (every injected shift of the suite is named as before)."""


def _chromaticity_test(sweep: ChannelSweep, context: DiagnosisContext,
                       leave_out: int | None = None):
    """(p, distance, its SE, lowest drive, coefficients (2, 2), z, (most deviant point, its
    distance in σ)) of one channel, or None; ``leave_out``: a point (index into the sweep) left
    out, and then no deviant point (None). The most deviant point is the one farthest from the
    fit with no shift (its xy residual in units of its own covariance, √ of a 2-dof χ²).

    Generalized least squares of the points' xy on ``1, u, u²`` (``u = 1 − d``)
    with each point's xy covariance, plus three nuisance parameters for the
    error of the subtracted black (one error shared by every point, with its
    own prior covariance): a black that is a little off moves the xy of dark
    points along a smooth curve, which must not pass for a shift.
    """
    usable = sweep.output >= MIN_CHROMATICITY_OUTPUT
    if leave_out is not None:
        usable[leave_out] = False
    if usable.sum() < 4:
        return None
    black_cov = mean_covariance(context.noise, context.black, context.black_count)
    u = 1.0 - sweep.drive[usable]
    xy = xy_of(sweep.XYZ[usable])
    points = int(usable.sum())
    blocks, covariance = [], np.zeros((2 * points, 2 * points))
    toward_black = np.zeros((points, 2))  # xy moved per unit drift-correction error
    for i, index in enumerate(np.flatnonzero(usable)):
        subtracted = sweep.XYZ[index]
        total = float(np.sum(subtracted))
        x, y = subtracted[0] / total, subtracted[1] / total
        jacobian = np.array([[1 - x, -x, -x], [-y, 1 - y, -y]]) / total
        covariance[2 * i:2 * i + 2, 2 * i:2 * i + 2] = jacobian @ mean_covariance(
            context.noise, subtracted + context.black, int(sweep.counts[index])) @ jacobian.T
        design = np.zeros((2, 9))
        design[0, :3] = [1.0, u[i], u[i] ** 2]
        design[1, 3:6] = [1.0, u[i], u[i] ** 2]
        design[:, 6:] = -jacobian  # xy moves by −J·δK when the black is off by δK
        blocks.append(design)
        # a drift correction off by δ scales the black with the light: after the black is
        # subtracted, δ·K is left, which moves xy by δ·J·K (toward the black's chromaticity)
        toward_black[i] = jacobian @ context.black
    if sweep.times is not None and context.drift is not None:
        # those errors are alike on the levels measured one after another between two
        # references (DriftCorrection.bridge_covariance): a smooth path, not noise
        bridge = context.drift.bridge_covariance(sweep.times[usable])
        covariance += (np.einsum("ia,jb->iajb", toward_black, toward_black)
                       * bridge[:, None, :, None]).reshape(2 * points, 2 * points)
    whitening = np.linalg.inv(np.linalg.cholesky(covariance))
    rows = [whitening @ np.vstack(blocks)]
    targets = [whitening @ xy.reshape(-1)]
    if context.black_count:
        prior = np.linalg.inv(np.linalg.cholesky(BLACK_PRIOR_INFLATION * black_cov
                                                 + 1e-30 * np.eye(3)))
        black_rows = np.zeros((3, 9))
        black_rows[:, 6:] = prior
        rows.append(black_rows)
        targets.append(np.zeros(3))
    design = np.vstack(rows)
    target = np.concatenate(targets)
    if not context.black_count:
        design = design[:, :6]
    full, *_ = np.linalg.lstsq(design, target, rcond=None)
    keep = [0, 3] + list(range(6, design.shape[1]))
    null_design = design[:, keep]
    null, *_ = np.linalg.lstsq(null_design, target, rcond=None)
    rss_full = float(np.sum((design @ full - target) ** 2))
    rss_null = float(np.sum((null_design @ null - target) ** 2))
    dof = 2 * int(usable.sum()) - 6
    scale = max(1.0, rss_full / dof) if dof > 0 else 1.0
    f_value = (rss_null - rss_full) / 4 / scale
    p = f_sf(f_value, 4, max(dof, 1))
    coefficients = np.array([[full[1], full[4]], [full[2], full[5]]])
    u0 = float(u.max())
    shift = u0 * coefficients[0] + u0 ** 2 * coefficients[1]
    distance = float(np.hypot(*shift))
    parameter_cov = np.linalg.pinv(design.T @ design) * scale
    gradient = np.zeros(design.shape[1])
    if distance > 0:
        direction = shift / distance
        gradient[[1, 2]] = direction[0] * np.array([u0, u0 ** 2])
        gradient[[4, 5]] = direction[1] * np.array([u0, u0 ** 2])
    standard_error = float(np.sqrt(max(gradient @ parameter_cov @ gradient, 0.0)))
    z = z_of_chi2(4 * f_value, 4)
    if leave_out is not None:  # the second test reads p alone
        return p, distance, standard_error, 1.0 - u0, coefficients, z, None
    # each point's distance from the fit with no shift, in units of its own xy covariance
    residual = xy - (np.vstack(blocks)[:, keep] @ null).reshape(points, 2)
    own = np.stack([covariance[2 * i:2 * i + 2, 2 * i:2 * i + 2] for i in range(points)])
    distances = np.sqrt(np.einsum("ia,ia->i", residual,
                                  np.linalg.solve(own, residual[:, :, None])[:, :, 0]))
    deviant = int(np.argmax(distances))
    return (p, distance, standard_error, 1.0 - u0, coefficients, z,
            (int(np.flatnonzero(usable)[deviant]), float(distances[deviant])))


MIN_ROBUST_CHROMATICITY_POINTS = 8
"""Usable sweep points (:data:`~workbench.diagnostics.evidence.MIN_CHROMATICITY_OUTPUT`) from
which a channel's chromaticity shift must also hold without its most deviant point
(:func:`_robust_chromaticity_test`; a DisplayCAL chart's four levels a channel keep the test as
it was). At the dark end the shift's quadratic has its leverage, and one heavy-tailed reading
there had made a shift: on fresh peer-bench seeds 59000–59009 (690 sessions) beside every drift
form of one display and an S-curve and a soft toe of another on the paper plan (7 sessions with
a false finding, now none), on the peer bench's 636 drift sessions 4 beside drifts on the
authors' plan (false-finding sessions 7 → 3, no score changed), on the 940-session suite one
beside a crosstalk (10 → 9, every other figure and score the same); every injected shift is
named as before. The four paper-plan drift sessions of one display scored worse without the
false term (0.093 → 0.107 mean ΔE00 on hidden colours, 0.171 → 0.288 for a wander no drift test
finds). On the public collection's 80 charts no score changed, and a shift that was never in the
exported model is no longer named on four of them (one reading carried it); the six real files
are unchanged."""


def _robust_chromaticity_test(sweep: ChannelSweep, context: DiagnosisContext):
    """:func:`_chromaticity_test`, or the same without the channel's most deviant point where
    that one is within :data:`OUTLIER_SIGMA` and the test so is less significant: one reading is
    not a shift, as it is not a drift (farther off than that it is no reading a heavy-tailed
    instrument gives). Not run where the channel's p is above
    :data:`~workbench.diagnostics.significance.FAMILY_ALPHA`: no finding can come of it there
    (profiled on 12 drift sessions, the chromaticity test took 5.2 % of their diagnosis with a
    second test on every channel, 2.7 % so)."""
    test = _chromaticity_test(sweep, context)
    if test is None:
        return None
    index, sigmas = test[6]
    usable = int(np.sum(sweep.output >= MIN_CHROMATICITY_OUTPUT))
    if (test[0] > FAMILY_ALPHA  # not significant whatever one point does: no second test
            or usable < MIN_ROBUST_CHROMATICITY_POINTS or sigmas >= OUTLIER_SIGMA):
        return test
    without = _chromaticity_test(sweep, context, leave_out=index)
    return test if without is None or without[0] <= test[0] else without


def detect_chromaticity_shift(context: DiagnosisContext) -> DetectorResult:
    tests = [_robust_chromaticity_test(s, context) for s in context.sweeps]
    tested = [t for t in tests if t is not None]
    if not tested:
        return _untestable("chromaticity-shift", "no sweep has 4 levels above 2 % of its "
                                                 "full output")
    p_values = [t[0] if t is not None else 1.0 for t in tests]
    worst = int(np.argmin(p_values))
    p = min(1.0, len(tested) * p_values[worst])
    _, distance, standard_error, level, _, z, _ = tests[worst]
    evidence = (f"the {CHANNEL_NAMES[worst]} primary's chromaticity (black subtracted) moves by "
                f"Δxy {distance:.4f} ± {standard_error:.4f} between full drive and DAC "
                f"{255 * level:.0f}; per channel "
                + ", ".join(f"{CHANNEL_NAMES[c][0].upper()} "
                            + ("—" if t is None else f"{t[1]:.4f}") for c, t in enumerate(tests)))
    return _result("chromaticity-shift", distance, standard_error, p, evidence,
                   {"shift_xy": [0.0 if t is None else t[1] for t in tests],
                    "p_per_channel": p_values}, z=z)


def tone_data(sweep: ChannelSweep, extra: tuple[np.ndarray, np.ndarray] | None = None):
    """(drive, output) of a channel, optionally with grey-derived points."""
    drive, output = sweep.drive, sweep.output
    if extra is not None:
        drive = np.concatenate([drive, extra[0]])
        output = np.concatenate([output, extra[1]])
    order = np.argsort(drive, kind="stable")
    return drive[order], output[order]


def _shape(form: str, d: np.ndarray, p: np.ndarray) -> np.ndarray:
    if form == "power":
        return d ** p[0]
    if form == "gog":
        return np.maximum(0.0, (1 - p[1]) * d + p[1]) ** p[0]
    safe = np.maximum(d, 1e-6)
    if form == "power-harmonic":
        return safe ** p[0] + p[1] * np.sin(np.pi * d) + p[2] * np.sin(2 * np.pi * d)
    return np.where(d > 0, safe ** (p[0] + p[1] * np.log(safe)), 0.0)


_SHAPE_START = {"power": ([2.2], [0.2], [8.0]), "gog": ([2.2, 0.0], [0.2, -0.5], [8.0, 0.5]),
                "extended-power": ([2.2, 0.0], [0.2, -2.0], [8.0, 2.0]),
                "power-harmonic": ([2.2, 0.0, 0.0], [0.2, -0.5, -0.5], [8.0, 0.5, 0.5])}

TONE_ALTERNATIVES = {"gog": 1, "extended-power": 1, "power-harmonic": 2}
"""The shapes a sweep is tested against the power law with, and their extra parameters: GOG
(an offset at the toe), extended power (a gamma that changes with level: shoulders, crushed
toes) and the power law plus the first two sine harmonics of drive (zero at both ends: an S,
a bump, a shape neither of the others bends to). Each F-test's p-value is multiplied by their
number (Bonferroni), so trying three shapes does not buy a finding."""

LACK_OF_FIT = "lack-of-fit"
"""The tone test's name for a sweep no power law fits within the noise, whatever the shape."""


def _shape_derivatives(form: str, d: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``∂ _shape(form, d, p) / ∂p``, one column a parameter: the fits' Jacobian in closed form.

    Finite differences cost a third of the tone test (each of a session's folds fits four shapes
    to three sweeps). With the closed form the diagnosis suite's 940 sessions, the peer bench's
    636 drift sessions, the six real files and the 76 public charts give the same findings, the
    same models and the same scores. With the closed-form gamma fit beside it, a suite session
    took 0.51 s where it took 0.57 (both codes run side by side on one machine).
    """
    if form == "gog":
        base = (1 - p[1]) * d + p[1]
        inside = base > 0
        safe = np.where(inside, base, 1.0)
        return np.column_stack([np.where(inside, safe ** p[0] * np.log(safe), 0.0),
                                np.where(inside, p[0] * safe ** (p[0] - 1) * (1 - d), 0.0)])
    safe = np.maximum(d, 1e-6)
    log = np.log(safe)
    if form == "power":
        return np.where(d > 0, d ** p[0] * log, 0.0)[:, None]
    if form == "power-harmonic":
        return np.column_stack([safe ** p[0] * log, np.sin(np.pi * d), np.sin(2 * np.pi * d)])
    value = np.where(d > 0, safe ** (p[0] + p[1] * log), 0.0)
    return np.column_stack([value * log, value * log ** 2])


def _fit_shape(form, drive, Y, sd, black_guess, full_guess):
    """Least squares of ``form`` through the points; ``sd`` per point, or a whitening matrix
    (the inverse Cholesky factor of the points' covariance) where their errors are correlated."""
    start, low, high = _SHAPE_START[form]
    whitening = np.asarray(sd) if np.ndim(sd) == 2 else None

    def residual(q):
        difference = q[0] + q[1] * _shape(form, drive, q[2:]) - Y
        return difference / sd if whitening is None else whitening @ difference

    def jacobian(q):
        columns = np.column_stack([np.ones_like(drive), _shape(form, drive, q[2:]),
                                   q[1] * _shape_derivatives(form, drive, q[2:])])
        return columns / np.asarray(sd)[:, None] if whitening is None else whitening @ columns

    result = least_squares(residual, x0=[black_guess, full_guess, *start], jac=jacobian,
                           bounds=([-np.inf, 0.0, *low], [np.inf, np.inf, *high]))
    return result.x, float(np.sum(result.fun ** 2))


def _grey_points(context: DiagnosisContext):
    """(drive, per-channel outputs (n, 3), their standard deviations (n, 3)) from the greys, or None.

    Each grey's black-subtracted XYZ is solved for the three channel outputs
    through the full-drive primaries scaled so that they add up to the white
    (white vs R + G + B is the interaction's test, not this one); the outputs
    carry the grey's relative luminance noise plus the floor over each
    primary's luminance.
    """
    rgb = context.fit.rgb
    greys = partial_greys(rgb) & ~context.copies
    if greys.sum() < MIN_GREY_LEVELS:
        return None
    matrix = np.column_stack([s.full_XYZ for s in context.sweeps])
    if context.white_count:  # primaries scaled to add up to the white: the interaction's own test
        matrix = matrix * np.linalg.solve(matrix, context.white - context.black)
    XYZ = context.fit.XYZ[greys]
    outputs = np.linalg.solve(matrix, (XYZ - context.black).T).T
    relative = context.noise.sd_Y(XYZ[:, 1]) / np.abs(XYZ[:, 1])
    full_Y = np.array([s.full_XYZ[1] for s in context.sweeps])
    sd = np.hypot(np.abs(outputs) * relative[:, None], context.noise.floor / full_Y)
    return rgb[greys, 0] / 255.0, outputs, sd


MIN_GREY_LEVELS = 7
"""Greys a channel's shape may be tested on where its own sweep is too short."""


def _tone_test_points(drive, Y, sd, black_guess, full, noise_dof=np.inf):
    """(p, gap, gap SE, better form, z): power law against the alternatives, and its lack of fit.

    Each alternative of :data:`TONE_ALTERNATIVES` by an F-test of its extra
    parameters; and the power law's own χ² against the noise model (an F-test
    on the noise estimate's ``noise_dof``), which a shape none of the
    alternatives bends to still fails. The p-values are multiplied by the
    number of tests (Bonferroni).
    """
    tests = len(TONE_ALTERNATIVES) + 1
    null, rss_null = _fit_shape("power", drive, Y, sd, black_guess, full)
    grid = np.linspace(0, 1, 256)
    best = (1.0, 0.0, 0.0, "power", float("-inf"))
    dof_null = Y.size - 3
    if dof_null >= 1:
        f_value = rss_null / dof_null
        p = min(1.0, tests * f_sf(f_value, dof_null, noise_dof if np.isfinite(noise_dof)
                                  else 10 ** 6))
        residual = Y - (null[0] + null[1] * _shape("power", drive, null[2:]))
        gap = float(np.max(np.abs(residual)) / null[1]) if null[1] > 0 else 0.0
        z = z_of_p(p)
        best = (p, gap, gap / z if z > 0 else np.inf, LACK_OF_FIT, z)
    for form, extra in TONE_ALTERNATIVES.items():
        alternative, rss_alt = _fit_shape(form, drive, Y, sd, black_guess, full)
        dof = Y.size - 3 - extra
        if dof < 1:
            continue
        scale = max(1.0, rss_alt / dof)
        f_value = (rss_null - rss_alt) / extra / scale
        p = min(1.0, tests * f_sf(f_value, extra, dof))
        gap = float(np.max(np.abs(_shape("power", grid, null[2:])
                                  - alternative[1] / null[1] * _shape(form, grid, alternative[2:]))))
        z = z_of_chi2(extra * f_value, extra) if f_value > 0 else float("-inf")
        standard_error = gap / z if z > 0 else np.inf
        if p < best[0] or (p == best[0] and f_value > 0 and z > best[4]):
            best = (p, gap, standard_error, form, z)
    return best


def _tone_test(sweep: ChannelSweep, context: DiagnosisContext, greys=None,
               slow_gain: float = 0.0):
    """(p, gap, gap SE, better form, z) of one channel, or None with too few levels.

    On the channel's own sweep (black rows at ``d = 0``) in absolute Y; where
    the sweep has fewer than :data:`MIN_TONE_LEVELS` levels below full drive,
    on the sweep and the grey-derived outputs together, in normalized output.
    ``slow_gain``: a relative gain variance each level carries
    (:func:`beyond_noise_gain_variance`).
    """
    inner = sweep.drive < 1.0
    if inner.sum() >= MIN_TONE_LEVELS:
        black = context.black
        Y = np.concatenate([np.full(context.black_count, black[1]) if context.black_count else [],
                            sweep.XYZ[:, 1] + black[1]])
        drive = np.concatenate([np.zeros(context.black_count), sweep.drive])
        counts = np.concatenate([np.ones(context.black_count), sweep.counts])
        sd = context.noise.sd_Y(Y) / np.sqrt(counts)
        if slow_gain > 0:  # the whites scatter beyond noise, no drift found: a gain on each level
            sd = np.hypot(sd, np.sqrt(slow_gain) * Y)
        if sweep.times is not None and context.drift is not None:
            # a drift correction's own error, alike on the levels measured one after another
            # between two references (DriftCorrection.bridge_covariance): one bend, not noise
            covariance = np.diag(sd ** 2)
            b = context.black_count
            covariance[b:, b:] += (context.drift.bridge_covariance(sweep.times)
                                   * np.outer(Y[b:], Y[b:]))
            sd = np.linalg.inv(np.linalg.cholesky(covariance))
        elif sweep.correction_sd is not None:  # a drift correction's own uncertainty
            correction = np.concatenate([np.zeros(context.black_count), sweep.correction_sd])
            sd = np.hypot(sd, correction * Y)
        return _tone_test_points(drive, Y, sd, black[1], float(sweep.full_XYZ[1]),
                                 context.noise.dof)
    if greys is None:
        return None
    grey_drive, outputs, grey_sd = greys
    full_Y = float(sweep.full_XYZ[1])
    drive = np.concatenate([sweep.drive, grey_drive])
    L = np.concatenate([sweep.output, outputs[:, sweep.channel]])
    own = context.noise.sd_Y(sweep.XYZ[:, 1] + context.black[1]) / full_Y / np.sqrt(sweep.counts)
    if sweep.correction_sd is not None:
        own = np.hypot(own, sweep.correction_sd * sweep.output)
    sd = np.concatenate([own, grey_sd[:, sweep.channel]])
    if slow_gain > 0:
        sd = np.hypot(sd, np.sqrt(slow_gain) * L)
    return _tone_test_points(drive, L, sd, 0.0, 1.0, context.noise.dof)


def detect_tone_curve_shape(context: DiagnosisContext) -> DetectorResult:
    greys = _grey_points(context)
    slow_gain = beyond_noise_gain_variance(context)
    tests = [_tone_test(s, context, greys, slow_gain) for s in context.sweeps]
    tested = [t for t in tests if t is not None]
    if not tested:
        return _untestable("tone-curve-shape", f"no sweep has {MIN_TONE_LEVELS} levels below "
                                               f"full drive and there are fewer than "
                                               f"{MIN_GREY_LEVELS} greys")
    p_values = [1.0 if t is None else t[0] for t in tests]
    worst = int(np.argmin(p_values))
    p = min(1.0, len(tested) * p_values[worst])
    _, gap, standard_error, form, z = tests[worst]
    article = "an" if form[0] in "aeiou" else "a"
    if form == LACK_OF_FIT:
        evidence = (f"the {CHANNEL_NAMES[worst]} sweep is not a power law: no power law fits "
                    f"it within the noise (lack-of-fit F-test p {p_values[worst]:.2g}), and it "
                    f"departs from the best one by up to {100 * gap:.1f} % of full output")
    else:
        evidence = (f"the {CHANNEL_NAMES[worst]} sweep is not a power law: {article} {form} "
                    f"curve fits it better (F-test p {p_values[worst]:.2g}) and departs from "
                    f"the best power law by up to {100 * gap:.1f} % of full output")
    return _result("tone-curve-shape", gap, standard_error, p, evidence,
                   {"max_gap": [0.0 if t is None else t[1] for t in tests],
                    "better_form": [None if t is None else t[3] for t in tests],
                    "p_per_channel": p_values}, z=z)


def detect_apl_dependence_in_context(context: DiagnosisContext) -> DetectorResult:
    """``apl-dependence`` on the context's load rows, each row's noise from the noise model."""
    return apl_dependence_result(context.load_session, context.noise)


def apl_dependence_result(session: Session | None, noise: NoiseModel) -> DetectorResult:
    """The ``apl-dependence`` test of ``session`` (distinct rows) against ``noise``."""
    from workbench.apl import detect_apl_dependence

    if session is None or not session.has_surround_data:
        return _untestable(APL_EFFECT, "every patch was measured full field on black; measure "
                                       "plan 'apl' or 'paper+apl' (windows and surrounds)")
    relative = noise.relative_sd_Y(session.XYZ[:, 1])
    test = detect_apl_dependence(session, relative)
    if not test.testable:
        return _untestable(APL_EFFECT, test.evidence.removeprefix("not testable: "))
    p = t_sf(test.z, noise.dof)  # one-sided: the noise is estimated
    # the test's own z is a normal one; the finding's is the Student t's (estimated noise)
    evidence = re.sub(r"; z = -?[0-9.]+\)", ")", test.evidence)
    result = _result(APL_EFFECT, test.statistic, test.standard_error, p,
                     f"{evidence} (the session's noise model: "
                     f"{100 * float(np.median(relative[relative < 1])):.2f} % median relative "
                     "luminance noise of these rows)",
                     {"rows": test.rows, "patches": test.patches,
                      "impact_dE00_low_vs_high_load": test.impact_dE00}, z=test.z)
    return replace(result, impact_dE00=test.impact_dE00)


DETECTORS = {
    "temporal-drift": detect_temporal_drift,
    "black-offset": detect_black_offset,
    "channel-interaction": detect_channel_interaction,
    "chromaticity-shift": detect_chromaticity_shift,
    "tone-curve-shape": detect_tone_curve_shape,
    APL_EFFECT: detect_apl_dependence_in_context,
}
"""Effect id → detector, in the order they run."""

FULL_FIELD_DETECTORS = tuple(e for e in DETECTORS if e != APL_EFFECT)
"""The detectors that read the full-field rows (and need the display model's ramps)."""


def run_detectors(fit_session: Session, noise: NoiseModel | None = None,
                  load_session: Session | None = None, effects=None
                  ) -> tuple[DiagnosisContext, tuple[DetectorResult, ...]]:
    """Every detector on the fit rows, with the family-wise significance level applied.

    The level is ``FAMILY_ALPHA / m`` for the ``m`` detectors of
    :data:`DETECTORS` (all of them, tested or not: a session that cannot test
    an effect does not earn the others a looser level), but
    ``apl-dependence`` counts only where it is testable (a session without
    windows or surrounds keeps the level it had before the test existed).
    ``effects``: run only these detectors (default all; a session without
    ramps runs ``apl-dependence`` alone).
    """
    context = build_context(fit_session, noise=noise, load_session=load_session)
    level = critical_p(family_size(context.apl_testable), FAMILY_ALPHA)
    critical = z_of_p(level)
    results = []
    for effect, detector in DETECTORS.items():
        if effects is not None and effect not in effects:
            continue
        result = detector(context)
        if result.testable:
            result = replace(result, critical_z=critical, significant=result.p_value <= level)
        results.append(result)
    return context, tuple(results)
