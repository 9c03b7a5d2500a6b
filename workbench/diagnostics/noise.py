"""The session's own noise model: how well one measurement is known, at every level.

A measurement ``v = (X, Y, Z)`` of a patch whose true value is ``v₀`` is modelled as

``v = v₀ · (1 + ε_gain) + J(v₀) · ε_xy + ε_floor``

- ``ε_gain ~ N(0, a²)``: a whole-measurement gain (the luminance repeatability),
  common to X, Y and Z;
- ``ε_xy ~ N(0, s² I₂)``: the chromaticity noise, independent in x and in y
  and of the luminance (a spectroradiometer specifies it apart: the CS-2000
  repeats Lv to 0.15 % and xy to ±0.0002). ``J = ∂(X, Y, Z)/∂(x, y)`` at
  constant Y (``X = xY/y``, ``Z = (1 − x − y)Y/y``) carries it into XYZ:
  ``J = [[S, −X/y], [0, 0], [−S, −(Y + Z)/y]]``, ``S = X + Y + Z``. The
  same ``s`` is a small relative error in the X and Z of a white but a large
  one in those of a deep blue (y ≈ 0.05: ±0.0002 in y is 0.4 % of its X and
  Z), which is why it is a term of its own and not a share of each coordinate;
- ``ε_floor ~ N(0, b²)`` per coordinate, ``b`` in the session's XYZ units: the
  absolute floor that dominates dark patches.

so ``Cov(v) = a² v₀ v₀ᵀ + s² J Jᵀ + b² I`` (:meth:`NoiseModel.covariance`).

Where the numbers come from (:func:`estimate_noise`), all from the rows a
model may be fitted on:

- **Sweep scatter.** Every sweep with at least :data:`MIN_SWEEP_LEVELS`
  levels (each channel's ramp, the grey ramp; full-field rows) is predicted point by point by
  a quadratic through its neighbours (three on each side, the point itself
  left out); the residuals are a known linear map ``A`` of the measurements,
  so their variance is exact (``Σ_k A_ik² σ_k²``). ``a`` comes from the
  differences of the residuals of bright points (Y ≥ 5 % of white) measured
  one after another, which a display that drifts or wanders over minutes
  does not inflate (the whole scatter is reported beside it); ``s`` from the
  residuals of x and y of the same bright points (the floor's share of them
  taken out); ``b`` from the dark points (Y < 2 % of white; :func:`floor_from_dark`) and
  repeated blacks. This is why the drift test can use it: it does not come
  from the references under test.
- **Repeated patches.** Rows with the same DAC values (under the same frame:
  window and surround) measured more than once
  (the white references, repeated blacks, any other repeats) give a second
  estimate of ``a``, reported beside the first. Rows whose XYZ equal an
  earlier row's to the last digit are copies (DisplayCAL writes its first
  whites that way), not measurements: they are excluded and counted. The
  white references also carry any drift between them, so this estimate is
  the model's only when there are no sweeps to estimate from. Their
  chromaticities, differenced between successive repeats of the same patch
  (a slow drift cancels), add to the squares that estimate ``s``.
- **Instrument default.** Without sweeps or repeats:
  :data:`DEFAULT_GAIN_SD`, :data:`INSTRUMENT_XY_SD` and
  :data:`DEFAULT_FLOOR_FRACTION`, and the model says so.
- **Chromaticity floor.** ``s`` is never below :data:`INSTRUMENT_XY_SD`, the
  CS-2000's specified xy repeatability: a session has few repeats, and a
  sweep's bright points are mostly those of the white-ish greys and the red
  and green ramps, so its own estimate can fall short of what a deep blue
  primary's chromaticity does from reading to reading.

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
    "floor_from_dark",
    "DEFAULT_GAIN_SD",
    "INSTRUMENT_XY_SD",
    "xy_to_XYZ_jacobian",
    "DEFAULT_FLOOR_FRACTION",
    "DEFAULT_DOF",
    "MIN_SWEEP_LEVELS",
]

DEFAULT_GAIN_SD = 0.002
"""Instrument default luminance repeatability (1σ, relative): a CS-2000 specifies 0.15 % (2σ)
on bright patches, a tristimulus colorimeter such as the i1 DisplayPro about 0.2 %."""

INSTRUMENT_XY_SD = 0.0002
"""Chromaticity noise (1σ, in x and in y) of one bright measurement, the floor of ``s``.

