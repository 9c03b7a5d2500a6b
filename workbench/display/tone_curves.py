"""Per-channel tone curves: normalized drive ``d ∈ [0, 1]`` → normalized output ``L ∈ [0, 1]``.

``L`` is the channel's black-subtracted output relative to full drive. Each
form has a forward, an inverse, JSON parameters and a least-squares fit; the
registry :data:`TONE_CURVES` and :func:`fit_tone_curve` pick one by name, and
:func:`select_tone_curve` picks the form with the lowest BIC.

Forms
-----
==================  ========================================
``power``           ``L = d^γ`` (the paper's).
``gog``             gain-offset-gamma, ``L = max(0, (1 − o)·d + o)^γ``: a negative
                    offset ``o`` is a black crush (toe), a positive one a lifted black.
``extended-power``  ``L = d^(γ + β·ln d)``: a power law whose exponent drifts with level
                    (shoulder or S-shaped departures).
``spline``          monotone piecewise-cubic (PCHIP) through the measured points after
                    isotonic regression: the 1D LUT from the sweeps.
``linear``          the same points joined by straight lines (the seed authors' grey-ramp
                    linearisation interpolates this way; PCHIP overshoots between two
                    nearly coincident levels, which real charts hold);
                    :func:`along_power_segments` tabulates the power laws through
                    consecutive points in this form.
==================  ========================================

The two table forms are fitted through the measured levels, or through the
levels smoothed where that predicts a left-out level better beyond noise
(:func:`smoothed_points`); the profile stores the points either way.

References
----------
Berns, R. S. (1996). Methods for characterizing CRT displays. Displays, 16(4),
173–182 (the GOG model).
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.optimize import brentq, least_squares

from workbench.display.smoothing import whittaker_pinned
from workbench.errors import InputError

__all__ = [
    "ToneCurve",
    "noise_weights",
    "PowerCurve",
    "GOGCurve",
    "ExtendedPowerCurve",
    "SplineCurve",
    "LinearCurve",
    "POWER_SEGMENT_GRID",
    "along_power_segments",
    "SWEEP_SEGMENT_LEVELS",
    "along_sweep_segments",
    "SmoothedPoints",
    "smoothed_points",
    "TONE_CURVES",
    "fit_tone_curve",
    "tone_curve_from_parameters",
    "select_tone_curve",
    "bic",
    "isotonic",
]


def isotonic(values: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Non-decreasing least-squares fit (pool-adjacent-violators)."""
    values = np.asarray(values, dtype=float)
    weights = np.ones_like(values) if weights is None else np.asarray(weights, dtype=float)
    blocks: list[list[float]] = []  # [mean, weight, count]
    for value, weight in zip(values, weights):
        blocks.append([value, weight, 1])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            v2, w2, n2 = blocks.pop()
            v1, w1, n1 = blocks.pop()
            blocks.append([(v1 * w1 + v2 * w2) / (w1 + w2), w1 + w2, n1 + n2])
    return np.concatenate([np.full(int(n), v) for v, _, n in blocks])


class ToneCurve(abc.ABC):
    form = ""
    n_parameters = 0

    @abc.abstractmethod
    def forward(self, drive) -> np.ndarray:
        """Normalized output for normalized drive (clipped to [0, 1])."""

    @abc.abstractmethod
    def inverse(self, output) -> np.ndarray:
        """Normalized drive for normalized output (clipped to [0, 1])."""

    @abc.abstractmethod
    def parameters(self) -> dict:
        ...

    def to_json(self) -> dict:
        return {"form": self.form, **self.parameters()}


def _drive(drive) -> np.ndarray:
    return np.clip(np.asarray(drive, dtype=float), 0.0, 1.0)


_INVERSE_GRID = np.linspace(0.0, 1.0, 255 * 64 + 1)  # 1/64 of a DAC count


