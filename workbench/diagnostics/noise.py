"""The session's own noise model: how well one measurement is known, at every level.

A measurement ``v = (X, Y, Z)`` of a patch whose true value is ``v₀`` is modelled as

``v = v₀ · (1 + ε_gain) + ε_coord + ε_floor``

- ``ε_gain ~ N(0, a²)``: a whole-measurement gain (the luminance repeatability),
  common to X, Y and Z;
- ``ε_coord ~ N(0, (c · v₀)²)`` per coordinate: what moves the chromaticity;
- ``ε_floor ~ N(0, b²)`` per coordinate, ``b`` in the session's XYZ units: the
  absolute floor that dominates dark patches.

so ``Cov(v) = a² v₀ v₀ᵀ + diag(c² v₀² + b²)`` (:meth:`NoiseModel.covariance`).

Where the numbers come from (:func:`estimate_noise`), all from the rows a
model may be fitted on:

- **Sweep scatter.** Every sweep with at least :data:`MIN_SWEEP_LEVELS`
  levels (each channel's ramp, the grey ramp; full-field rows) is predicted point by point by
  a quadratic through its neighbours (three on each side, the point itself
  left out); the residuals are a known linear map ``A`` of the measurements,
  so their variance is exact (``Σ_k A_ik² σ_k²``). ``a`` comes from the
  differences of the residuals of bright points (Y ≥ 5 % of white) measured
  one after another, which a display that drifts or wanders over minutes
  does not inflate (the whole scatter is reported beside it); ``c`` from the
  residuals of x and y; ``b`` from the dark points (Y < 2 % of white) and
  repeated blacks. This is why the drift test can use it: it does not come
  from the references under test.
- **Repeated patches.** Rows with the same DAC values (under the same frame:
  window and surround) measured more than once
  (the white references, repeated blacks, any other repeats) give a second
  estimate of ``a``, reported beside the first. Rows whose XYZ equal an
  earlier row's to the last digit are copies (DisplayCAL writes its first
  whites that way), not measurements: they are excluded and counted. The
  white references also carry any drift between them, so this estimate is
  the model's only when there are no sweeps to estimate from.
- **Instrument default.** Without sweeps or repeats:
  :data:`DEFAULT_GAIN_SD`, :data:`DEFAULT_CHROMA_SD` and
  :data:`DEFAULT_FLOOR_FRACTION`, and the model says so.

Robust scale: every estimate is the mean of squared, leverage-corrected
residuals winsorized at 4σ of their median-based scale, so a few outliers
(a quantization step, a bad reading) do not inflate it and heavy-tailed
instrument noise is not underestimated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.diagnostics.evidence import partial_greys
from workbench.session import Session

__all__ = [
    "NoiseModel",
    "estimate_noise",
    "copy_rows",
    "DEFAULT_GAIN_SD",
    "DEFAULT_CHROMA_SD",
    "DEFAULT_FLOOR_FRACTION",
    "DEFAULT_DOF",
    "MIN_SWEEP_LEVELS",
]

DEFAULT_GAIN_SD = 0.002
"""Instrument default luminance repeatability (1σ, relative): a CS-2000 specifies 0.15 % (2σ)
on bright patches, a tristimulus colorimeter such as the i1 DisplayPro about 0.2 %."""

DEFAULT_CHROMA_SD = 0.0005
"""Instrument default per-coordinate relative noise (≈ 0.0002 in xy at a display white)."""

DEFAULT_FLOOR_FRACTION = 2e-5
"""Instrument default absolute floor as a fraction of the white's Y."""

DEFAULT_DOF = 1000.0
"""Degrees of freedom given to the stated instrument default (treated as known)."""

MIN_SWEEP_LEVELS = 7
"""A sweep needs this many levels for its scatter to estimate noise."""

_CHI2_1_MEDIAN = 0.45493642311957174
_BRIGHT = 0.05  # of white Y: points that estimate the relative noise
_DARK = 0.02  # of white Y: points that estimate the floor
_MIN_POINTS = 8


