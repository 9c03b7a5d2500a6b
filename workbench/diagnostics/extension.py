"""Fit the extended display model with exactly the terms the detectors found.

Effect → term: ``black-offset`` → the black XYZ; ``tone-curve-shape`` → per
channel the tone-curve form with the lowest BIC (GOG, extended power, or the
monotone spline / 1D LUT); ``chromaticity-shift`` → level-dependent primaries;
``channel-interaction`` → the load-dependent gain, its amount fitted on the
white references (never on validation rows); ``temporal-drift`` → the fit data
are divided by the drift ``g(t)`` from the white references, and predictions
for a measurement at time ``t`` are multiplied by it.

Grey rows (``r = g = b``), where a session has them, add per-channel output
points: each grey's black-subtracted XYZ is solved for the three channel
outputs through the full-drive primaries (divided by the interaction gain when
that term is on).
"""

from __future__ import annotations

import numpy as np

from workbench.diagnostics.detectors import DiagnosisContext, tone_data
from workbench.diagnostics.evidence import ChannelSweep, fit_chromaticity_drift, xy_of
from workbench.display.extended import ChannelInteraction, ChromaticityDrift, ExtendedDisplay
from workbench.display.tone_curves import PowerCurve, fit_tone_curve, select_tone_curve

__all__ = ["TERMS", "fitted_on", "fit_extended", "grey_channel_outputs"]

TERMS = {
    "temporal-drift": "drift correction from the white references",
    "black-offset": "black/flare offset",
    "tone-curve-shape": "flexible per-channel tone curves",
    "chromaticity-shift": "level-dependent primaries",
    "channel-interaction": "load-dependent channel interaction",
}
"""Effect id → the model term that answers it."""


def fitted_on(effect: str, session) -> str:
    """Which rows the term answering ``effect`` was fitted on (never validation rows)."""
    n_white = int(session.mask("white").sum())
    n_grey = int(session.mask("grey").sum())
    sweeps = int(session.mask("ramp-r", "ramp-g", "ramp-b").sum())
    return {
        "temporal-drift": f"the {n_white} white references over time",
        "black-offset": "the black (0, 0, 0) measurement",
        "tone-curve-shape": f"the {sweeps} sweep points" + (f" and {n_grey} greys" if n_grey else ""),
        "chromaticity-shift": f"the chromaticity of the {sweeps} sweep points",
        "channel-interaction": f"the {n_white} white references against the full-drive primaries",
    }[effect]


def grey_channel_outputs(context: DiagnosisContext, interaction: ChannelInteraction | None = None):
    """Per-channel (drive, output) points implied by the grey rows, or None."""
    greys = context.fit.mask("grey") & (context.fit.rgb[:, 0] > 0)
    if greys.sum() < 3:
        return None
    matrix = np.column_stack([s.full_XYZ for s in context.sweeps])
    target = context.fit.XYZ[greys] - context.black
    outputs = np.linalg.solve(matrix, target.T).T
    if interaction is not None:
        for _ in range(20):
            outputs = np.linalg.solve(matrix, (target / interaction.gain(
                np.clip(outputs, 0, 1).mean(axis=1))[:, None]).T).T
    drive = context.fit.rgb[greys, 0] / 255.0
    return drive, outputs


def _chromaticity_term(sweep: ChannelSweep) -> ChromaticityDrift | None:
    fit = fit_chromaticity_drift(sweep)
    if fit is None:
        return None
    return ChromaticityDrift(tuple(tuple(float(v) for v in row) for row in fit[0]))


def _interaction_term(context: DiagnosisContext) -> ChannelInteraction:
    summed = sum(s.full_XYZ for s in context.sweeps)
    white = context.white - context.black
    ratio = float(white @ summed / (summed @ summed))
    return ChannelInteraction(amount=1.0 - ratio)


def fit_extended(context: DiagnosisContext, effects, baseline=None, tone_forms=None
                 ) -> ExtendedDisplay:
    """The extended model with the terms for ``effects`` (ids of found effects).

    Where a channel has fewer than three sweep points (published primaries
    only), its tone curve is the ``baseline``'s power law. ``tone_forms``
    (one form per channel) skips the choice of form by BIC and refits those
    forms: the cross-validation folds refit the chosen model, not a new choice.
    """
    effects = set(effects)
    interaction = _interaction_term(context) if "channel-interaction" in effects else None
    greys = grey_channel_outputs(context, interaction)
    tone = []
    for sweep in context.sweeps:
        extra = None if greys is None else (greys[0], greys[1][:, sweep.channel])
        drive, output = tone_data(sweep, extra)
        if drive.size < 3 and baseline is not None:
            curve = PowerCurve(float(baseline.gamma[sweep.channel]))
        elif "tone-curve-shape" in effects and tone_forms is not None:
            curve = fit_tone_curve(drive, output, tone_forms[sweep.channel])
        elif "tone-curve-shape" in effects:
            curve, _ = select_tone_curve(drive, output)
        else:
            curve = fit_tone_curve(drive, output, "power")
        tone.append(curve)
    chromaticity = tuple(_chromaticity_term(s) if "chromaticity-shift" in effects else None
                         for s in context.sweeps)
    full = np.array([s.full_XYZ for s in context.sweeps])
    return ExtendedDisplay(
        black=context.black if "black-offset" in effects else np.zeros(3),
        white=context.white,
        primaries_xy=xy_of(full),
        primaries_Y=full[:, 1],
        tone=tuple(tone),
        chromaticity=chromaticity,
        interaction=interaction,
        components=tuple(e for e in TERMS if e in effects),
    )
