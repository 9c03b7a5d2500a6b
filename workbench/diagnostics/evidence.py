"""What the detectors and the extended fit read from a session.

Everything here is derived from the rows a model may be fitted on (never the
``validation`` rows): the white references over time, the black, each
channel's black-subtracted sweep, and per-channel outputs implied by grey
rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.display.gamma_matrix import RAMP_KINDS
from workbench.errors import InputError
from workbench.session import Session

__all__ = ["DriftCorrection", "ChannelSweep", "estimate_drift", "channel_sweeps",
           "fit_chromaticity_drift", "xy_of", "MIN_CHROMATICITY_OUTPUT"]


def xy_of(XYZ: np.ndarray) -> np.ndarray:
    XYZ = np.asarray(XYZ, dtype=float)
    total = XYZ.sum(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return XYZ[..., :2] / total


@dataclass(frozen=True, eq=False)
class DriftCorrection:
    """Relative output ``g(t)`` from the white references (1 at the reference state).

    ``g`` is interpolated piecewise-linearly between the white references and
    held flat beyond them; the reference state is the mean of the last two
    whites (a warmed-up display).
    """

    times: np.ndarray
    gains: np.ndarray

    def gain(self, t_s) -> np.ndarray:
        return np.interp(np.asarray(t_s, dtype=float), self.times, self.gains)

    def correct(self, session: Session) -> Session:
        """The session with every measurement divided by ``g(t)``."""
        g = self.gain(session.t_s)[:, None]
        return Session(kind=session.kind, rgb=session.rgb, XYZ=session.XYZ / g, t_s=session.t_s,
                       wavelengths=session.wavelengths,
                       spectra=None if session.spectra is None else session.spectra / g,
                       source=session.source, metadata=dict(session.metadata))

    @property
    def span(self) -> float:
        """Largest relative change of the white over the session."""
        return float(self.gains.max() - self.gains.min())


def estimate_drift(session: Session) -> DriftCorrection | None:
    """Drift from repeated whites, or None when there are fewer than 3 with times."""
    if session.t_s is None:
        return None
    whites = session.mask("white")
    if whites.sum() < 3:
        return None
    order = np.argsort(session.t_s[whites], kind="stable")
    times = session.t_s[whites][order]
    Y = session.XYZ[whites, 1][order]
    reference = Y[-2:].mean()
    return DriftCorrection(times=times, gains=Y / reference)


@dataclass(frozen=True, eq=False)
class ChannelSweep:
    """One channel's sweep, black subtracted.

    Attributes
    ----------
    drive : ndarray
        Normalized drive ``d`` of each point (0..1], ascending.
    XYZ : ndarray (n, 3)
        Black-subtracted XYZ at each point.
    full_XYZ : ndarray (3,)
        Black-subtracted XYZ at full drive.
    """

    channel: int
    drive: np.ndarray
    XYZ: np.ndarray
    full_XYZ: np.ndarray

    @property
    def output(self) -> np.ndarray:
        """Normalized output ``L`` (Y relative to full drive)."""
        return self.XYZ[:, 1] / self.full_XYZ[1]

    @property
    def full_xy(self) -> np.ndarray:
        return xy_of(self.full_XYZ)


def channel_sweeps(session: Session, black: np.ndarray) -> tuple[ChannelSweep, ...]:
    """The three black-subtracted sweeps (rows of kind ramp-*, other channels at 0)."""
    sweeps = []
    for channel, kind in enumerate(RAMP_KINDS):
        others = [c for c in range(3) if c != channel]
        rows = (session.mask(kind) & np.all(session.rgb[:, others] == 0, axis=1)
                & (session.rgb[:, channel] > 0))
        if not rows.any() or session.rgb[rows, channel].max() < 255:
            raise InputError(f"session {session.source!r}: the {kind} sweep is missing or does not "
                             "reach DAC 255; diagnosis needs each channel swept to full drive")
        levels = session.rgb[rows, channel]
        XYZ = session.XYZ[rows] - black
        unique = np.unique(levels)
        mean_XYZ = np.array([XYZ[levels == v].mean(axis=0) for v in unique])
        sweeps.append(ChannelSweep(channel=channel, drive=unique / 255.0, XYZ=mean_XYZ,
                                   full_XYZ=mean_XYZ[-1]))
    return tuple(sweeps)


MIN_CHROMATICITY_OUTPUT = 0.02
"""Sweep points below this normalized output are too dim for a reliable xy."""


def fit_chromaticity_drift(sweep: ChannelSweep) -> tuple[np.ndarray, float] | None:
    """Fit ``Δxy(d) = a₁(1 − d) + a₂(1 − d)²`` to a black-subtracted sweep.

    Points are weighted by the square root of their output and those below
    :data:`MIN_CHROMATICITY_OUTPUT` are left out. Returns the (2, 2)
    coefficients ([a₁, a₂] × [x, y]) and the lowest drive used, or None when
    fewer than three points are usable.
    """
    usable = (sweep.output >= MIN_CHROMATICITY_OUTPUT) & (sweep.drive < 1.0)
    if usable.sum() < 3:
        return None
    delta = xy_of(sweep.XYZ[usable]) - sweep.full_xy
    u = 1.0 - sweep.drive[usable]
    weights = np.sqrt(sweep.output[usable])
    coefficients, *_ = np.linalg.lstsq(np.column_stack([u, u ** 2]) * weights[:, None],
                                       delta * weights[:, None], rcond=None)
    return coefficients, float(sweep.drive[usable].min())