@dataclass(frozen=True)
class NoiseModel:
    """Noise of one measurement (module doc for the form).

    Attributes
    ----------
    gain_sd : float
        ``a``, relative luminance repeatability (1σ).
    chroma_sd : float
        ``c``, relative per-coordinate noise (1σ).
    floor : float
        ``b``, absolute floor per coordinate, in the session's XYZ units.
    white_Y : float
        Luminance of the white the figures are quoted against.
    white_xy : tuple
        Chromaticity of that white.
    source : str
        Where ``a`` came from: ``sweep scatter``, ``repeats`` or ``instrument default``.
    repeat_gain_sd : float or None
        ``a`` estimated from repeated patches (reported beside the model's).
    scatter_gain_sd : float or None
        ``a`` from the sweeps' whole scatter, wander included (the model's
        ``a`` uses only differences between points measured one after another).
    sweep_points : int
        Sweep points whose scatter was used.
    repeat_groups : int
        Groups of repeated patches used.
    dof : float
        Degrees of freedom of the estimate of ``a`` (tests use Student t / F
        with it, so an estimate from few points cannot produce findings):
        Satterthwaite's, from the squares the estimate averaged
        (:func:`effective_dof`: their count, shrunk by the dispersion of the
        squares, which heavy-tailed noise raises, and by the overlap of
        successive differences), or :data:`DEFAULT_DOF` for the stated
        default.
    copies : int
        Rows excluded as exact copies of an earlier row.
    """

    gain_sd: float
    chroma_sd: float
    floor: float
    white_Y: float
    white_xy: tuple
    source: str
    repeat_gain_sd: float | None = None
    scatter_gain_sd: float | None = None
    dof: float = DEFAULT_DOF
    sweep_points: int = 0
    repeat_groups: int = 0
    copies: int = 0

    def covariance(self, XYZ) -> np.ndarray:
        """Covariance (..., 3, 3) of one measurement of ``XYZ`` (..., 3)."""
        v = np.abs(np.asarray(XYZ, dtype=float))
        outer = self.gain_sd ** 2 * v[..., :, None] * v[..., None, :]
        diagonal = self.chroma_sd ** 2 * v ** 2 + self.floor ** 2
        return outer + diagonal[..., :, None] * np.eye(3)

    def sd_Y(self, Y) -> np.ndarray:
        """Standard deviation of one luminance measurement at ``Y``."""
        Y = np.abs(np.asarray(Y, dtype=float))
        return np.sqrt((self.gain_sd ** 2 + self.chroma_sd ** 2) * Y ** 2 + self.floor ** 2)

    def relative_sd_Y(self, Y) -> np.ndarray:
        """Standard deviation of one luminance measurement at ``Y`` relative to ``|Y|`` (``ΔY/Y``)."""
        Y = np.abs(np.asarray(Y, dtype=float))
        return self.sd_Y(Y) / np.maximum(Y, 1e-300)

    def sd_xy(self, XYZ) -> float:
        """Standard deviation of x (≈ of y) of one measurement of ``XYZ``."""
        XYZ = np.asarray(XYZ, dtype=float)
        jacobian = _xy_jacobian(XYZ)
        covariance = jacobian @ self.covariance(XYZ) @ jacobian.T
        return float(np.sqrt(np.mean(np.diag(covariance))))

    def relative_sd_at(self, fraction_of_white: float) -> float:
        """Relative luminance noise of a patch at ``fraction_of_white`` of the white's Y."""
        return float(self.sd_Y(fraction_of_white * self.white_Y) / (fraction_of_white * self.white_Y))

    def white_XYZ(self) -> np.ndarray:
        x, y = self.white_xy
        return np.array([x / y, 1.0, (1 - x - y) / y]) * self.white_Y

    def describe(self) -> str:
        """E.g. ``repeatability 0.21 % in Y, 0.0004 in xy at white; 1.5 % at 1 % of white``."""
        text = (f"repeatability {100 * self.relative_sd_at(1.0):.2f} % in Y, "
                f"{self.sd_xy(self.white_XYZ()):.4f} in xy at white; "
                f"{100 * self.relative_sd_at(0.01):.1f} % at 1 % of white")
        if self.source == "sweep scatter":
            text += (f" (from the scatter of {self.sweep_points} sweep points about a local fit, "
                     "between points measured one after another")
            if (self.scatter_gain_sd is not None
                    and self.scatter_gain_sd > 1.5 * self.relative_sd_at(1.0)):
                text += (f"; over the whole session they scatter by {100 * self.scatter_gain_sd:.2f} %:"
                         " the display wanders")
            if self.repeat_gain_sd is not None:
                text += (f"; repeated patches give {100 * self.repeat_gain_sd:.2f} %, drift "
                         "between them included")
            text += ")"
        elif self.source == "repeats":
            text += f" (from {self.repeat_groups} groups of repeated patches; no sweep long enough)"
        else:
            text += (" (instrument default: the session has no sweep of "
                     f"≥ {MIN_SWEEP_LEVELS} levels and no repeated patch)")
        if self.copies:
            text += (f"; {self.copies} row(s) identical to an earlier one to the last digit are "
                     "copies, not measurements, and were left out")
        return text

    def to_json(self) -> dict:
        return {
            "relative_sd_Y_at_white": self.relative_sd_at(1.0),
            "sd_xy_at_white": self.sd_xy(self.white_XYZ()),
            "relative_sd_Y_at_1pct_of_white": self.relative_sd_at(0.01),
            "gain_sd": self.gain_sd, "chroma_sd": self.chroma_sd, "floor": self.floor,
            "source": self.source, "repeat_gain_sd": self.repeat_gain_sd,
            "scatter_gain_sd": self.scatter_gain_sd,
            "dof": self.dof, "sweep_points": self.sweep_points,
            "repeat_groups": self.repeat_groups,
            "copies_excluded": self.copies, "summary": self.describe(),
        }