def _table_inverse(curve: "ToneCurve", output) -> np.ndarray:
    """Invert a monotone forward through a dense table of its own values (exact to 1/64 count)."""
    values = np.maximum.accumulate(curve.forward(_INVERSE_GRID))
    # the first drive reaching each output, so flat stretches invert to their start
    return np.interp(_drive(output), values, _INVERSE_GRID, left=0.0, right=1.0)


def _positive(name: str, value: float, form: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"tone curve {form!r}: {name} must be a positive number, got {value!r}")
    return value


def noise_weights(output) -> np.ndarray:
    """Least-squares weights of normalized outputs: one over a spectroradiometer's noise.

    Relative noise with a floor: bright levels are known to about 0.2 %, dark ones to about
    1e-4 of full drive (a CS-2000's repeatability and its dark end).
    """
    return 1.0 / (0.002 * np.abs(np.asarray(output, dtype=float)) + 1e-4)


@dataclass(frozen=True)
class PowerCurve(ToneCurve):
    gamma: float

    form = "power"
    n_parameters = 1

    def __post_init__(self):
        object.__setattr__(self, "gamma", _positive("gamma", self.gamma, self.form))

    def forward(self, drive):
        return _drive(drive) ** self.gamma

    def inverse(self, output):
        return _drive(output) ** (1.0 / self.gamma)

    def parameters(self):
        return {"gamma": float(self.gamma)}

    @classmethod
    def fit(cls, drive, output):
        """Weighted least squares in ``γ`` on [0.2, 8] (one dimension: bounded Brent search)."""
        from scipy.optimize import minimize_scalar

        w = noise_weights(output)
        drive = np.asarray(drive, dtype=float)
        result = minimize_scalar(lambda g: float(np.sum(((drive ** g - output) * w) ** 2)),
                                 bounds=(0.2, 8.0), method="bounded",
                                 options={"xatol": 1e-7})
        return cls(float(result.x))


@dataclass(frozen=True)
class GOGCurve(ToneCurve):
    offset: float
    gamma: float

    form = "gog"
    n_parameters = 2

    def __post_init__(self):
        object.__setattr__(self, "gamma", _positive("gamma", self.gamma, self.form))
        if not (np.isfinite(self.offset) and -1.0 < self.offset < 1.0):
            raise InputError(f"tone curve 'gog': offset must lie in (-1, 1), got {self.offset!r}")

    def forward(self, drive):
        return np.maximum(0.0, (1.0 - self.offset) * _drive(drive) + self.offset) ** self.gamma

    def inverse(self, output):
        """Closed form; output 0 (black) inverts to DAC 0, anything brighter to above the toe."""
        output = _drive(output)
        drive = (output ** (1.0 / self.gamma) - self.offset) / (1.0 - self.offset)
        return np.where(output <= 0, 0.0, np.clip(drive, 0.0, 1.0))

    def parameters(self):
        return {"offset": float(self.offset), "gamma": float(self.gamma)}

    @classmethod
    def fit(cls, drive, output):
        w = noise_weights(output)

        def residual(p):
            return (np.maximum(0.0, (1 - p[0]) * drive + p[0]) ** p[1] - output) * w

        result = least_squares(residual, x0=[0.0, 2.2], bounds=([-0.5, 0.2], [0.5, 8.0]))
        return cls(float(result.x[0]), float(result.x[1]))


_HALF_COUNT = 0.5 / 255.0
_MONOTONE_SPAN = 2.0 * np.log(1.0 / _HALF_COUNT)


