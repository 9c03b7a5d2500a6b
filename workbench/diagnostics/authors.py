"""The second peer: the seed authors' own current characterization method.

Díaz-Barrancas, Gil-Rodríguez et al. publish their current HMD
characterization code (rkl-gilro/ColorCharacterization, 2025,
``src/HMD_ColourCharacterisation.m``). In the workbench's terms it is:

1. the black ``K`` is the mean of the DAC-0 measurements;
2. the matrix ``M`` has the full-drive primaries less ``K`` as columns;
3. each grey ``g`` of the grey ramp gives three "radiometric" channel values
   ``ρ(g) = M⁻¹ (XYZ(g) − K)``;
4. a colour ``(r, g, b)`` is predicted as ``XYZ = M · [ρ_r(r), ρ_g(g), ρ_b(b)] + K``,
   each ``ρ_c`` interpolated linearly between the measured grey levels.

The single-channel sweeps are not used beyond their full-drive point: the
grey ramp carries the tone curves, so whatever the channels do to each other
along the grey axis (crosstalk, a backlight that follows the picture) is
inside the curves. :func:`fit_grey_ramp_linearisation` is that method, exactly
(linear interpolation, no smoothing); :func:`score_authors_method` fits it on
a session's fit rows and scores it on the validation rows with the
convention of :func:`workbench.diagnostics.diagnose` (CIEDE2000, CIELAB white
the measured display white), beside ArgyllCMS in the benchmarks and the
real-data table. :func:`grey_ramp_model` is the same method as an exportable
:class:`~workbench.display.extended.ExtendedDisplay` (monotone curves through
the same points), one of the candidates the diagnosis chooses among.

References
----------
Díaz-Barrancas, F., Cwierz, H., Pardo, P. J., Pérez, Á. L., Suero, M. I.
(2020). Spectral Color Management in Virtual Reality Scenes. Sensors 20(19),
5658. Code: github.com/rkl-gilro/ColorCharacterization (2025).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from workbench.colorimetry import delta_E2000
from workbench.display.extended import ChannelInteraction, ExtendedDisplay
from workbench.display.tone_curves import along_power_segments, along_sweep_segments, fit_tone_curve
from workbench.diagnostics.peer_score import PeerScore, peer_score
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["AUTHORS_METHOD", "GREY_RAMP_COMPONENT", "MIN_GREYS", "GreyRampLinearisation", "AuthorsScore",
           "grey_ramp_points", "fit_grey_ramp_linearisation", "grey_ramp_model",
           "score_authors_method"]

AUTHORS_METHOD = "authors' grey-ramp linearisation (Díaz-Barrancas et al., 2025 code)"

GREY_RAMP_COMPONENT = "grey-ramp-linearisation"
"""The component id a grey-ramp model carries in a profile (beside the effect ids)."""

MIN_GREYS = 3
"""Grey levels strictly between black and white the method needs (fewer: it is not applicable)."""


@dataclass(frozen=True)
class GreyRampPoints:
    """The measured quantities the method is built from."""

    black: np.ndarray  # (3,) XYZ
    matrix: np.ndarray  # (3, 3) columns: full-drive primaries less black
    drive: np.ndarray  # (n,) grey levels 0..1, 0 and 1 included, rising
    radiometric: np.ndarray  # (n, 3) ρ at each level


def _mean_by_level(drive: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    levels, inverse = np.unique(drive, return_inverse=True)
    sums = np.zeros((levels.size, values.shape[1]))
    np.add.at(sums, inverse, values)
    return levels, sums / np.bincount(inverse)[:, None]


def grey_ramp_points(session: Session, nonnegative_black: bool = False) -> GreyRampPoints:
    """Black, matrix and the grey ramp's radiometric values of ``session``'s non-validation rows.

    ``nonnegative_black``: a black read below zero in X, Y or Z (noise about none) is taken as
    zero there, and the matrix and the grey ramp are built on that same black, so the model still
    reproduces the greys it was built from (the authors' method itself keeps the black as read).

    Raises
    ------
    InputError
        Naming what is missing: a black, a full-drive primary, or
        :data:`MIN_GREYS` grey levels between black and white.
    """
    rows = session.without("validation")
    rgb, XYZ = rows.rgb, rows.XYZ
    dark = np.all(rgb == 0, axis=1)
    if not dark.any():
        raise InputError(f"{AUTHORS_METHOD} needs a black (0, 0, 0) measurement; "
                         f"{session.source!r} has none")
    black = XYZ[dark].mean(axis=0)
    if nonnegative_black:
        black = np.maximum(black, 0.0)
    columns = []
    for c, name in enumerate("RGB"):
        others = np.delete(rgb, c, axis=1)
        full = (rgb[:, c] >= 255) & np.all(others == 0, axis=1)
        if not full.any():
            raise InputError(f"{AUTHORS_METHOD} needs the full-drive {name} primary; "
                             f"{session.source!r} has none")
        columns.append(XYZ[full].mean(axis=0) - black)
    matrix = np.column_stack(columns)
    grey = (rgb[:, 0] == rgb[:, 1]) & (rgb[:, 1] == rgb[:, 2])
    partial = grey & (rgb[:, 0] > 0) & (rgb[:, 0] < 255)
    if np.unique(rgb[partial, 0]).size < MIN_GREYS:
        raise InputError(f"{AUTHORS_METHOD} needs a grey ramp (at least {MIN_GREYS} grey levels "
                         f"between black and white); {session.source!r} has "
                         f"{np.unique(rgb[partial, 0]).size}: measure plan 'authors-2024' or "
                         "'paper+greys'")
    drive = rgb[grey, 0] / 255.0
    radiometric = np.linalg.solve(matrix, (XYZ[grey] - black).T).T
    levels, means = _mean_by_level(drive, radiometric)
    if levels[0] > 0:
        levels, means = np.concatenate([[0.0], levels]), np.vstack([np.zeros(3), means])
    if levels[-1] < 1:  # no white: the primaries at full drive add up to ρ = 1
        levels, means = np.concatenate([levels, [1.0]]), np.vstack([means, np.ones(3)])
    return GreyRampPoints(black=black, matrix=matrix, drive=levels, radiometric=means)


@dataclass(frozen=True, eq=False)
class GreyRampLinearisation:
    """The authors' model, exactly: linear interpolation of ρ between grey levels (module doc)."""

    points: GreyRampPoints

    def linear(self, rgb) -> np.ndarray:
        d = np.asarray(rgb, dtype=float).reshape(-1, 3) / 255.0
        p = self.points
        return np.column_stack([np.interp(d[:, c], p.drive, p.radiometric[:, c])
                                for c in range(3)])

    def forward(self, rgb) -> np.ndarray:
        return self.linear(rgb) @ self.points.matrix.T + self.points.black

    def describe(self) -> str:
        return f"{AUTHORS_METHOD}, {self.points.drive.size} grey levels"


def fit_grey_ramp_linearisation(session: Session) -> GreyRampLinearisation:
    """The authors' method fitted on ``session``'s non-validation rows (module doc)."""
    return GreyRampLinearisation(grey_ramp_points(session))


def grey_ramp_model(session: Session, white: np.ndarray | None = None,
                    with_sweeps: bool = False, power_segments: bool = False,
                    sweep_segments: bool = False) -> ExtendedDisplay:
    """The authors' method as an exportable display model; ``with_sweeps``: its extension.

    Each channel's ``ρ_c`` is normalized by its value at full drive (so the
    primaries become ``ρ_c(1) · (P_c − K)``: their sum is the measured white)
    and made a monotone curve through the grey levels
    (:class:`~workbench.display.tone_curves.LinearCurve`: isotonic, joined by
    straight lines), so the model has the inverse every display model needs.

    ``with_sweeps``: the single-channel sweeps, which the authors' method
    leaves unused below full drive, correct each channel as a colour leaves
    the grey axis (:class:`~workbench.display.extended.ChannelInteraction`
    with ``axis_ratio``): the model then reproduces the greys and the sweeps,
    and a colour between them by how grey it is (the fade's exponent: the one that
    predicts the fit rows' mixtures best where they hold
    :data:`MIN_MIXTURES_FOR_EXPONENT`, else :data:`GREYNESS_EXPONENT`). Where a
    channel's sweep and its grey-ramp curve agree the correction is 1 and the
    model is the authors'.

    ``power_segments``: each channel's curve follows the power law through each two
    consecutive greys instead of the straight line
    (:func:`~workbench.display.tone_curves.along_power_segments`; where the model choice asks
    for it: :func:`~workbench.diagnostics.model_choice.fit_candidate`); with
    ``sweep_segments`` too, in the shape of the channel's own sweep (smoothed) where it holds two
    levels or more inside a stretch
    (:func:`~workbench.display.tone_curves.along_sweep_segments`).

    Components: ``black-offset`` (the method always has the black),
    ``grey-ramp-linearisation`` and, with the sweeps, ``channel-interaction``.
    """
    # the black it adds back is the black it subtracted: a black clipped only where added back
    # moved every predicted colour by the clipped part (0.066 → 0.085 mean ΔE00 on a
    # generated display whose black read slightly below zero in Z)
    p = grey_ramp_points(session, nonnegative_black=True)
    top = p.radiometric[-1]
    if np.any(top <= 0):
        raise InputError(f"{AUTHORS_METHOD}: the white solves to a non-positive amount of a "
                         f"primary ({np.round(top, 3).tolist()}); the grey ramp and the primaries "
                         "disagree")
    full = p.matrix * top[None, :]
    x = full[0] / full.sum(axis=0)
    y = full[1] / full.sum(axis=0)
    inner = (p.drive > 0) & (p.drive < 1)
    tone = tuple(fit_tone_curve(p.drive[inner], p.radiometric[inner, c] / top[c], "linear")
                 for c in range(3))
    if power_segments and sweep_segments:
        tone = tuple(along_sweep_segments(curve, *_sweep_points(session, p, c))
                     for c, curve in enumerate(tone))
    elif power_segments:
        tone = tuple(along_power_segments(curve) for curve in tone)
    white = p.black + full.sum(axis=1) if white is None else np.asarray(white, dtype=float)
    interaction = _axis_ratio(session, p, tone) if with_sweeps else None
    components = ("black-offset", GREY_RAMP_COMPONENT) + (
        ("channel-interaction",) if interaction is not None else ())

    def model(interaction):
        return ExtendedDisplay(black=p.black, white=white,
                               primaries_xy=np.column_stack([x, y]),
                               primaries_Y=full[1], tone=tone, interaction=interaction,
                               components=components)

    if interaction is None:
        return model(None)
    mixtures = session.without("validation")
    mixtures = mixtures.subset(_mixture_rows(mixtures.rgb))
    if len(mixtures) < MIN_MIXTURES_FOR_EXPONENT:
        return model(interaction)
    candidates = [model(replace(interaction, greyness_exponent=q))
                  for q in GREYNESS_EXPONENTS]
    errors = [float(delta_E2000(m.forward(mixtures.rgb), mixtures.XYZ, white).mean())
              for m in candidates]
    return candidates[int(np.argmin(errors))]


def _sweep_points(session: Session, points: GreyRampPoints, channel: int) -> np.ndarray:
    """(2, n): channel ``channel``'s sweep levels (0..1) and its ρ there (mean per level)."""
    rows = session.without("validation")
    rgb = rows.rgb
    own = (rgb[:, channel] > 0) & np.all(np.delete(rgb, channel, axis=1) == 0, axis=1)
    if not own.any():
        return np.zeros((2, 0))
    amount = np.linalg.solve(points.matrix, (rows.XYZ[own] - points.black).T).T[:, channel]
    levels, means = _mean_by_level(rgb[own, channel] / 255.0, amount[:, None])
    return np.vstack([levels, means[:, 0]])


GREYNESS_EXPONENT = 0.5
"""How fast the grey ramp takes over from a channel's sweep as the other channels come up
(:class:`~workbench.display.extended.ChannelInteraction` ``greyness_exponent``) where the fit rows
hold too few mixtures to choose it. The sweeps and the greys fix the correction on the channel
axes and on the grey axis; only mixtures tell how it fades between them. On 34 real LCD
sessions (ArgyllCMS charts: sweeps, a grey ramp and a few hundred mixtures, these held out),
against the grey ramp alone, the linear fade (1) lost on 6 sessions by more than 0.02 ΔE00 (0.17
at most); a square-root fade gained more in all (held-out mean ΔE00 summed over the sessions:
5.19 against 3.77 for the linear fade and 4.47 for the square root of the larger other channel)
and lost on one (0.05); exponents 0.25 and 0.35 lost on none but gained less (4.25, 4.90). The
sweeps on these panels fall 2–4 % short of the grey ramp's share at mid drive: the shortfall goes
as soon as a little of the other channels comes up."""

GREYNESS_EXPONENTS = (0.25, 0.35, 0.5, 0.7, 1.0, 1.5, 2.0)
"""Exponents tried on the fit rows' mixtures, where they hold
:data:`MIN_MIXTURES_FOR_EXPONENT` (the ratio table comes from the sweeps alone, so the mixtures
are unseen by it)."""

MIN_MIXTURES_FOR_EXPONENT = 10


def _mixture_rows(rgb: np.ndarray) -> np.ndarray:
    """Rows with two or three channels lit that are not greys."""
    grey = (rgb[:, 0] == rgb[:, 1]) & (rgb[:, 1] == rgb[:, 2])
    return ((rgb > 0).sum(axis=1) >= 2) & ~grey


AXIS_RATIO_FLOOR = 0.005
"""Sweep levels whose grey-ramp output is below this (of full drive) give no ratio: too dark to
divide by."""


def _axis_ratio(session: Session, points: GreyRampPoints, tone) -> ChannelInteraction | None:
    """Each channel's sweep over its grey-ramp curve at the sweep levels (None: no sweep)."""
    rows = session.without("validation")
    rgb = rows.rgb
    top = points.radiometric[-1]
    table = []
    for c in range(3):
        own = (rgb[:, c] > 0) & np.all(np.delete(rgb, c, axis=1) == 0, axis=1)
        if not own.any():
            return None
        drive = rgb[own, c] / 255.0
        measured = np.linalg.solve(points.matrix, (rows.XYZ[own] - points.black).T).T[:, c]
        levels, means = _mean_by_level(drive, measured[:, None])
        curve = tone[c].forward(levels)
        keep = curve > AXIS_RATIO_FLOOR
        if not keep.any():
            return None
        ratio = np.clip(means[keep, 0] / (top[c] * curve[keep]), 1e-3, 10.0)
        output, index = np.unique(curve[keep], return_inverse=True)
        ratio = np.bincount(index, weights=ratio) / np.bincount(index)
        table.append((tuple(float(v) for v in output), tuple(float(v) for v in ratio)))
    white_loss = float(1.0 - 1.0 / np.average(1.0 / np.array([t[1][-1] for t in table]),
                                              weights=points.matrix[1]))
    return ChannelInteraction(amount=float(np.clip(white_loss, -0.95, 0.95)),
                              axis_ratio=tuple(table), greyness_exponent=GREYNESS_EXPONENT)


AuthorsScore = PeerScore
"""The authors' method scored on the validation colours (a :class:`PeerScore`)."""


def score_authors_method(session: Session) -> AuthorsScore:
    """The authors' method on ``session``'s fit rows, scored on its validation rows."""
    validation = session.select("validation")
    if len(validation) == 0:
        return AuthorsScore(AUTHORS_METHOD, unavailable="no validation colours to score on")
    if not session.has_white:
        return AuthorsScore(AUTHORS_METHOD, unavailable="no white measured")
    try:
        model = fit_grey_ramp_linearisation(session)
    except InputError as error:
        return AuthorsScore(AUTHORS_METHOD, unavailable=str(error))
    return peer_score(model.describe(), delta_E2000(model.forward(validation.rgb),
                                                    validation.XYZ, session.white_XYZ))