def _xy_jacobian(XYZ: np.ndarray) -> np.ndarray:
    """d(x, y)/d(X, Y, Z) (2, 3) at ``XYZ`` (3,)."""
    total = float(np.sum(XYZ))
    x, y = XYZ[0] / total, XYZ[1] / total
    return np.array([[1 - x, -x, -x], [-y, 1 - y, -y]]) / total


def copy_rows(session: Session) -> np.ndarray:
    """True for rows whose DAC values and XYZ equal an earlier row's exactly (copies)."""
    seen: set = set()
    copies = np.zeros(len(session), dtype=bool)
    for i in range(len(session)):
        key = (tuple(session.rgb[i]), tuple(session.XYZ[i]))
        copies[i] = key in seen
        seen.add(key)
    return copies


def _sweeps(session: Session, keep: np.ndarray) -> list[tuple[np.ndarray, ...]]:
    """(row index, drive, XYZ) of each single-channel ramp and of the grey ramp, one row per level.

    Full-field rows only: a patch shown as a window depends on its frame's load.
    """
    rgb = session.rgb
    keep = keep & (session.window_or_full >= 1.0)  # a window's output depends on its frame's load
    lit = rgb > 0
    single = [(lit.sum(axis=1) == 1) & lit[:, c] for c in range(3)]
    grey = partial_greys(rgb)
    out = []
    for rows, channel in [(s, c) for c, s in enumerate(single)] + [(grey, 0)]:
        rows = rows & keep
        levels = rgb[rows, channel]
        _, first = np.unique(levels, return_index=True)
        if first.size < MIN_SWEEP_LEVELS:
            continue
        index = np.flatnonzero(rows)[first]
        out.append((index, rgb[index, channel] / 255.0, session.XYZ[index]))
    return out