@dataclass(frozen=True)
class ExtendedPowerCurve(ToneCurve):
    """``L = d^(γ + β ln d)``, kept monotone: ``β ≤ γ / (2 ln 510)``.

    The exponent's log-derivative ``γ + 2β ln d`` stays positive down to half
    a DAC count; below that the curve is continued linearly to 0.
    """

    gamma: float
    beta: float

    form = "extended-power"
    n_parameters = 2

    def __post_init__(self):
        object.__setattr__(self, "gamma", _positive("gamma", self.gamma, self.form))
        limit = self.gamma / _MONOTONE_SPAN
        if not (np.isfinite(self.beta) and self.beta <= limit + 1e-12):
            raise InputError(f"tone curve 'extended-power': beta {self.beta!r} makes the curve "
                             f"non-monotone; it must be at most gamma / (2 ln 510) = {limit:.4g}")

    def _power(self, d):
        return d ** (self.gamma + self.beta * np.log(d))

    def forward(self, drive):
        d = _drive(drive)
        floor = self._power(_HALF_COUNT)
        safe = np.maximum(d, _HALF_COUNT)
        return np.where(d >= _HALF_COUNT, self._power(safe), floor * d / _HALF_COUNT)

    def inverse(self, output):
        return _table_inverse(self, output)

    def parameters(self):
        return {"gamma": float(self.gamma), "beta": float(self.beta)}

    @classmethod
    def fit(cls, drive, output):
        w = noise_weights(output)
        d = np.maximum(drive, _HALF_COUNT)

        def curve(p):  # β = t·γ/(2 ln 510) with t ≤ 1 keeps the curve monotone
            gamma, beta = p[0], p[1] * p[0] / _MONOTONE_SPAN
            return d ** (gamma + beta * np.log(d))

        result = least_squares(lambda p: (curve(p) - output) * w, x0=[2.2, 0.0],
                               bounds=([0.2, -20.0], [8.0, 1.0]))
        gamma = float(result.x[0])
        return cls(gamma, float(result.x[1]) * gamma / _MONOTONE_SPAN)


@dataclass(frozen=True, eq=False)
class SplineCurve(ToneCurve):
    """Monotone PCHIP through (0, 0), the isotonic-regressed points, and (1, 1)."""

    drive_points: tuple[float, ...]
    output_points: tuple[float, ...]

    form = "spline"

    @property
    def n_parameters(self) -> int:  # type: ignore[override]
        return max(len(self.drive_points) - 2, 1)

    def __post_init__(self):
        d = np.asarray(self.drive_points, dtype=float)
        L = np.asarray(self.output_points, dtype=float)
        if (d.ndim != 1 or d.shape != L.shape or d.size < 2 or not np.all(np.isfinite(d))
                or not np.all(np.isfinite(L)) or np.any(np.diff(d) <= 0) or np.any(np.diff(L) < 0)
                or d[0] != 0.0 or d[-1] != 1.0):
            raise InputError("tone curve 'spline': drive points must rise strictly from 0 to 1 "
                             "and output points must not decrease, one per drive point")
        object.__setattr__(self, "_forward", PchipInterpolator(d, L, extrapolate=True))

    def forward(self, drive):
        return np.clip(self._forward(_drive(drive)), 0.0, 1.0)

    def inverse(self, output):
        return _table_inverse(self, output)

    def parameters(self):
        return {"drive": [float(v) for v in self.drive_points],
                "output": [float(v) for v in self.output_points]}

    @classmethod
    def fit(cls, drive, output):
        """Through the points smoothed as far as leave-one-out allows (:func:`smoothed_points`)."""
        points = smoothed_points(drive, output, "pchip")
        return cls(*with_crush_edge(points.drive, points.output))


@dataclass(frozen=True, eq=False)
class LinearCurve(SplineCurve):
    """Monotone piecewise-linear through (0, 0), the isotonic-regressed points, and (1, 1)."""

    form = "linear"

    def __post_init__(self):
        super().__post_init__()
        d = np.asarray(self.drive_points, dtype=float)
        L = np.asarray(self.output_points, dtype=float)
        object.__setattr__(self, "_forward", lambda x: np.interp(x, d, L))

    STRICT_SLOPE = 1e-4
    """Added to the slope (then rescaled to end at 1) so a flat stretch still inverts uniquely."""

    @classmethod
    def fit(cls, drive, output):
        points = smoothed_points(drive, output, "linear")
        d, L = (np.asarray(v) for v in with_crush_edge(points.drive, points.output))
        L = (L + cls.STRICT_SLOPE * d) / (1.0 + cls.STRICT_SLOPE)
        return cls(tuple(d), tuple(L))


