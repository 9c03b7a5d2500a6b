"""What a patch costs in instrument time, learned from this session's own measurements.

A CS-2000 integrates as long as a patch needs: about a second on a bright
patch, up to its 242 s limit near black, and the dark end differs from panel
to panel and from instrument to instrument. So the adaptive plan
(:mod:`workbench.measurement.adaptive`) takes no table: :class:`PatchCostModel`
is fitted to the journal's records of this session, each the patch's
luminance (``Lv``), the seconds it took (``duration_s``: show, settle,
pre-measurement, measurement and transfer, on the session clock) and, where
the instrument announced it, the measurement time of its ``MEAS,1`` reply
(``OK00,ttt``, the record's ``measurement_time_s``).

The model: in log seconds against log luminance, a piecewise-linear curve
through the measured points (the mean at each distinct luminance), made
monotone (a darker patch never costs less than a brighter one measured);
darker than the darkest lit patch measured it follows the slope of the darkest
measured points (integration time grows as a power of the signal), never past
the seconds the black took; brighter than the brightest, the brightest's
seconds. A patch that reads no more light than the black, or took as long
(a toe crushes the shadows to black), is a point of the floor, as the black
is, not the darkest lit one: read at the floor's luminance, a line from it to
the darkest lit patch had put what a toe crushes at a minute where it takes
four. Where every record carries the announced countdown, the cost is the
countdown's curve plus the curve of the rest (``duration_s − ttt``:
pre-measurement and transfer), each fitted that way.

Units: luminance in cd/m², seconds on the session clock (the modelled
instrument time for a simulated instrument).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DARKEST_CD_M2", "PatchCostModel", "fit_patch_cost"]

DARKEST_CD_M2 = 1e-6
"""Luminances below this are placed here (a black that measures 0 cd/m² keeps a finite log)."""

_DARK_POINTS = 3  # the darkest lit points whose slope extends the curve into the dark


@dataclass(frozen=True)
class _LogLogCurve:
    """Monotone piecewise-linear log10 seconds against log10 luminance (see the module doc)."""

    log_L: tuple
    log_s: tuple
    dark_slope: float
    black_log_s: float | None

    @classmethod
    def fit(cls, luminance, seconds, black) -> "_LogLogCurve | None":
        luminance = np.asarray(luminance, dtype=float)
        seconds = np.maximum(np.asarray(seconds, dtype=float), 1e-3)
        black = np.asarray(black, dtype=bool)
        black_log_s = float(np.log10(seconds[black].max())) if black.any() else None
        lit = ~black & np.isfinite(luminance) & np.isfinite(seconds)
        if not lit.any():
            return None if black_log_s is None else cls((0.0,), (black_log_s,), 0.0, black_log_s)
        x = np.log10(np.maximum(luminance[lit], DARKEST_CD_M2))
        values, inverse = np.unique(np.round(x, 6), return_inverse=True)
        y = np.bincount(inverse, weights=np.log10(seconds[lit])) / np.bincount(inverse)
        # darker never cheaper: from the bright end down, each point at least the brighter's
        y = np.maximum.accumulate(y[::-1])[::-1]
        slope = 0.0
        if values.size >= 2:
            n = min(_DARK_POINTS, values.size)
            slope = float(np.polyfit(values[:n], y[:n], 1)[0]) if np.ptp(values[:n]) > 0 else 0.0
        return cls(tuple(values), tuple(y), min(slope, 0.0), black_log_s)

    def log_seconds(self, luminance) -> np.ndarray:
        x = np.log10(np.maximum(np.asarray(luminance, dtype=float), DARKEST_CD_M2))
        xs, ys = np.asarray(self.log_L), np.asarray(self.log_s)
        out = np.interp(x, xs, ys)
        darker = x < xs[0]
        out[darker] = ys[0] + self.dark_slope * (x[darker] - xs[0])
        if self.black_log_s is not None:
            out = np.minimum(out, max(self.black_log_s, ys.max()))
        return out


@dataclass(frozen=True)
class PatchCostModel:
    """Seconds a patch takes against its luminance (module doc). Build it with :func:`fit_patch_cost`.

    Attributes
    ----------
    countdown : _LogLogCurve or None
        The announced measurement time's curve (``None`` where the records lack it).
    rest : _LogLogCurve or None
        ``duration_s − ttt`` where ``countdown`` is given; else the whole ``duration_s``.
    points : int
        Records it was fitted on.
    """

    countdown: _LogLogCurve | None
    rest: _LogLogCurve | None
    points: int

    def seconds(self, luminance) -> np.ndarray:
        """Predicted seconds for patches of ``luminance`` (cd/m², any shape)."""
        luminance = np.atleast_1d(np.asarray(luminance, dtype=float))
        total = np.zeros(luminance.shape)
        for curve in (self.countdown, self.rest):
            if curve is not None:
                total += 10.0 ** curve.log_seconds(luminance)
        return total

    def describe(self) -> str:
        basis = ("the CS-2000's announced countdown (MEAS,1) plus the rest of each patch's time"
                 if self.countdown is not None else "each patch's time on the session clock")
        return f"from {basis}, against luminance, over the {self.points} patches measured so far"


def fit_patch_cost(records) -> PatchCostModel | None:
    """The cost model of the successful ``records`` (:class:`~workbench.measurement.journal.JournalRecord`).

    ``None`` before any record was measured. A black is a record whose DAC
    values are all 0.
    """
    records = [r for r in records if r.ok and r.Lv is not None and np.isfinite(r.Lv)]
    if not records:
        return None
    luminance = np.array([r.Lv for r in records])
    duration = np.array([r.duration_s for r in records])
    black = np.array([not any(r.rgb) for r in records])
    if black.any():
        # a patch that reads no more light than the black, or took as long (a toe's crushed
        # shadows: the instrument's limit, its reading noise about zero), is a point of the
        # floor, not the darkest lit one
        black |= ((luminance <= max(0.0, float(luminance[black].max())))
                  | (duration >= duration[black].max()))
    announced = [r.measurement_time_s for r in records]
    if all(a is not None for a in announced):
        countdown = np.array(announced, dtype=float)
        return PatchCostModel(_LogLogCurve.fit(luminance, countdown, black),
                              _LogLogCurve.fit(luminance, np.maximum(duration - countdown, 0.0), black),
                              len(records))
    return PatchCostModel(None, _LogLogCurve.fit(luminance, duration, black), len(records))