Konica Minolta's CS-2000 specification gives an xy repeatability of ±0.0002 for
a bright patch (its luminance repeatability, 0.15 % in Lv, is specified apart;
both are quoted for illuminant A, xy worsening below about 1 cd/m²). It is
used here as one standard deviation: the specification's figure is for a
broadband source, and a display's deep blue primary (little ȳ signal, y ≈ 0.05)
repeats its xy no better than that. A session's own scatter raises it, never
lowers it."""

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
    xy_sd : float
        ``s``, chromaticity noise in x and in y (1σ): the session's own
        estimate or :data:`INSTRUMENT_XY_SD`, whichever is larger.
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
    session_xy_sd : float or None
        ``s`` from the session's own squares (sweep residuals, successive
        repeats), before the floor; None with fewer than eight of them.
    xy_points : int
        Squares of x and y that estimate ``session_xy_sd``.
    xy_dof : float
        Degrees of freedom of ``s``: Satterthwaite's from its squares where
        the session's estimate is the model's, :data:`DEFAULT_DOF` where the
        floor is (the specification, treated as known). Tests whose variance
        is mostly chromaticity noise weigh it against ``dof``
        (:meth:`chromaticity_covariance` gives that part).
    """

    gain_sd: float
    xy_sd: float
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
    session_xy_sd: float | None = None
    xy_points: int = 0
    xy_dof: float = DEFAULT_DOF

    def covariance(self, XYZ) -> np.ndarray:
        """Covariance (..., 3, 3) of one measurement of ``XYZ`` (..., 3).

        ``a² v vᵀ + s² J Jᵀ + b² I`` (module doc): the gain, the chromaticity
        noise carried through ``J = ∂(X, Y, Z)/∂(x, y)`` at constant Y, the floor.
        """
        v = np.abs(np.asarray(XYZ, dtype=float))
        outer = self.gain_sd ** 2 * v[..., :, None] * v[..., None, :]
        return outer + self.chromaticity_covariance(v) + self.floor ** 2 * np.eye(3)

    def chromaticity_covariance(self, XYZ) -> np.ndarray:
        """The chromaticity noise's part of :meth:`covariance`: ``s² J Jᵀ`` (..., 3, 3)."""
        jacobian = xy_to_XYZ_jacobian(np.abs(np.asarray(XYZ, dtype=float)))
        return self.xy_sd ** 2 * jacobian @ np.swapaxes(jacobian, -1, -2)

    def sd_Y(self, Y) -> np.ndarray:
        """Standard deviation of one luminance measurement at ``Y``."""
        Y = np.abs(np.asarray(Y, dtype=float))
        return np.sqrt(self.gain_sd ** 2 * Y ** 2 + self.floor ** 2)

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
        if self.session_xy_sd is None:
            text += (f"; xy noise {self.xy_sd:.5f}, the instrument floor (the CS-2000's specified "
                     "repeatability; too few sweep points or repeats to estimate it)")
        elif self.session_xy_sd <= self.xy_sd:
            text += (f"; xy noise {self.xy_sd:.5f}, the instrument floor (the CS-2000's specified "
                     f"repeatability; the session's own scatter gives {self.session_xy_sd:.5f} "
                     f"from {self.xy_points} squares of x and y)")
        else:
            text += (f"; xy noise {self.xy_sd:.5f} from {self.xy_points} squares of x and y "
                     "(sweep residuals, successive repeats)")
        if self.copies:
            text += (f"; {self.copies} row(s) identical to an earlier one to the last digit are "
                     "copies, not measurements, and were left out")
        return text

    def to_json(self) -> dict:
        return {
            "relative_sd_Y_at_white": self.relative_sd_at(1.0),
            "sd_xy_at_white": self.sd_xy(self.white_XYZ()),
            "relative_sd_Y_at_1pct_of_white": self.relative_sd_at(0.01),
            "gain_sd": self.gain_sd, "xy_sd": self.xy_sd,
            "session_xy_sd": self.session_xy_sd, "xy_points": self.xy_points,
            "xy_dof": self.xy_dof,
            "instrument_xy_sd": INSTRUMENT_XY_SD, "floor": self.floor,
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


_MIN_Y_SHARE = 1e-3  # y below this (no display primary) is taken at it: J stays finite


def xy_to_XYZ_jacobian(XYZ) -> np.ndarray:
    """∂(X, Y, Z)/∂(x, y) at constant Y (..., 3, 2), at ``XYZ`` (..., 3).

    ``X = xY/y`` and ``Z = (1 − x − y)Y/y``: ``[[S, −X/y], [0, 0], [−S, −(Y + Z)/y]]``
    with ``S = X + Y + Z`` and ``y = Y/S``. Zero where ``S`` is not positive.
    """
    v = np.asarray(XYZ, dtype=float)
    X, Y, Z = v[..., 0], v[..., 1], v[..., 2]
    S = X + Y + Z
    positive = S > 0
    S = np.where(positive, S, 0.0)
    y = np.maximum(np.divide(Y, S, out=np.zeros_like(S), where=positive), _MIN_Y_SHARE)
    jacobian = np.zeros(v.shape + (2,))
    jacobian[..., 0, 0] = S
    jacobian[..., 0, 1] = -np.where(positive, X, 0.0) / y
    jacobian[..., 2, 0] = -S
    jacobian[..., 2, 1] = -np.where(positive, Y + Z, 0.0) / y
    return jacobian


def _xy_floor_factor(XYZ: np.ndarray) -> np.ndarray:
    """Variance of x and of y (N, 2) per unit floor variance ``b²`` at each ``XYZ`` (N, 3).

    Zero where the total is not positive (a point that dark carries no weight where it is used).
    """
    total = XYZ.sum(axis=1)
    positive = total > 0
    safe = np.where(positive, total, 1.0)
    x, y = XYZ[:, 0] / safe, XYZ[:, 1] / safe
    factor = np.column_stack([(1 - x) ** 2 + 2 * x ** 2, (1 - y) ** 2 + 2 * y ** 2]) / safe[:, None] ** 2
    return np.where(positive[:, None], factor, 0.0)


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


def floor_from_dark(squares: np.ndarray, relative: np.ndarray, start: float) -> float:
    """The floor's variance ``b²`` from the dark points' squared residuals (each normalized to
    one measurement's variance, ``a² Y² + b²`` expected) and their relative part ``a² Y²``.

    Each square is winsorized at 16× the median-based scale of the squares in units of its own
    expected variance (4σ, as :func:`_robust_variance`), and ``b²`` is the excess over the
    relative part averaged with weights ``1 / (a² Y² + b²)²`` (each point by what it says of
    ``b``: the darkest most), iterated to a fixed point from ``start``. The relative part
    cannot be taken out before winsorizing: where it dominates the dark points (a panel whose
    darkest sweep levels are still a few % of white at a 0.4 % gain noise), the differences
    have a negative median, every one was capped below zero, and the floor fell to its clamp,
    a tenth of the instrument default: on the independent generator (floor 0.0035, white 177)
    it read 0.0003, the dark ends of the sweeps weighed a hundred times too much, and a blue
    sweep whose DAC 5 read 0.013 above its true value (4σ of the real floor) was "not a power
    law".
    """
    floor = max(float(start), 0.0)
    for _ in range(20):
        expected = relative + floor
        safe = np.where(expected > 0, expected, 1.0)
        units = squares / safe
        cap = 16.0 * float(np.median(units)) / _CHI2_1_MEDIAN
        weights = 1.0 / safe ** 2
        excess = np.minimum(units, cap) * expected - relative
        updated = max(float(np.sum(weights * excess) / np.sum(weights)), 0.0)
        if abs(updated - floor) <= 1e-6 * max(floor, 1e-300):
            return updated
        floor = updated
    return floor


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

    gain_sq, successive_sq, dark = [], [], []
    xy_sq, xy_floor = [], []  # squares of x and y residuals, and their floor share per unit b²
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
        # chromaticity noise: the residual of x (of y) has variance s² Σ_k A_ik² plus the
        # floor's share, b² Σ_k A_ik² f_k (taken out once b is known)
        total = XYZ.sum(axis=1)
        inflation = (A ** 2).sum(axis=1)[bright]
        floor_factor = (A ** 2)[bright] @ _xy_floor_factor(XYZ)
        for k in range(2):
            rc = A @ (XYZ[:, k] / total)
            xy_sq.extend(rc[bright] ** 2 / inflation)
            xy_floor.extend(floor_factor[:, k] / inflation)

    repeat_sq, groups = [], 0
    # a repeat is the same patch under the same frame (window, surround): an OLED shows a patch
    # dimmer when more of the frame is lit, which is apl-dependence, not noise
    keys = [tuple(v) + (w,) + tuple(s) for v, w, s in
            zip(session.rgb, session.window_or_full, session.surround_or_black)]
    order = np.argsort(session.t_s, kind="stable") if session.t_s is not None else \
        np.arange(len(session))
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
        # chromaticity: differences between successive repeats (a slow drift cancels), halved
        rows = rows[np.argsort(np.argsort(order)[rows], kind="stable")]
        XYZ = session.XYZ[rows]
        xy = XYZ[:, :2] / XYZ.sum(axis=1)[:, None]
        factor = _xy_floor_factor(XYZ)
        xy_sq.extend((np.diff(xy, axis=0) ** 2 / 2).ravel())
        xy_floor.extend(((factor[1:] + factor[:-1]) / 2).ravel())
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
    floor_var = (DEFAULT_FLOOR_FRACTION * white_Y) ** 2
    if len(dark) >= _MIN_POINTS:
        Y_dark, squares = (np.asarray(v) for v in zip(*dark))
        # the larger of the excess winsorized as differences (too low where the relative part
        # dominates) and floor_from_dark's: alone, the weighted estimate read a lower floor on a
        # real chart (a GPD Win, black-point compensated), a chromaticity term passed its test
        # at z 2.55 against 2.33, and its 286 held-out colours went 0.296 → 0.378 mean ΔE00
        relative_part = relative * Y_dark ** 2
        floor_var = max(_robust_variance(squares - relative_part),
                        floor_from_dark(squares, relative_part, floor_var), floor_var * 0.01)
    blacks = session.XYZ[np.all(session.rgb <= 0, axis=1) & ~copies, 1]
    if blacks.size >= 2:  # repeated blacks measure the floor directly
        floor_var = max(floor_var, float(np.var(blacks, ddof=1)))
    session_xy, xy_dof = None, DEFAULT_DOF
    if len(xy_sq) >= _MIN_POINTS:
        variance = _robust_variance(np.asarray(xy_sq)) - floor_var * float(np.mean(xy_floor))
        session_xy = float(np.sqrt(max(variance, 0.0)))
        if session_xy > INSTRUMENT_XY_SD:  # the session's own estimate is the model's
            xy_dof = effective_dof(xy_sq, SUCCESSIVE_OVERLAP)
    xy_sd = max(session_xy or 0.0, INSTRUMENT_XY_SD)
    return NoiseModel(gain_sd=float(np.sqrt(relative)), xy_sd=float(xy_sd),
                      floor=float(np.sqrt(floor_var)), white_Y=white_Y, white_xy=white_xy,
                      source=source, repeat_gain_sd=repeat_gain, scatter_gain_sd=scatter_gain,
                      dof=float(dof), sweep_points=sweep_points,
                      repeat_groups=groups, copies=int(copies.sum()),
                      session_xy_sd=session_xy, xy_points=len(xy_sq), xy_dof=float(xy_dof))