CRUSH_SHARE = 0.25
"""A level reads black beside a crush (:func:`with_crush_edge`) where its output is at most this
share of the power law through the next two levels, continued down to it."""


CRUSH_MIN_LIGHT = 0.005
"""The least output (share of full drive, above the black level) of the first lit level beside
a level that reads black, for :func:`with_crush_edge` to take the black reading for a crush."""


def with_crush_edge(drive, output) -> tuple[tuple, tuple]:
    """Table points with the edge of a black crush added where the points show one.

    A toe crushes the levels below an edge to black, and a table curve through a level that
    reads black and the first lit level above it draws its rise from the black level, where
    the light rises only from the edge: on a toe of the independent generator, read at the
    adaptive plan's greys 8 DAC apart, hidden colours with a channel between DAC 8 and 16 were
    0.6 ΔE00 off. Where a level ``d_k > 0`` reads at most :data:`CRUSH_SHARE` of the power law
    through the next two levels continued down to it, the edge ``d_0`` is where the lit levels
    above rise from (:func:`_crush_edge`); where ``d_k < d_0 < d_{k+1}`` the point
    ``(d_0, L_k)`` is added, so the curve stays at the black level up to the edge and rises
    from there. The highest such level is taken (one edge), and only where the first lit level
    gives at least :data:`CRUSH_MIN_LIGHT` above the black level: beside a dimmer one a reading
    of zero is what noise does to a lit level too (a negative reading clipped, or pooled by the
    isotonic regression; without the floor a reddish black beside an S-curve of the diagnosis
    suite went 0.137 → 0.536 ΔE00 on hidden colours).
    """
    d = np.asarray(drive, dtype=float)
    L = np.asarray(output, dtype=float)
    for k in range(d.size - 3, 0, -1):  # the level d_k that may read black, then two lit ones
        (d_k, d_1, d_2), (L_k, L_1, L_2) = d[k:k + 3], L[k:k + 3]
        if not 0.0 < L_1 < L_2 or not 0.0 < d_k:
            continue
        if not L_1 - L_k >= CRUSH_MIN_LIGHT:
            break  # the first lit level is too dim for a reading of black below it to tell
        exponent = np.log(L_2 / L_1) / np.log(d_2 / d_1)
        if not L_k <= CRUSH_SHARE * L_1 * (d_k / d_1) ** exponent:
            continue
        edge = _crush_edge(d_k, d[k + 1:k + 4], L[k + 1:k + 4] - L_k)
        if edge is not None and d_k < edge < d_1:
            d, L = np.insert(d, k + 1, edge), np.insert(L, k + 1, L_k)
        break
    return tuple(float(v) for v in d), tuple(float(v) for v in L)


def _crush_edge(black, d, L):
    """Where the light of the lit levels ``d`` (``L`` above the black level) rises from.

    The edge ``e`` of ``L = A (d − e)^γ`` through the first three levels where that rise is
    convex (``γ ≥ 1``, a power law starting at the edge); else (a rise that is steepest at the
    edge, as shadows lifted above a power law are, which the form reads as a late edge) the
    chord through the first two continued down to black. None where the form puts the edge at
    or below ``black`` (the level that reads black is then noise, not a crush).
    """
    if not (d.size >= 2 and 0 < L[0] < L[1]):
        return None
    chord = float(d[0] - L[0] * (d[1] - d[0]) / (L[1] - L[0]))
    if d.size < 3 or not L[2] > L[1]:
        return chord
    r1, r2 = np.log(L[1] / L[0]), np.log(L[2] / L[1])

    def mismatch(e):
        return r1 * np.log((d[2] - e) / (d[1] - e)) - r2 * np.log((d[1] - e) / (d[0] - e))

    if not mismatch(black) > 0:
        return None  # the form through them rises from the black level or below it
    top = d[0] * (1.0 - 1e-9)
    if not mismatch(top) < 0:
        return chord  # the form has no edge below the first lit level (a flat stretch above)
    edge = float(brentq(mismatch, black, top))
    return edge if r1 / np.log((d[1] - edge) / (d[0] - edge)) >= 1.0 else chord