def _loo_operator(drive: np.ndarray, half_window: int = 3):
    """The linear map from a sweep's values to its leave-one-out local-quadratic residuals.

    Returns ``(A, index)``: ``residual = A @ values`` for the points ``index``
    (those with ``half_window`` neighbours on each side); row ``i`` of ``A`` is
    1 at the point itself and minus the neighbours' weights in the quadratic's
    prediction of it, so the residual's variance is ``Σ_k A_ik² σ_k²``.
    """
    n = drive.size
    rows, index = [], []
    for i in range(half_window, n - half_window):
        neighbours = np.r_[i - half_window:i, i + 1:i + 1 + half_window]
        design = np.column_stack([np.ones(neighbours.size), drive[neighbours] - drive[i],
                                  (drive[neighbours] - drive[i]) ** 2])
        try:
            weights = np.linalg.solve(design.T @ design, design.T)[0]
        except np.linalg.LinAlgError:
            continue
        row = np.zeros(n)
        row[i] = 1.0
        row[neighbours] -= weights
        rows.append(row)
        index.append(i)
    return np.asarray(rows).reshape(-1, n), np.asarray(index, dtype=int)


def _robust_variance(squares: np.ndarray) -> float:
    """Mean of the squares winsorized at 16× their median-based scale (4σ).

    A plain median underestimates the variance of heavy-tailed noise (a
    Student t, which instruments show); a plain mean lets one bad reading
    or a quantization step dominate. Winsorizing at 4σ keeps the tails that
    noise has and caps those it does not.
    """
    return float(np.mean(_winsorized(squares)))


def _winsorized(squares: np.ndarray) -> np.ndarray:
    """``squares`` capped at 16× their median-based scale (4σ)."""
    squares = np.asarray(squares, dtype=float)
    scale = float(np.median(squares) / _CHI2_1_MEDIAN)
    return np.minimum(squares, 16.0 * scale)


SUCCESSIVE_OVERLAP = 1.5
"""Variance inflation of a mean of squared successive differences: neighbouring differences share
a residual (correlation −½, so ¼ between their squares: 1 + 2 · ¼)."""


def effective_dof(squares: np.ndarray, overlap: float = 1.0) -> float:
    """Satterthwaite's degrees of freedom of a variance estimated as the mean of ``squares``.

    ``2 n mean² / var`` of the squares (winsorized as :func:`_robust_variance`
    does), divided by ``overlap`` where the squares are correlated; never more
    than a Gaussian sample of the same size (``n / overlap``). Heavy-tailed
    noise (a Student t with 6 dof has squares twice as dispersed as a
    Gaussian's) gets proportionally fewer: an F-test against it then keeps its
    stated false-alarm rate, whatever the noise's tails, without assuming them.
    """
    kept = _winsorized(squares)
    n = kept.size
    if n < 2:
        return 1.0
    mean = float(np.mean(kept))
    dispersion = float(np.var(kept, ddof=1)) / mean ** 2 if mean > 0 else 2.0
    return max(n / overlap * 2.0 / max(dispersion, 2.0), 1.0)


