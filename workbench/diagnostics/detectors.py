"""Effect detectors: one per effect id of the diagnostics vocabulary (design §5).

Each detector computes a statistic from the rows a model may be fitted on and
compares it with a threshold. Thresholds were set on simulated clean sessions
(the simulated headset measured with the CS-2000 emulator's noise model plus
0.1 % repeatability) so that a clean session gives a false finding in at most
5 % of sessions; the realistic magnitudes of each effect lie well above them
(see ``tests/test_diagnostics.py``, which checks both sides). A result's
``score`` is the statistic over its threshold: how far beyond noise the
evidence is, the quantity findings are ordered by.

Registry: :data:`DETECTORS` (effect id → detector), run in that order by
:func:`run_detectors` because later detectors read data corrected for earlier
findings (drift first, then black).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from workbench.diagnostics.evidence import (
    ChannelSweep,
    DriftCorrection,
    channel_sweeps,
    estimate_drift,
    fit_chromaticity_drift,
    xy_of,
)
from workbench.display.tone_curves import bic, fit_tone_curve
from workbench.session import Session

__all__ = [
    "DetectorResult",
    "DiagnosisContext",
    "THRESHOLDS",
    "DETECTORS",
    "build_context",
    "run_detectors",
    "detect_temporal_drift",
    "detect_black_offset",
    "detect_channel_interaction",
    "detect_chromaticity_shift",
    "detect_tone_curve_shape",
]

THRESHOLDS = {
    "temporal-drift": 0.01,  # span of the white over the session, relative
    "black-offset": 0.001,  # black luminance relative to white
    "channel-interaction": 0.005,  # |1 − (W − K)/Σ(P − K)| in Y (and X, Z)
    "chromaticity-shift": 0.004,  # xy distance of a primary at low drive from full drive
    "tone-curve-shape": 0.003,  # max |power − flexible| in normalized output, with ΔBIC > 10
}
"""Detection thresholds (module doc for how they were set)."""

CHANNEL_NAMES = ("red", "green", "blue")


@dataclass(frozen=True)
class DetectorResult:
    effect: str
    found: bool
    statistic: float
    threshold: float
    evidence: str
    details: dict = field(default_factory=dict)

    @property
    def score(self) -> float:
        return float(self.statistic / self.threshold) if self.threshold else 0.0


@dataclass(frozen=True, eq=False)
class DiagnosisContext:
    """What the detectors read: fit rows (drift-corrected if drift was found), black, sweeps."""

    raw: Session
    fit: Session
    drift: DriftCorrection | None
    drift_found: bool
    black: np.ndarray
    white: np.ndarray
    sweeps: tuple[ChannelSweep, ...]


def build_context(fit_session: Session, drift_found: bool | None = None) -> DiagnosisContext:
    drift = estimate_drift(fit_session)
    if drift_found is None:
        drift_found = drift is not None and drift.span > THRESHOLDS["temporal-drift"]
    corrected = drift.correct(fit_session) if (drift is not None and drift_found) else fit_session
    black = corrected.black_XYZ
    white = corrected.white_XYZ if corrected.has_white else None
    sweeps = channel_sweeps(corrected, black)
    if white is None:  # ramps-only data (e.g. Psychtoolbox): the additive white
        white = black + sum(s.full_XYZ for s in sweeps)
    return DiagnosisContext(raw=fit_session, fit=corrected, drift=drift, drift_found=drift_found,
                            black=black, white=white, sweeps=sweeps)


def detect_temporal_drift(context: DiagnosisContext) -> DetectorResult:
    threshold = THRESHOLDS["temporal-drift"]
    drift = context.drift
    if drift is None:
        return DetectorResult("temporal-drift", False, 0.0, threshold,
                              "not testable: fewer than 3 white references with times")
    low = int(np.argmin(drift.gains))
    evidence = (f"white luminance varies by {100 * drift.span:.1f} % over the session "
                f"({len(drift.times)} references); lowest {100 * drift.gains[low]:.1f} % of the "
                f"final level at t = {drift.times[low]:.0f} s"
                + (", rising toward the end (warm-up)" if low < len(drift.gains) // 2 else ""))
    return DetectorResult("temporal-drift", drift.span > threshold, drift.span, threshold, evidence,
                          {"times_s": drift.times.tolist(), "relative_white": drift.gains.tolist()})


def detect_black_offset(context: DiagnosisContext) -> DetectorResult:
    threshold = THRESHOLDS["black-offset"]
    if not (context.fit.mask("black").any() or np.any(np.all(context.fit.rgb <= 0, axis=1))):
        return DetectorResult("black-offset", False, 0.0, threshold,
                              "not testable: no black (0, 0, 0) measurement")
    ratio = float(context.black[1] / context.white[1])
    xy = xy_of(context.black)
    evidence = (f"black measures {100 * ratio:.2f} % of white (Y {context.black[1]:.4g} of "
                f"{context.white[1]:.4g}) at xy ({xy[0]:.3f}, {xy[1]:.3f}); the baseline "
                "predicts no light at DAC 0 and lets black leak into every primary")
    return DetectorResult("black-offset", ratio > threshold, ratio, threshold, evidence,
                          {"black_XYZ": context.black.tolist(), "ratio": ratio})


def detect_channel_interaction(context: DiagnosisContext) -> DetectorResult:
    threshold = THRESHOLDS["channel-interaction"]
    summed = sum(s.full_XYZ for s in context.sweeps)
    white = context.white - context.black
    ratio = white / summed
    if not (context.fit.mask("white").any()):
        return DetectorResult("channel-interaction", False, 0.0, threshold,
                              "not testable: no white measured beside the primaries")
    deviation = float(np.max(np.abs(1.0 - ratio)))
    direction = "falls short of" if ratio[1] < 1 else "exceeds"
    evidence = (f"white measures {100 * ratio[1]:.1f} % of R+G+B in luminance "
                f"(X {100 * ratio[0]:.1f} %, Z {100 * ratio[2]:.1f} %, black subtracted): "
                f"the full-drive mixture {direction} the sum of its primaries")
    return DetectorResult("channel-interaction", deviation > threshold, deviation, threshold,
                          evidence, {"white_over_sum": ratio.tolist()})


def _chromaticity_drift(sweep: ChannelSweep) -> tuple[float, float]:
    """Fitted xy distance from full drive at the lowest usable level, and that level."""
    fit = fit_chromaticity_drift(sweep)
    if fit is None:
        return 0.0, 1.0
    coefficients, lowest = fit
    u0 = 1.0 - lowest
    return float(np.hypot(*(u0 * coefficients[0] + u0 ** 2 * coefficients[1]))), lowest


def detect_chromaticity_shift(context: DiagnosisContext) -> DetectorResult:
    threshold = THRESHOLDS["chromaticity-shift"]
    shifts = [_chromaticity_drift(s) for s in context.sweeps]
    worst = int(np.argmax([d for d, _ in shifts]))
    distance, level = shifts[worst]
    evidence = (f"the {CHANNEL_NAMES[worst]} primary's chromaticity (black subtracted) moves by "
                f"Δxy {distance:.4f} between full drive and DAC {255 * level:.0f}; per channel "
                + ", ".join(f"{CHANNEL_NAMES[c][0].upper()} {d:.4f}" for c, (d, _) in
                            enumerate(shifts)))
    return DetectorResult("chromaticity-shift", distance > threshold, distance, threshold,
                          evidence, {"shift_xy": [d for d, _ in shifts]})


def tone_data(sweep: ChannelSweep, extra: tuple[np.ndarray, np.ndarray] | None = None):
    """(drive, output) of a channel, optionally with grey-derived points."""
    drive, output = sweep.drive, sweep.output
    if extra is not None:
        drive = np.concatenate([drive, extra[0]])
        output = np.concatenate([output, extra[1]])
    order = np.argsort(drive, kind="stable")
    return drive[order], output[order]


def detect_tone_curve_shape(context: DiagnosisContext) -> DetectorResult:
    threshold = THRESHOLDS["tone-curve-shape"]
    per_channel = []
    for sweep in context.sweeps:
        drive, output = tone_data(sweep)
        if drive.size < 4:
            per_channel.append((0.0, 0.0, "power"))
            continue
        power = fit_tone_curve(drive, output, "power")
        best_gap, best_delta, best_form = 0.0, 0.0, "power"
        for form in ("gog", "extended-power"):
            flexible = fit_tone_curve(drive, output, form)
            delta_bic = bic(power, drive, output) - bic(flexible, drive, output)
            grid = np.linspace(0, 1, 256)
            gap = float(np.max(np.abs(power.forward(grid) - flexible.forward(grid))))
            if delta_bic > 10 and gap > best_gap:
                best_gap, best_delta, best_form = gap, delta_bic, form
        per_channel.append((best_gap, best_delta, best_form))
    worst = int(np.argmax([gap for gap, _, _ in per_channel]))
    gap, delta_bic, form = per_channel[worst]
    article = "an" if form[0] in "aeiou" else "a"
    evidence = (f"the {CHANNEL_NAMES[worst]} sweep is not a power law: {article} {form} curve fits it "
                f"better by ΔBIC {delta_bic:.0f} and departs from the best power law by up to "
                f"{100 * gap:.1f} % of full output" if gap > 0 else
                "every sweep is fitted by a power law within noise")
    return DetectorResult("tone-curve-shape", gap > threshold, gap, threshold, evidence,
                          {"max_gap": [g for g, _, _ in per_channel],
                           "delta_bic": [d for _, d, _ in per_channel],
                           "better_form": [f for _, _, f in per_channel]})


DETECTORS = {
    "temporal-drift": detect_temporal_drift,
    "black-offset": detect_black_offset,
    "channel-interaction": detect_channel_interaction,
    "chromaticity-shift": detect_chromaticity_shift,
    "tone-curve-shape": detect_tone_curve_shape,
}
"""Effect id → detector, in the order they run."""


def run_detectors(fit_session: Session) -> tuple[DiagnosisContext, tuple[DetectorResult, ...]]:
    """Every detector on the fit rows; the context the extended fit then uses."""
    context = build_context(fit_session)
    return context, tuple(detector(context) for detector in DETECTORS.values())