POWER_SEGMENT_GRID = 300
"""Drives at which :func:`along_power_segments` tabulates its curve beside the curve's own
points: spaced evenly in ``log d`` from half a DAC count to full drive (2.1 % apart), so the
``linear`` form's straight lines between them stay within 2 parts in 10,000 of the power laws
at any level (evenly in ``d``, a DAC count apart, they were 0.4 % off at DAC 8)."""


def along_power_segments(curve: LinearCurve, grid: int = POWER_SEGMENT_GRID) -> LinearCurve:
    """``curve`` with each stretch between two lit points bent along the power law through them.

    A tone curve rises about as a power of the drive, and a straight line between two of its
    points is a chord above it: between greys 16 DAC apart at DAC 48 and 64, on a curve
    ``d^2.2``, 2.7 % too bright at DAC 56 (0.2–0.3 ΔE00 in every colour lit there), and a
    chord's error grows as the square of the stretch. Each stretch between two points of
    positive, rising output, ``(d_i, L_i)`` and ``(d_{i+1}, L_{i+1})``, is drawn as
    ``L_i (d / d_i)^k``, ``k = ln(L_{i+1} / L_i) / ln(d_{i+1} / d_i)``: through both points
    and between them, exact on a power law, and as a chord where ``d_{i+1} / d_i`` is near 1.
    The stretch from black to the first point, and a flat stretch, stay straight lines.

    Returns a :class:`LinearCurve` through the curve's points and the ``grid`` drives between
    them, so a profile stores and reads it as any ``linear`` curve.
    """
    d = np.asarray(curve.drive_points, dtype=float)
    L = np.asarray(curve.output_points, dtype=float)
    between = np.geomspace(_HALF_COUNT, 1.0, grid)
    between = between[np.min(np.abs(between[:, None] - d[None, :]), axis=1) > 1e-6]
    knots = np.union1d(between, d)
    values = np.interp(knots, d, L)
    for lo, hi, L_lo, L_hi in zip(d[1:-1], d[2:], L[1:-1], L[2:]):
        if not 0.0 < L_lo < L_hi:
            continue
        inside = (knots > lo) & (knots < hi)
        exponent = np.log(L_hi / L_lo) / np.log(hi / lo)
        values[inside] = L_lo * (knots[inside] / lo) ** exponent
    return LinearCurve(tuple(knots), tuple(values))


SWEEP_SEGMENT_LEVELS = 2
"""Sweep levels a stretch between two greys must hold inside it for
:func:`along_sweep_segments` to draw it in the sweep's shape."""