def estimate_noise(session: Session) -> NoiseModel:
    """The noise model of ``session`` (its fit rows; module doc for the method).

    Parameters
    ----------
    session : Session
        The rows a model may be fitted on (never the validation rows).
    """
    copies = copy_rows(session)
    white = session.white_XYZ if session.has_white else None
    if white is None:  # ramps only: the additive white
        tops = [session.XYZ[(session.rgb[:, c] >= 255) & (np.sum(session.rgb > 0, axis=1) == 1)]
                for c in range(3)]
        white = sum(t.mean(axis=0) for t in tops if len(t)) if any(len(t) for t in tops) else \
            session.XYZ[np.argmax(session.XYZ[:, 1])]
    white_Y = float(white[1])
    white_xy = (float(white[0] / white.sum()), float(white[1] / white.sum()))

    gain_sq, successive_sq, chroma_sq, dark = [], [], [], []
    for rows, drive, XYZ in _sweeps(session, ~copies):
        A, index = _loo_operator(drive)
        if index.size == 0:
            continue
        Y = XYZ[:, 1]
        r = A @ Y
        level = Y[index] / white_Y
        bright, dim = level >= _BRIGHT, level < _DARK
        # relative gain noise: the residual's variance is a² Σ_k A_ik² Y_k²
        spread = np.sqrt((A ** 2) @ Y ** 2)
        gain_sq.extend((r[bright] / spread[bright]) ** 2)
        # the same, from differences of residuals of points measured one after the other:
        # free of a display that wanders during the session
        time = rows[index][bright]
        order = np.argsort(time, kind="stable")
        A_b, r_b = A[bright][order], r[bright][order]
        for j in range(len(order) - 1):
            difference = np.sqrt(((A_b[j] - A_b[j + 1]) ** 2) @ Y ** 2)
            successive_sq.append(((r_b[j] - r_b[j + 1]) / difference) ** 2)
        dark.extend(zip(Y[index][dim], r[dim] ** 2 / ((A[dim] ** 2).sum(axis=1))))
        total = XYZ.sum(axis=1)
        for k in range(2):
            coordinate = XYZ[:, k] / total
            rc = A @ coordinate
            xyz = XYZ[index] / total[index, None]
            other = np.delete(xyz, k, axis=1)
            scale = xyz[:, k] ** 2 * ((1 - xyz[:, k]) ** 2 + np.sum(other ** 2, axis=1))
            inflation = (A ** 2).sum(axis=1)
            chroma_sq.extend(rc[bright] ** 2 / inflation[bright] / scale[bright])

    repeat_sq, groups = [], 0
    # a repeat is the same patch under the same frame (window, surround): an OLED shows a patch
    # dimmer when more of the frame is lit, which is apl-dependence, not noise
    keys = [tuple(v) + (w,) + tuple(s) for v, w, s in
            zip(session.rgb, session.window_or_full, session.surround_or_black)]
    for key in set(keys):
        rows = np.flatnonzero([(k == key) for k in keys] & ~copies)
        if rows.size < 2 or max(key[:3]) <= 0:
            continue
        Y = session.XYZ[rows, 1]
        if np.mean(Y) < _BRIGHT * white_Y:
            continue
        groups += 1
        deviations = Y / Y.mean() - 1.0
        repeat_sq.extend(deviations ** 2 * rows.size / (rows.size - 1))
    repeat_gain = float(np.sqrt(np.mean(repeat_sq))) if repeat_sq else None

    sweep_points = len(gain_sq)
    scatter_gain = np.sqrt(_robust_variance(np.asarray(gain_sq))) if gain_sq else None
    dof = DEFAULT_DOF
    if len(successive_sq) >= _MIN_POINTS:
        relative = _robust_variance(np.asarray(successive_sq))
        source = "sweep scatter"
        dof = effective_dof(successive_sq, SUCCESSIVE_OVERLAP)
    elif repeat_gain is not None:
        relative = repeat_gain ** 2
        source = "repeats"
        dof = max(effective_dof(repeat_sq) * (len(repeat_sq) - groups) / len(repeat_sq), 1.0)
    else:
        relative = DEFAULT_GAIN_SD ** 2
        source = "instrument default"
    chroma_var = (_robust_variance(np.asarray(chroma_sq)) if len(chroma_sq) >= _MIN_POINTS
                  else DEFAULT_CHROMA_SD ** 2)
    chroma_var = min(chroma_var, relative)  # a coordinate cannot be noisier than the total
    gain_var = max(relative - chroma_var, 0.0)
    floor_var = (DEFAULT_FLOOR_FRACTION * white_Y) ** 2
    if len(dark) >= _MIN_POINTS:
        Y_dark, squares = (np.asarray(v) for v in zip(*dark))
        floor_var = max(_robust_variance(squares - relative * Y_dark ** 2), floor_var * 0.01)
    blacks = session.XYZ[np.all(session.rgb <= 0, axis=1) & ~copies, 1]
    if blacks.size >= 2:  # repeated blacks measure the floor directly
        floor_var = max(floor_var, float(np.var(blacks, ddof=1)))
    return NoiseModel(gain_sd=float(np.sqrt(gain_var)), chroma_sd=float(np.sqrt(chroma_var)),
                      floor=float(np.sqrt(floor_var)), white_Y=white_Y, white_xy=white_xy,
                      source=source, repeat_gain_sd=repeat_gain, scatter_gain_sd=scatter_gain,
                      dof=float(dof), sweep_points=sweep_points,
                      repeat_groups=groups, copies=int(copies.sum()))