def along_sweep_segments(curve: LinearCurve, sweep_drive, sweep_output,
                         grid: int = POWER_SEGMENT_GRID) -> LinearCurve:
    """``curve`` with each stretch between two of its points drawn in the shape of the channel's
    own sweep where the sweep holds :data:`SWEEP_SEGMENT_LEVELS` levels inside it, along the power
    law through the two points elsewhere (:func:`along_power_segments`).

    Between greys ``(d_i, L_i)`` and ``(d_{i+1}, L_{i+1})`` the curve is
    ``L_i + (L_{i+1} − L_i) (S(d) − S(d_i)) / (S(d_{i+1}) − S(d_i))``, ``S`` the sweep's output
    (black subtracted) smoothed as a table tone curve is (:func:`smoothed_points`, ``"linear"``:
    made monotone, joined by straight lines): through both greys, and bent as the channel
    itself bends there, a toe's crush or a shoulder's as much as a power law's. The stretch from
    black to the first grey too, where the sweep holds the levels. Unsmoothed, the sweep's
    levels carried each reading's noise into every colour lit near them (on the peer bench's
    ``paper+greys`` sessions of seeds 30000 and 31000, drawn from the raw sweeps wherever the
    greys are coarse, a clean display went 0.073 → 0.143 mean ΔE00 on hidden colours).
    """
    bent = along_power_segments(curve, grid)
    d = np.asarray(curve.drive_points, dtype=float)
    L = np.asarray(curve.output_points, dtype=float)
    sd = np.asarray(sweep_drive, dtype=float)
    so = np.asarray(sweep_output, dtype=float)
    top = float(np.mean(so[sd >= 1.0])) if np.any(sd >= 1.0) else float(np.max(so, initial=0.0))
    if sd.size >= 3 and top > 0:
        smooth = smoothed_points(sd, np.clip(so / top, 0.0, 1.0), "linear")
        sd, so = np.asarray(smooth.drive), np.asarray(smooth.output)
    order = np.argsort(sd)
    sd, so = sd[order], np.maximum.accumulate(so[order])
    if sd.size == 0 or sd[0] > 0:
        sd, so = np.concatenate([[0.0], sd]), np.concatenate([[0.0], np.maximum(so, 0.0)])
    knots = np.union1d(np.asarray(bent.drive_points), sd[(sd > 0) & (sd < 1)])
    values = np.interp(knots, np.asarray(bent.drive_points), np.asarray(bent.output_points))
    for lo, hi, L_lo, L_hi in zip(d[:-1], d[1:], L[:-1], L[1:]):
        if np.sum((sd > lo) & (sd < hi)) < SWEEP_SEGMENT_LEVELS or not L_hi > L_lo:
            continue
        S_lo, S_hi = np.interp([lo, hi], sd, so)
        if not S_hi > S_lo:
            continue
        inside = (knots > lo) & (knots < hi)
        shape = (np.interp(knots[inside], sd, so) - S_lo) / (S_hi - S_lo)
        values[inside] = L_lo + (L_hi - L_lo) * shape
    return LinearCurve(tuple(knots), tuple(values))


@dataclass(frozen=True)
class SmoothedPoints:
    """A table curve's points (from 0 to 1), and how well they predict a left-out point.

    ``loo_rss``: the weighted (:func:`noise_weights`, times the number of readings merged at
    a level) sum of squared leave-one-out errors over the interior levels; ``n`` the interior
    readings; ``strength`` the smoothing kept (None: the points themselves, interpolated).
    """

    drive: tuple
    output: tuple
    loo_rss: float
    n: int
    strength: float | None


def _pchip_slope(h0, h1, m0, m1):
    """PCHIP's derivative at a knot between two intervals (Fritsch–Butland, as SciPy's)."""
    w0, w1 = 2.0 * h1 + h0, h1 + 2.0 * h0
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (w0 + w1) / (w0 / m0 + w1 / m1)
    return np.where(np.sign(m0) * np.sign(m1) > 0, slope, 0.0)


def _interpolation_loo(d, L, interpolation: str) -> np.ndarray:
    """Each interior level's error when the curve through the others predicts it.

    Closed form: leaving out level ``i``, the curve between ``i − 1`` and ``i + 1`` is a
    straight line, or PCHIP's cubic whose end slopes depend on ``i − 2`` and ``i + 2`` only;
    next to an end of the curve (one-sided end slopes) SciPy's interpolator is built.
    """
    errors = np.empty(d.size - 2)
    i = np.arange(1, d.size - 1)
    span = d[i + 1] - d[i - 1]
    t = (d[i] - d[i - 1]) / span
    if interpolation == "linear":
        return L[i] - (L[i - 1] + t * (L[i + 1] - L[i - 1]))
    mid = (L[i + 1] - L[i - 1]) / span
    inner = i[(i >= 2) & (i <= d.size - 3)]
    if inner.size:
        k = inner - 1  # positions in ``errors``
        before = (L[inner - 1] - L[inner - 2]) / (d[inner - 1] - d[inner - 2])
        after = (L[inner + 2] - L[inner + 1]) / (d[inner + 2] - d[inner + 1])
        slope_b = _pchip_slope(d[inner - 1] - d[inner - 2], span[k], before, mid[k])
        slope_c = _pchip_slope(span[k], d[inner + 2] - d[inner + 1], mid[k], after)
        u = t[k]
        predicted = ((2 * u ** 3 - 3 * u ** 2 + 1) * L[inner - 1]
                     + (u ** 3 - 2 * u ** 2 + u) * span[k] * slope_b
                     + (-2 * u ** 3 + 3 * u ** 2) * L[inner + 1]
                     + (u ** 3 - u ** 2) * span[k] * slope_c)
        errors[k] = L[inner] - predicted
    for j in {1, d.size - 2}:  # the levels beside the ends (one, where there is one level)
        errors[j - 1] = L[j] - PchipInterpolator(np.delete(d, j), np.delete(L, j))(d[j])
    return errors


SMOOTHING_Z = 2.0
"""Paired standard errors by which smoothing must lower the leave-one-out error of the points
themselves (the model choice's rule for a more flexible candidate, ``CV_Z``)."""


def _beyond_noise(gains: np.ndarray) -> bool:
    """Whether per-level gains (interpolation's squared error less smoothing's) sum to more
    than :data:`SMOOTHING_Z` standard errors of their sum."""
    if gains.size < 3:
        return False
    spread = float(np.std(gains, ddof=1))
    return float(gains.sum()) > SMOOTHING_Z * np.sqrt(gains.size) * spread


def smoothed_points(drive, output, interpolation: str = "pchip") -> SmoothedPoints:
    """The levels of a table tone curve, smoothed as far as leave-one-out prediction allows.

    Repeated levels are merged (their mean), and the curve runs from (0, 0) to (1, 1). Two
    candidates: the points themselves, joined by ``interpolation`` (``"pchip"`` or
    ``"linear"``); and the points' departure from the best power law, smoothed by a
    second-difference penalty pinned at both ends (:func:`~workbench.display.smoothing.whittaker_pinned`,
    its strength chosen by leave-one-out). The smoothed levels are kept where they predict a
    left-out level better than the points themselves by more than :data:`SMOOTHING_Z` paired
    standard errors (squared errors weighted by :func:`noise_weights`), then made
    non-decreasing (isotonic regression).

    Interpolating copies every reading's noise into the curve. On noisy sweeps and grey ramps
    of the independent generator the smoothed curves predicted hidden colours better (the peer
    bench: a clean display on the seed authors' plan 0.063 → 0.018 ΔE00); where the levels are
    sparse and the curve bends sharply between them (a drive crosstalk clips the greys near full
    drive) leave-one-out keeps the interpolation. Without the paired rule a nearly noiseless
    real grey ramp (a Dell S2317HWi) was smoothed on a gain within noise and lost 0.349 →
    0.363 ΔE00 on its held-out colours.
    """
    drive, output = _check(drive, output)
    order = np.argsort(drive, kind="stable")
    drive, output = drive[order], output[order]
    unique, inverse = np.unique(drive, return_inverse=True)
    counts = np.bincount(inverse).astype(float)
    merged = np.bincount(inverse, weights=output) / counts
    fitted = np.clip(isotonic(merged), 0.0, 1.0)
    inner = (unique > 0) & (unique < 1)
    d = np.concatenate([[0.0], unique[inner], [1.0]])
    raw = np.concatenate([[0.0], merged[inner], [1.0]])
    interpolated = np.maximum.accumulate(np.concatenate([[0.0], fitted[inner], [1.0]]))
    n = int(np.count_nonzero((drive > 0) & (drive < 1)))
    weight = noise_weights(raw[1:-1]) ** 2 * counts[inner]
    if d.size < 3:
        return SmoothedPoints(tuple(d), tuple(interpolated), 0.0, n, None)
    interpolation_errors = _interpolation_loo(d, raw, interpolation)
    best = (float(np.sum(weight * interpolation_errors ** 2)), None, interpolated)
    try:
        reference = PowerCurve.fit(d[1:-1], raw[1:-1]).forward(d) if np.any(raw[1:-1] > 0) else d
    except (InputError, ValueError, FloatingPointError):
        reference = d
    smooth = whittaker_pinned(d, (raw - reference)[1:-1], weight)
    if smooth is not None and _beyond_noise(weight * (interpolation_errors ** 2
                                                      - smooth.loo_errors ** 2)):
        values = np.clip(isotonic(reference[1:-1] + smooth.values), 0.0, 1.0)
        best = (smooth.loo_rss, smooth.strength,
                np.maximum.accumulate(np.concatenate([[0.0], values, [1.0]])))
    return SmoothedPoints(tuple(float(v) for v in d), tuple(float(v) for v in best[2]),
                          best[0], n, best[1])


TONE_CURVES = {cls.form: cls for cls in (PowerCurve, GOGCurve, ExtendedPowerCurve, SplineCurve,
                                         LinearCurve)}


def _check(drive, output):
    drive = np.asarray(drive, dtype=float)
    output = np.asarray(output, dtype=float)
    if drive.shape != output.shape or drive.size < 2:
        raise InputError("a tone-curve fit needs matching drive and output arrays of ≥ 2 points")
    if not (np.all(np.isfinite(drive)) and np.all(np.isfinite(output))):
        raise InputError("tone-curve data hold NaN or infinity")
    return drive, output


def fit_tone_curve(drive, output, form: str = "power") -> ToneCurve:
    """Fit tone curve ``form`` (a key of :data:`TONE_CURVES`) to normalized data."""
    try:
        cls = TONE_CURVES[form]
    except KeyError:
        raise InputError(f"unknown tone-curve form {form!r}; use one of {sorted(TONE_CURVES)}"
                         ) from None
    return cls.fit(*_check(drive, output))


def tone_curve_from_parameters(parameters: dict) -> ToneCurve:
    parameters = dict(parameters)
    form = parameters.pop("form")
    if form in ("spline", "linear"):
        return TONE_CURVES[form](tuple(parameters["drive"]), tuple(parameters["output"]))
    return TONE_CURVES[form](**parameters)


def _interior(drive, output):
    keep = (drive > 0) & (drive < 1)
    return drive[keep], output[keep]


def bic(curve: ToneCurve, drive, output) -> float:
    """Bayesian information criterion of ``curve`` on the (weighted) interior points.

    Only points with ``0 < d < 1`` count, so every form — and the spline's
    leave-one-out score — is computed on the same ``n``; lower is better.
    """
    drive, output = _interior(*_check(drive, output))
    residual = (curve.forward(drive) - output) * noise_weights(output)
    n = drive.size
    rss = max(float(residual @ residual), 1e-300)
    return n * np.log(rss / n) + curve.n_parameters * np.log(n)


def select_tone_curve(drive, output, forms=("power", "gog", "extended-power", "spline")
                      ) -> tuple[ToneCurve, dict[str, float]]:
    """The form with the lowest BIC, and every form's BIC.

    The spline passes through (or near) its points, so it is scored by its leave-one-out
    prediction error (:func:`smoothed_points`) rather than by its training residual.
    """
    drive, output = _check(drive, output)
    scores, curves = {}, {}
    for form in forms:
        if form == "spline":
            if drive.size < 6:
                continue
            points = smoothed_points(drive, output, "pchip")
            curves[form] = SplineCurve(points.drive, points.output)
            scores[form] = _loo_bic(points)
        else:
            curves[form] = fit_tone_curve(drive, output, form)
            scores[form] = bic(curves[form], drive, output)
    best = min(scores, key=scores.get)
    return curves[best], scores


def _loo_bic(points: SmoothedPoints) -> float:
    """BIC-like score of a table curve from its leave-one-out errors on the interior points."""
    n = max(points.n, 1)
    rss = max(points.loo_rss, 1e-300)
    return n * np.log(rss / n) + np.log(n)  # the spline's shape costs one 'parameter' here
